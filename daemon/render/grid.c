#include "grid.h"

#include <math.h>
#include <string.h>

#include "brightness.h"
#include "geometry.h"

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

bool grid_sample(const struct scene_draw *d, const double f[3], uint8_t out[3])
{
	const struct scene_transfer *tf = &d->transfer;
	float rgba[4] = { 0 };
	float v = sample_at(d, f, rgba);
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
			if (!inside || !grid_sample(job->draw, f, rgb))
				continue;
			uint32_t out = mirror ? g->width - 1 - u : u;
			if (m) { /* a solid fills every slice: weighted as a crossing surface */
				struct brightness_weight w = { m->rate, m->wall, 1.0f };
				for (int i = 0; i < 3; i++)
					rgb[i] = brightness_apply(m, &w, out, rgb[i]);
			}
			section_pixel(c, out, v, rgb);
		}
	}
}
