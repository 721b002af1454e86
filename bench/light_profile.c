/* Light per unit area in radial bands (light_profile.h). */
#include "light_profile.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "geometry.h"
#include "svol.h"

unsigned light_profile_bands(uint32_t width, double lo[], double hi[], unsigned max)
{
	double rim = width / 2.0;
	if (width < 2)
		return 0;
	unsigned n = 0;
	double a = 0.0, b = 1.0;
	while (a < rim) {
		if (n == max)
			return 0;
		lo[n] = a;
		hi[n] = b < rim ? b : rim;
		n++;
		a = b;
		b = 2.0 * b;
	}
	return n;
}

static double clampd(double x, double lo, double hi)
{
	return x < lo ? lo : x > hi ? hi : x;
}

/* A sphere's area between cylindrical radii lo and hi (pixels): in pixel
 * space it is a spheroid, s horizontal pixels round and v vertical pixels
 * high (half axes). With rho = s sin t, y = v cos t, each hemisphere's
 * band is the integral of 2 pi rho ds, ds = sqrt(s^2 cos^2 t + v^2 sin^2 t)
 * dt (Simpson's rule: the integrand is smooth in t). */
static double sphere_area(double s, double v, double lo, double hi)
{
	lo = clampd(lo, 0.0, s);
	hi = clampd(hi, 0.0, s);
	if (!(hi > lo))
		return 0.0;
	double t0 = asin(lo / s), t1 = asin(hi / s);
	const int n = 512; /* even */
	double step = (t1 - t0) / n, sum = 0.0;
	for (int i = 0; i <= n; i++) {
		double t = t0 + i * step, c = cos(t), si = sin(t);
		double f = 2.0 * M_PI * s * si * sqrt(s * s * c * c + v * v * si * si);
		sum += f * (i == 0 || i == n ? 1.0 : i % 2 ? 4.0 : 2.0);
	}
	return 2.0 * sum * step / 3.0; /* both hemispheres */
}

double light_shape_area(const struct light_shape *shape, uint32_t width, uint32_t height, double half_height, double lo,
			double hi)
{
	double r = shape->radius * width / 2.0;                     /* horizontal pixels */
	double rows = shape->height * height / (2.0 * half_height); /* vertical pixels */
	double a = clampd(lo, 0.0, r), b = clampd(hi, 0.0, r);
	switch (shape->kind) {
	case LIGHT_SHAPE_DISK:
		return M_PI * (b * b - a * a);
	case LIGHT_SHAPE_WALL:
		return 2.0 * (b - a) * rows;
	case LIGHT_SHAPE_TUBE:
		return r >= lo && r < hi ? 2.0 * M_PI * r * rows : 0.0;
	case LIGHT_SHAPE_RING:
		return r >= lo && r < hi ? 2.0 * M_PI * r : 0.0;
	case LIGHT_SHAPE_SPHERE:
		return sphere_area(r, shape->radius * height / (2.0 * half_height), lo, hi);
	}
	return 0.0;
}

/* Lit voxels per band: the OR of the three planes, bit by bit, each
 * column's band from its radius |u + 0.5 - W/2|. 0, or -EINVAL for an
 * image wider than the table. */
static int count_lit(const uint8_t *svol, const struct svol_header *hd, const double *hi, unsigned n,
		     struct light_profile *out)
{
	const struct svol_header h = *hd;
	uint8_t band_of[8192];
	if (h.width > sizeof(band_of))
		return -EINVAL;
	for (uint32_t u = 0; u < h.width; u++) {
		double r = fabs(u + 0.5 - h.width / 2.0);
		unsigned i = 0;
		while (i + 1 < n && r >= hi[i])
			i++;
		band_of[u] = (uint8_t)i;
	}
	size_t row_bytes = (h.width + 7) / 8, plane = row_bytes * h.height;
	const uint8_t *p = svol + SVOL_HEADER_SIZE;
	for (uint32_t k = 0; k < h.image_count; k++, p += 3 * plane) {
		for (size_t i = 0; i < plane; i++) {
			unsigned bits = p[i] | p[plane + i] | p[2 * plane + i];
			if (!bits)
				continue;
			size_t u0 = (i % row_bytes) * 8;
			for (unsigned bit = 0; bit < 8; bit++)
				if (bits & (0x80u >> bit) && u0 + bit < h.width)
					out->band[band_of[u0 + bit]].lit++;
		}
	}

	return 0;
}

/* Reads the file's header into h and what the profile takes from it
 * into out. 0, or -EINVAL for no valid .svol file. */
static int read_header(const uint8_t *svol, size_t size, struct svol_header *h, struct light_profile *out)
{
	if (size < SVOL_HEADER_SIZE || svol_header_decode(svol, h) < 0 || svol_file_size(h) != size)
		return -EINVAL;
	if (h->width < 2 || h->height < 1 || !(h->half_height > 0.0f))
		return -EINVAL;
	out->width = h->width;
	out->height = h->height;
	out->images = h->image_count;
	out->images_per_rev = h->images_per_rev;
	out->mirrored = (h->flags & SVOL_FLAG_MIRRORED) != 0;
	out->half_height = h->half_height;
	struct geometry g = { .width = h->width, .height = h->height, .images_per_rev = h->images_per_rev };
	out->r0_px = geometry_r0_px(&g);
	return 0;
}

/* Each band's light per area, relative to the r0 band's, and the whole
 * shape's, from the lit voxels counted. */
static void compute_values(struct light_profile *out)
{
	unsigned n = out->band_count;
	for (unsigned i = 0; i < n; i++) {
		struct light_band *b = &out->band[i];
		out->lit += b->lit;
		b->value = b->area > 0.0 ? b->lit / b->area : 0.0;
	}
	out->value = out->lit / out->area;
	double ref = out->r0_band >= 0 ? out->band[out->r0_band].value : 0.0;
	for (unsigned i = 0; i < n; i++)
		out->band[i].relative = ref > 0.0 && out->band[i].area > 0.0 ? out->band[i].value / ref : 0.0;
}

int light_profile_compute(const uint8_t *svol, size_t size, const struct light_shape *shape, struct light_profile *out)
{
	struct svol_header h;
	memset(out, 0, sizeof(*out));
	if (read_header(svol, size, &h, out) < 0)
		return -EINVAL;

	double lo[LIGHT_PROFILE_MAX_BANDS], hi[LIGHT_PROFILE_MAX_BANDS];
	unsigned n = light_profile_bands(h.width, lo, hi, LIGHT_PROFILE_MAX_BANDS);
	if (n == 0)
		return -EINVAL;
	out->band_count = n;
	out->r0_band = -1;
	for (unsigned i = 0; i < n; i++) {
		struct light_band *b = &out->band[i];
		b->lo = lo[i];
		b->hi = hi[i];
		b->area = light_shape_area(shape, h.width, h.height, h.half_height, lo[i], hi[i]);
		out->area += b->area;
		if (out->r0_px >= lo[i] && out->r0_px < hi[i])
			out->r0_band = (int)i;
	}
	if (!(out->area > 0.0))
		return -EINVAL;

	if (count_lit(svol, &h, hi, n, out) < 0)
		return -EINVAL;
	compute_values(out);
	return 0;
}

double light_profile_peak_relative(const struct light_profile *p, double from_px, double to_px)
{
	double peak = 0.0;
	for (unsigned i = 0; i < p->band_count; i++) {
		const struct light_band *b = &p->band[i];
		if (b->area > 0.0 && b->lo >= from_px && b->lo <= to_px && b->relative > peak)
			peak = b->relative;
	}
	return peak;
}
