#include "grid.h"

#include <math.h>
#include <string.h>

#include "brightness.h"
#include "geometry.h"

/* Whether the grid's up axis is the display's: f_x and f_z do not change
 * along a pixel column, nor f_y along a row. */
static bool upright(const struct grid_job *job)
{
	return job->lin[0][1] == 0.0 && job->lin[2][1] == 0.0 && job->lin[1][0] == 0.0 && job->lin[1][2] == 0.0;
}

bool grid_prepare(struct grid_job *job, const struct scene_draw *d)
{
	const float *m = d->transform;
	/* a: the linear part (a[row][col]), column-major m. */
	double a[3][3];
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++)
			a[r][c] = m[c * 4 + r];
	double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
		     a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
		     a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
	if (!(fabs(det) > 1e-30) || !isfinite(det))
		return false;
	/* The inverse by cofactors, then the grid's spacing: f = p' / s - 0.5. */
	double inv[3][3];
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++) {
			int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
			inv[r][c] = (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) / det;
		}
	const struct scene_grid *g = d->grid;
	job->draw = d;
	for (int r = 0; r < 3; r++) {
		double t = 0.0;
		for (int c = 0; c < 3; c++) {
			job->lin[r][c] = inv[r][c] / g->spacing[r];
			t -= inv[r][c] * m[12 + c];
		}
		job->off[r] = t / g->spacing[r] - 0.5;
		for (int c = 0; c < 3; c++)
			if (!isfinite(job->lin[r][c]))
				return false;
		if (!isfinite(job->off[r]))
			return false;
	}
	job->upright = upright(job);
	job->reference = false;
	job->colours = NULL;
	return true;
}

/* Sample (i, j, k) of g as a number (RGBA8: its alpha), and the colour of
 * an RGBA8 one in rgba. */
static float value_at(const struct scene_grid *g, uint32_t i, uint32_t j, uint32_t k, float rgba[4])
{
	size_t at = ((size_t)k * g->n[0] + i) * g->n[1] + j;
	switch (g->type) {
	case SCENE_GRID_U8:
		return ((const uint8_t *)g->data)[at];
	case SCENE_GRID_U16:
		return ((const uint16_t *)g->data)[at];
	case SCENE_GRID_I16:
		return ((const int16_t *)g->data)[at];
	case SCENE_GRID_F32:
		return ((const float *)g->data)[at];
	case SCENE_GRID_RGBA8: {
		const uint8_t *p = (const uint8_t *)g->data + 4 * at;
		for (int c = 0; c < 4; c++)
			rgba[c] = p[c];
		return p[3];
	}
	}
	return NAN;
}

static uint32_t clamp_index(int64_t i, uint32_t n)
{
	return i < 0 ? 0 : i >= (int64_t)n ? n - 1 : (uint32_t)i;
}

/* The sample at f: nearest, or trilinear with the edge samples repeated. */
static float sample_at(const struct scene_draw *d, const double f[3], float rgba[4])
{
	const struct scene_grid *g = d->grid;
	if (d->transfer.sampling != SCENE_TRILINEAR) {
		uint32_t i[3];
		for (int a = 0; a < 3; a++)
			i[a] = clamp_index((int64_t)floor(f[a] + 0.5), g->n[a]);
		return value_at(g, i[0], i[1], i[2], rgba);
	}
	int64_t i0[3];
	float t[3];
	for (int a = 0; a < 3; a++) {
		double fl = floor(f[a]);
		i0[a] = (int64_t)fl;
		t[a] = (float)(f[a] - fl);
	}
	float v = 0.0f, acc[4] = { 0 };
	for (int corner = 0; corner < 8; corner++) {
		float w = 1.0f, c4[4] = { 0 };
		uint32_t i[3];
		for (int a = 0; a < 3; a++) {
			int bit = (corner >> a) & 1;
			w *= bit ? t[a] : 1.0f - t[a];
			i[a] = clamp_index(i0[a] + bit, g->n[a]);
		}
		v += w * value_at(g, i[0], i[1], i[2], c4);
		for (int c = 0; c < 4; c++)
			acc[c] += w * c4[c];
	}
	memcpy(rgba, acc, sizeof(acc));
	return v;
}

/* The colour of sample value v (and rgba, for an RGBA8 grid) by d's
 * transfer. false: dark. */
static bool transfer(const struct scene_draw *d, float v, const float rgba[4], uint8_t out[3])
{
	const struct scene_transfer *tf = &d->transfer;
	if (!(v >= tf->threshold))
		return false;
	if (d->grid->type == SCENE_GRID_RGBA8) {
		for (int c = 0; c < 3; c++)
			out[c] = (uint8_t)(rgba[c] * rgba[3] / 255.0f + 0.5f);
	} else {
		float g = (v - tf->lo) / (tf->hi - tf->lo);
		g = g > 0.0f ? (g < 1.0f ? g : 1.0f) : 0.0f;
		if (tf->lut) {
			const uint8_t *e = tf->lut + 3 * (uint32_t)(g * (float)(tf->lut_count - 1) + 0.5f);
			memcpy(out, e, 3);
		} else {
			for (int c = 0; c < 3; c++)
				out[c] = (uint8_t)((float)d->rgb[c] * g + 0.5f);
		}
	}
	return out[0] | out[1] | out[2];
}

bool grid_sample(const struct scene_draw *d, const double f[3], uint8_t out[3])
{
	float rgba[4] = { 0 };
	float v = sample_at(d, f, rgba);
	return transfer(d, v, rgba, out);
}

size_t grid_colours_size(const struct scene_draw *d)
{
	if (d->transfer.sampling != SCENE_NEAREST)
		return 0;
	switch (d->grid->type) {
	case SCENE_GRID_U8:
		return 256;
	case SCENE_GRID_U16:
	case SCENE_GRID_I16:
		return 65536;
	}
	return 0;
}

void grid_colours(const struct scene_draw *d, uint8_t *out)
{
	size_t n = grid_colours_size(d);
	float base = d->grid->type == SCENE_GRID_I16 ? -32768.0f : 0.0f, none[4] = { 0 };
	for (size_t i = 0; i < n; i++, out += 4)
		out[3] = transfer(d, base + (float)i, none, out);
}

void grid_line_max(const struct scene_grid *g, float *out)
{
	for (uint32_t k = 0; k < g->n[2]; k++)
		for (uint32_t i = 0; i < g->n[0]; i++) {
			float mx = -INFINITY, rgba[4];
			for (uint32_t j = 0; j < g->n[1]; j++) {
				float v = value_at(g, i, j, k, rgba);
				mx = v > mx ? v : mx; /* NaN never wins: it lights nothing */
			}
			out[(size_t)k * g->n[0] + i] = mx;
		}
}

/* The columns of row v (plane point base + s dirs) whose centres may lie in
 * the box: an interval of s from each axis, widened by a column. */
static bool columns_of(const struct grid_job *job, const double base[3], const double dir[3], const struct geometry *g,
		       uint32_t *u0, uint32_t *u1)
{
	const struct scene_grid *gr = job->draw->grid;
	double lo = -1.0, hi = 1.0;
	for (int a = 0; a < 3; a++) {
		double min = -0.5, max = gr->n[a] - 0.5;
		if (dir[a] == 0.0) {
			if (!(base[a] >= min && base[a] < max))
				return false;
			continue;
		}
		double s0 = (min - base[a]) / dir[a], s1 = (max - base[a]) / dir[a];
		lo = fmax(lo, fmin(s0, s1));
		hi = fmin(hi, fmax(s0, s1));
	}
	if (!(lo <= hi))
		return false;
	double w = g->width, c0 = floor((lo + 1.0) / 2.0 * w - 0.5) - 1, c1 = ceil((hi + 1.0) / 2.0 * w - 0.5) + 1;
	*u0 = c0 < 0 ? 0 : (uint32_t)c0;
	*u1 = c1 > w - 1 ? g->width - 1 : (uint32_t)c1;
	return *u0 <= *u1;
}

/* One pixel column of an upright grid: the one line (nearest) or four
 * lines (trilinear) of samples it reads, with what sample_at() works out
 * per axis for x and z, done once. */
struct column {
	uint32_t i[2], k[2]; /* sample indices (clamped), the second of each pair for trilinear */
	float tx, tz;        /* trilinear weights along x and z */
	size_t line[4];      /* trilinear: where line (i[b & 1], k[b >> 1]) starts */
};

static void column_setup(struct column *col, const struct scene_grid *gr, double fx, double fz, bool tri)
{
	if (!tri) {
		col->i[0] = clamp_index((int64_t)floor(fx + 0.5), gr->n[0]);
		col->k[0] = clamp_index((int64_t)floor(fz + 0.5), gr->n[2]);
		return;
	}
	double lx = floor(fx), lz = floor(fz);
	col->tx = (float)(fx - lx);
	col->tz = (float)(fz - lz);
	for (int b = 0; b < 2; b++) {
		col->i[b] = clamp_index((int64_t)lx + b, gr->n[0]);
		col->k[b] = clamp_index((int64_t)lz + b, gr->n[2]);
	}
	for (int b = 0; b < 4; b++)
		col->line[b] = ((size_t)col->k[b >> 1] * gr->n[0] + col->i[b & 1]) * gr->n[1];
}

/* Whether every sample the column reads is below the threshold, from the
 * lines' maxima (NULL: not known). Trilinear mixes may round a hair above
 * their largest sample: a margin of 1e-5 of it. */
static bool column_dark(const struct column *col, const struct scene_grid *gr, const struct scene_transfer *tf,
			bool tri)
{
	if (!gr->line_max)
		return false;
	float mx = -INFINITY;
	for (int b = 0; b < (tri ? 4 : 1); b++) {
		float v = gr->line_max[(size_t)col->k[b >> 1] * gr->n[0] + col->i[b & 1]];
		mx = v > mx ? v : mx;
	}
	return (double)mx + fabs((double)mx) * 1e-5 < tf->threshold;
}

/* Sample at of a u8, u16 or i16 grid as an index of its colour table. */
static inline size_t sample_index(const struct scene_grid *gr, size_t at)
{
	switch (gr->type) {
	case SCENE_GRID_U8:
		return ((const uint8_t *)gr->data)[at];
	case SCENE_GRID_U16:
		return ((const uint16_t *)gr->data)[at];
	default:
		return (size_t)(((const int16_t *)gr->data)[at] + 32768);
	}
}

/* Sample at of a scalar grid, as a number. */
static inline float scalar_at(uint32_t type, const void *data, size_t at)
{
	switch (type) {
	case SCENE_GRID_U8:
		return ((const uint8_t *)data)[at];
	case SCENE_GRID_U16:
		return ((const uint16_t *)data)[at];
	case SCENE_GRID_I16:
		return ((const int16_t *)data)[at];
	default:
		return ((const float *)data)[at];
	}
}

/* sample_at() for the point at f_y on the column: the same operations in
 * the same order, so the same value; a scalar grid's samples read straight
 * from its lines (the colour sums of RGBA8 left out: they stay 0). */
static float column_sample(const struct column *col, const struct scene_grid *gr, double fy, bool tri, float rgba[4])
{
	if (!tri)
		return value_at(gr, col->i[0], clamp_index((int64_t)floor(fy + 0.5), gr->n[1]), col->k[0], rgba);
	double ly = floor(fy);
	float t[3] = { col->tx, (float)(fy - ly), col->tz };
	uint32_t j[2] = { clamp_index((int64_t)ly, gr->n[1]), clamp_index((int64_t)ly + 1, gr->n[1]) };
	float v = 0.0f;
	if (gr->type != SCENE_GRID_RGBA8) {
		for (int corner = 0; corner < 8; corner++) {
			float w = 1.0f;
			for (int a = 0; a < 3; a++)
				w *= (corner >> a) & 1 ? t[a] : 1.0f - t[a];
			size_t at = col->line[(corner & 1) | (corner >> 2) << 1] + j[(corner >> 1) & 1];
			v += w * scalar_at(gr->type, gr->data, at);
		}
		return v;
	}
	float acc[4] = { 0 };
	for (int corner = 0; corner < 8; corner++) {
		float w = 1.0f, c4[4] = { 0 };
		for (int a = 0; a < 3; a++)
			w *= (corner >> a) & 1 ? t[a] : 1.0f - t[a];
		v += w * value_at(gr, col->i[corner & 1], j[(corner >> 1) & 1], col->k[corner >> 2], c4);
		for (int ch = 0; ch < 4; ch++)
			acc[ch] += w * c4[ch];
	}
	memcpy(rgba, acc, sizeof(acc));
	return v;
}

/* Lights pixel (out, v) with rgb, weighted by m where it is active. */
static void light(struct section_canvas *c, const struct brightness_map *m, uint32_t out, uint32_t v, uint8_t rgb[3])
{
	if (m) { /* a solid fills every slice: weighted as a crossing surface */
		struct brightness_weight w = { m->rate, m->wall, 1.0f };
		for (int i = 0; i < 3; i++)
			rgb[i] = brightness_apply(m, &w, out, rgb[i]);
	}
	section_pixel(c, out, v, rgb);
}

/* An upright grid, column by column: each column's x and z once, its
 * samples down one run of memory per line, and columns whose lines stay
 * below the threshold skipped. The same pixels and colours as the
 * reference loop below, which computes every pixel's f the same way. */
static void draw_upright(struct section_canvas *c, const struct grid_job *job, const double dir[3], const double up[3],
			 bool mirror, const struct brightness_map *m)
{
	const struct geometry *g = &c->geom;
	const struct scene_draw *d = job->draw;
	const struct scene_grid *gr = d->grid;
	bool tri = d->transfer.sampling == SCENE_TRILINEAR;
	double h = g->half_height, y0 = h - 0.5 * 2.0 * h / g->height;
	/* up[0] = up[2] = 0: every row's base for x and z is row 0's. */
	double bx = job->off[0] + y0 * up[0], bz = job->off[2] + y0 * up[2];
	for (uint32_t u = 0; u < g->width; u++) {
		double s = (u + 0.5) * 2.0 / g->width - 1.0, fx = bx + s * dir[0], fz = bz + s * dir[2];
		if (!(fx >= -0.5 && fx < gr->n[0] - 0.5 && fz >= -0.5 && fz < gr->n[2] - 0.5))
			continue;
		struct column col = { 0 };
		column_setup(&col, gr, fx, fz, tri);
		if (column_dark(&col, gr, &d->transfer, tri))
			continue;
		uint32_t out = mirror ? g->width - 1 - u : u;
		for (uint32_t v = 0; v < g->height; v++) {
			double y = h - (v + 0.5) * 2.0 * h / g->height, fy = (job->off[1] + y * up[1]) + s * dir[1];
			if (!(fy >= -0.5 && fy < gr->n[1] - 0.5))
				continue;
			if (job->colours) { /* nearest: the value's colour, looked up */
				size_t at = ((size_t)col.k[0] * gr->n[0] + col.i[0]) * gr->n[1] +
					    clamp_index((int64_t)floor(fy + 0.5), gr->n[1]);
				const uint8_t *e = job->colours + 4 * sample_index(gr, at);
				if (e[3]) {
					uint8_t rgb[3] = { e[0], e[1], e[2] };
					light(c, m, out, v, rgb);
				}
				continue;
			}
			float rgba[4] = { 0 };
			uint8_t rgb[3];
			if (transfer(d, column_sample(&col, gr, fy, tri, rgba), rgba, rgb))
				light(c, m, out, v, rgb);
		}
	}
}

void grid_draw_image(struct section_canvas *c, const struct grid_job *job, uint32_t src, bool mirror)
{
	const struct geometry *g = &c->geom;
	const struct scene_grid *gr = job->draw->grid;
	double th = geometry_image_angle(g, src), dx = cos(th), dz = sin(th);
	/* f(s, y) = off + s lin d + y lin e_y. */
	double dir[3], up[3];
	for (int a = 0; a < 3; a++) {
		dir[a] = job->lin[a][0] * dx + job->lin[a][2] * dz;
		up[a] = job->lin[a][1];
	}
	const struct brightness_map *m = c->bright && brightness_active(c->bright) ? c->bright : NULL;
	if (job->upright && !job->reference) {
		draw_upright(c, job, dir, up, mirror, m);
		return;
	}
	double h = g->half_height;
	for (uint32_t v = 0; v < g->height; v++) {
		double y = h - (v + 0.5) * 2.0 * h / g->height, base[3];
		for (int a = 0; a < 3; a++)
			base[a] = job->off[a] + y * up[a];
		uint32_t u0, u1;
		if (!columns_of(job, base, dir, g, &u0, &u1))
			continue;
		for (uint32_t u = u0; u <= u1; u++) {
			double s = (u + 0.5) * 2.0 / g->width - 1.0, f[3];
			bool inside = true;
			for (int a = 0; a < 3; a++) {
				f[a] = base[a] + s * dir[a];
				inside &= f[a] >= -0.5 && f[a] < gr->n[a] - 0.5;
			}
			uint8_t rgb[3];
			if (inside && grid_sample(job->draw, f, rgb))
				light(c, m, mirror ? g->width - 1 - u : u, v, rgb);
		}
	}
}
