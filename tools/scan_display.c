/* A scan placed on the display (scan_display.h): the nearest axis
 * permutation and flips of its voxel-to-RAS transform, its samples
 * written in that order, the fit, and the percentiles of its values. */
#include "scan_display.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fdio.h"
/* RAS to display: x = -R, y = S, z = A (a rotation: determinant +1). */
static void ras_to_display(const double ras[3], double d[3])
{
	d[0] = -ras[0];
	d[1] = ras[2];
	d[2] = ras[1];
}

/* The six ways to put voxel axes (values) on display axes (indices). */
static const unsigned perms[6][3] = { { 0, 1, 2 }, { 0, 2, 1 }, { 1, 0, 2 }, { 1, 2, 0 }, { 2, 0, 1 }, { 2, 1, 0 } };

void scan_layout_of(const uint32_t dims[3], const double spacing[3], const double to_ras[16], struct scan_layout *out)
{
	double u[3][3]; /* u[c]: voxel axis c as a unit vector in display axes */
	for (int c = 0; c < 3; c++) {
		ras_to_display(&to_ras[4 * c], u[c]);
		double len = sqrt(u[c][0] * u[c][0] + u[c][1] * u[c][1] + u[c][2] * u[c][2]);
		for (int a = 0; a < 3; a++)
			u[c][a] = len > 0 ? u[c][a] / len : 0;
	}
	int best = 0;
	double best_score = -1;
	for (int p = 0; p < 6; p++) {
		double score = 0;
		for (int a = 0; a < 3; a++)
			score += fabs(u[perms[p][a]][a]);
		if (score > best_score + 1e-12) {
			best = p;
			best_score = score;
		}
	}
	memset(out, 0, sizeof(*out));
	for (int a = 0; a < 3; a++) {
		unsigned c = perms[best][a];
		double cosine = fmin(fabs(u[c][a]), 1.0);
		out->axis[a] = c;
		out->flip[a] = u[c][a] < 0;
		out->dims[a] = dims[c];
		out->spacing[a] = spacing[c];
		out->oblique_deg = fmax(out->oblique_deg, acos(cosine) * 180 / M_PI);
	}
}

/* Element strides of the voxel axes i, j, k. */
static void strides(const uint32_t dims[3], size_t stride[3])
{
	stride[0] = 1;
	stride[1] = dims[0];
	stride[2] = (size_t)dims[0] * dims[1];
}

size_t scan_layout_source(const struct scan_layout *l, const uint32_t scan_dims[3], uint32_t x, uint32_t y, uint32_t z)
{
	const uint32_t d[3] = { x, y, z };
	size_t stride[3], index = 0;
	strides(scan_dims, stride);
	for (int a = 0; a < 3; a++) {
		uint32_t v = l->flip[a] ? l->dims[a] - 1 - d[a] : d[a];
		index += v * stride[l->axis[a]];
	}
	return index;
}

/* Samples of n bytes, step elements apart; n a constant in each use, so
 * that each copy is a move, not a call (a call a sample was a fifth of
 * spindlectl's time showing a 157 MB scan). */
#define GATHER(n)                                                                   \
	for (uint32_t x = 0; x < nx; x++, src += step * (ptrdiff_t)(n), dst += (n)) \
		memcpy(dst, src, (n));

/* One display row (fixed y and z): nx samples from src, step elements apart. */
static void gather_row(uint8_t *dst, const uint8_t *src, ptrdiff_t step, uint32_t nx, size_t per)
{
	if (step == 1) { /* the row as it is stored */
		memcpy(dst, src, (size_t)nx * per);
		return;
	}
	switch (per) {
	case 1:
		GATHER(1)
		break;
	case 2:
		GATHER(2)
		break;
	case 4:
		GATHER(4)
		break;
	default:
		GATHER(per)
		break;
	}
}

#define WRITE_CHUNK (4u << 20)

int scan_layout_write(const struct scan *s, const struct scan_layout *l, int fd)
{
	size_t per = scan_type_size(s->type), stride[3], row = (size_t)l->dims[0] * per;
	size_t cap = row > WRITE_CHUNK ? row : WRITE_CHUNK - WRITE_CHUNK % row, used = 0;
	uint8_t *buf = malloc(cap);
	if (!buf)
		return -ENOMEM;
	strides(s->dims, stride);
	ptrdiff_t step = (ptrdiff_t)stride[l->axis[0]] * (l->flip[0] ? -1 : 1);
	int ret = 0;
	for (uint32_t z = 0; ret == 0 && z < l->dims[2]; z++)
		for (uint32_t y = 0; ret == 0 && y < l->dims[1]; y++) {
			size_t first = scan_layout_source(l, s->dims, 0, y, z);
			gather_row(buf + used, (const uint8_t *)s->data + first * per, step, l->dims[0], per);
			used += row;
			if (used + row > cap) {
				ret = fd_write_all(fd, buf, used);
				used = 0;
			}
		}
	if (ret == 0 && used > 0)
		ret = fd_write_all(fd, buf, used);
	free(buf);
	return ret;
}

void scan_layout_fit(const struct scan_layout *l, float half_height, float margin, float m[16])
{
	double half[3];
	for (int a = 0; a < 3; a++)
		half[a] = 0.5 * l->dims[a] * l->spacing[a];
	double radius = sqrt(half[0] * half[0] + half[2] * half[2]);
	double scale = fmin(margin / radius, margin * half_height / half[1]);
	memset(m, 0, 16 * sizeof(float));
	for (int a = 0; a < 3; a++) {
		m[5 * a] = (float)scale;
		m[12 + a] = (float)(-scale * half[a]);
	}
	m[15] = 1;
}

/* ---- percentiles ---- */

#define BINS 65536u

/* A histogram: bin b counts the values in [lo + b width, lo + (b + 1) width). */
struct histogram {
	uint64_t *bins;
	double lo, width;
};

/* The value below which a fraction q of total counted values lie: a bin's
 * lower edge for integers (a bin per value), its middle for floats. */
static double quantile(const struct histogram *h, uint64_t total, double q, bool integer)
{
	uint64_t want = (uint64_t)ceil(q * (double)total), seen = 0;
	if (want < 1)
		want = 1;
	for (size_t b = 0; b < BINS; b++) {
		seen += h->bins[b];
		if (seen >= want)
			return h->lo + (double)b * h->width + (integer ? 0 : 0.5 * h->width);
	}
	return h->lo + (double)BINS * h->width;
}

/* Integer samples: a bin per value, one pass. */
static void count_integers(enum scan_type type, const void *data, size_t count, struct histogram *h)
{
	if (type == SCAN_U8)
		for (size_t n = 0; n < count; n++)
			h->bins[((const uint8_t *)data)[n]]++;
	else if (type == SCAN_U16)
		for (size_t n = 0; n < count; n++)
			h->bins[((const uint16_t *)data)[n]]++;
	else
		for (size_t n = 0; n < count; n++)
			h->bins[((const int16_t *)data)[n] + 32768]++;
	h->lo = type == SCAN_I16 ? -32768.0 : 0.0;
	h->width = 1;
}

static void integer_stats(enum scan_type type, const void *data, size_t count, struct histogram *h,
			  struct scan_stats *out)
{
	count_integers(type, data, count, h);
	size_t zero = (size_t)-h->lo, first = 0;
	out->nonzero = count - h->bins[zero];
	while (first < BINS && h->bins[first] == 0)
		first++;
	out->min = first < BINS ? h->lo + (double)first : 0;
	h->bins[zero] = 0;
	if (out->nonzero == 0)
		return;
	out->p1 = quantile(h, out->nonzero, 0.01, true);
	out->p99 = quantile(h, out->nonzero, 0.99, true);
}

/* Float samples: their range first, then a histogram over it. */
static void float_stats(const float *data, size_t count, struct histogram *h, struct scan_stats *out)
{
	float min = INFINITY, nz_min = INFINITY, nz_max = -INFINITY;
	for (size_t n = 0; n < count; n++) {
		float v = data[n];
		if (!isfinite(v))
			continue;
		min = fminf(min, v);
		if (v != 0) {
			nz_min = fminf(nz_min, v);
			nz_max = fmaxf(nz_max, v);
			out->nonzero++;
		}
	}
	out->min = isfinite(min) ? min : 0;
	if (out->nonzero == 0)
		return;
	h->lo = nz_min;
	h->width = fmax(((double)nz_max - nz_min) / BINS, 1e-30);
	for (size_t n = 0; n < count; n++) {
		float v = data[n];
		if (isfinite(v) && v != 0) {
			double b = floor(((double)v - h->lo) / h->width);
			h->bins[b < 0 ? 0 : b >= BINS ? BINS - 1 : (size_t)b]++;
		}
	}
	out->p1 = fmax(quantile(h, out->nonzero, 0.01, false), nz_min);
	out->p99 = fmin(quantile(h, out->nonzero, 0.99, false), nz_max);
}

int scan_stats_of(enum scan_type type, const void *data, size_t count, struct scan_stats *out)
{
	memset(out, 0, sizeof(*out));
	if (type == SCAN_RGBA8 || scan_type_size(type) == 0)
		return -EINVAL;
	struct histogram h = { .bins = calloc(BINS, sizeof(uint64_t)) };
	if (!h.bins)
		return -ENOMEM;
	if (type == SCAN_F32)
		float_stats(data, count, &h, out);
	else
		integer_stats(type, data, count, &h, out);
	out->looks_like_ct = type == SCAN_I16 && count > 0 && out->min < -500;
	free(h.bins);
	return 0;
}
