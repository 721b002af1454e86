#include "grid.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "geometry.h"
#include "grid_column.h"
#include "grid_tiles.h"

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
	job->columns = false;
	job->rows = NULL;
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

/* Trilinear mixing, in the one order every path uses: along x, then z,
 * at each of the two rows j[0] and j[1], then along y between them (the
 * upright path mixes each column's lines once and reuses them for every
 * row: the same operations on the same values, so the same result). */
static float trilinear_scalar(const struct scene_grid *g, const uint32_t i[2], const uint32_t j[2], const uint32_t k[2],
			      const float t[3])
{
	float c[2], rgba[4];
	for (int b = 0; b < 2; b++) {
		float x0 = lerp(value_at(g, i[0], j[b], k[0], rgba), value_at(g, i[1], j[b], k[0], rgba), t[0]);
		float x1 = lerp(value_at(g, i[0], j[b], k[1], rgba), value_at(g, i[1], j[b], k[1], rgba), t[0]);
		c[b] = lerp(x0, x1, t[2]);
	}
	return lerp(c[0], c[1], t[1]);
}

/* The same for each channel of an RGBA8 grid; the value is the alpha's. */
static float trilinear_rgba(const struct scene_grid *g, const uint32_t i[2], const uint32_t j[2], const uint32_t k[2],
			    const float t[3], float rgba[4])
{
	float s[2][2][2][4];
	for (int b = 0; b < 8; b++)
		value_at(g, i[b & 1], j[(b >> 1) & 1], k[b >> 2], s[b >> 2][(b >> 1) & 1][b & 1]);
	for (int ch = 0; ch < 4; ch++) {
		float c[2];
		for (int b = 0; b < 2; b++)
			c[b] = lerp(lerp(s[0][b][0][ch], s[0][b][1][ch], t[0]),
				    lerp(s[1][b][0][ch], s[1][b][1][ch], t[0]), t[2]);
		rgba[ch] = lerp(c[0], c[1], t[1]);
	}
	return rgba[3];
}

/* The sample at f: nearest, or trilinear with the edge samples repeated. */
static float sample_at(const struct scene_draw *d, const double f[3], float rgba[4])
{
	const struct scene_grid *g = d->grid;
	if (d->transfer.sampling != SCENE_TRILINEAR) {
		uint32_t i[3];
		for (int a = 0; a < 3; a++)
			i[a] = grid_clamp_index((int64_t)floor(f[a] + 0.5), g->n[a]);
		return value_at(g, i[0], i[1], i[2], rgba);
	}
	uint32_t idx[3][2];
	float t[3];
	for (int a = 0; a < 3; a++) {
		double fl = floor(f[a]);
		t[a] = (float)(f[a] - fl);
		idx[a][0] = grid_clamp_index((int64_t)fl, g->n[a]);
		idx[a][1] = grid_clamp_index((int64_t)fl + 1, g->n[a]);
	}
	if (g->type == SCENE_GRID_RGBA8)
		return trilinear_rgba(g, idx[0], idx[1], idx[2], t, rgba);
	return trilinear_scalar(g, idx[0], idx[1], idx[2], t);
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
		float g = (v - tf->lo) * (1.0f / (tf->hi - tf->lo)); /* scene.h: a reciprocal, as vectors do it */
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

void grid_brick_max_slabs(const struct scene_grid *g, uint32_t k0, uint32_t k1, float *out)
{
	uint32_t nb = scene_grid_bricks(g->n[1]), n1 = g->n[1];
	size_t lines = (size_t)g->n[0] * (k1 - k0), skip = (size_t)g->n[0] * k0;
	out += skip * nb;
	/* Line by line, as the samples lie: NaN never wins (it lights nothing). */
#define BRICKS(T, STEP, VALUE)                                                                                    \
	do {                                                                                                      \
		const T *p = (const T *)g->data + skip * n1 * STEP;                                               \
		for (size_t l = 0; l < lines; l++, p += (size_t)n1 * STEP)                                        \
			for (uint32_t b = 0; b < nb; b++) {                                                       \
				float mx = -INFINITY;                                                             \
				uint32_t end = (b + 1) * SCENE_GRID_BRICK < n1 ? (b + 1) * SCENE_GRID_BRICK : n1; \
				for (uint32_t j = b * SCENE_GRID_BRICK; j < end; j++) {                           \
					float v = VALUE;                                                          \
					mx = v > mx ? v : mx;                                                     \
				}                                                                                 \
				*out++ = mx;                                                                      \
			}                                                                                         \
	} while (0)
	switch (g->type) {
	case SCENE_GRID_U8:
		BRICKS(uint8_t, 1, (float)p[j]);
		break;
	case SCENE_GRID_U16:
		BRICKS(uint16_t, 1, (float)p[j]);
		break;
	case SCENE_GRID_I16:
		BRICKS(int16_t, 1, (float)p[j]);
		break;
	case SCENE_GRID_F32:
		BRICKS(float, 1, p[j]);
		break;
	case SCENE_GRID_RGBA8: /* the alpha */
		BRICKS(uint8_t, 4, (float)p[4 * j + 3]);
		break;
	}
#undef BRICKS
}

void grid_brick_max(const struct scene_grid *g, float *out)
{
	grid_brick_max_slabs(g, 0, g->n[2], out);
}

bool grid_prepare_rows(struct grid_job *job, const struct geometry *g)
{
	job->rows = NULL;
	if (!job->upright)
		return true;
	struct grid_rows *r = malloc(sizeof(*r) + (size_t)g->height * sizeof(r->row[0]));
	if (!r)
		return false;
	const struct scene_grid *gr = job->draw->grid;
	bool tri = job->draw->transfer.sampling == SCENE_TRILINEAR;
	double h = g->half_height;
	r->v0 = g->height;
	r->v1 = 0;
	for (uint32_t v = 0; v < g->height; v++) {
		/* What the reference loop computes for f_y: the row's part (the
		 * column's, s lin[1] d, is 0 for an upright grid). */
		double y = h - (v + 0.5) * 2.0 * h / g->height, fy = job->off[1] + y * job->lin[1][1];
		struct grid_row *row = &r->row[v];
		*row = (struct grid_row){ 0, 0, 0.0f };
		if (!(fy >= -0.5 && fy < gr->n[1] - 0.5))
			continue;
		r->v0 = v < r->v0 ? v : r->v0;
		r->v1 = v + 1;
		if (!tri) {
			row->j0 = row->j1 = grid_clamp_index((int64_t)floor(fy + 0.5), gr->n[1]);
			continue;
		}
		double ly = floor(fy);
		row->t = (float)(fy - ly);
		row->j0 = grid_clamp_index((int64_t)ly, gr->n[1]);
		row->j1 = grid_clamp_index((int64_t)ly + 1, gr->n[1]);
	}
	job->rows = r;
	return true;
}

void grid_job_finish(struct grid_job *job)
{
	free(job->rows);
	job->rows = NULL;
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

/* Where pixel column u of c starts (row 0), and the step to the next
 * tile row. */
struct canvas_column {
	uint8_t *base;
	uint32_t *rows;
	size_t tile_step;
	uint32_t rows_step;
};

static inline void column_pixel(const struct canvas_column *cc, uint32_t v, const uint8_t rgb[3])
{
	uint8_t *px = cc->base + (v / VOLUME_TILE) * cc->tile_step + (v % VOLUME_TILE) * HALFTONE_ROW_BYTES;
	for (int i = 0; i < 3; i++)
		if (px[i * HALFTONE_PLANE_BYTES] < rgb[i])
			px[i * HALFTONE_PLANE_BYTES] = rgb[i];
	cc->rows[(v / VOLUME_TILE) * cc->rows_step] |= 1u << (v % VOLUME_TILE);
}

/* Lights pixel v of column cc (u = out) with rgb, weighted by m where it
 * is active: light() on the column. */
static void column_light(struct section_canvas *c, const struct canvas_column *cc, const struct brightness_map *m,
			 uint32_t out, uint32_t v, uint8_t rgb[3])
{
	if (m) {
		light(c, m, out, v, rgb);
		return;
	}
	column_pixel(cc, v, rgb);
}

/* An upright grid, column by column (what the tile path leaves: RGBA8,
 * and tests): each column's x and z once, its lines mixed along x and z
 * once (trilinear) and then read by every row through the rows' table,
 * bricks whose samples stay below the threshold skipped. The same pixels and colours as the reference loop below, which
 * computes every pixel's f the same way. */
/* Mixes along x and z the samples of col's lit bricks b0..b1 and their
 * neighbours (the bricks the rows read, within jlo..jhi) into mixed. */
static void mix_bricks(struct column *col, const struct scene_grid *gr, const bool *dark, uint32_t b0, uint32_t b1,
		       uint32_t jlo, uint32_t jhi, float *mixed)
{
	for (uint32_t b = b0; b <= b1; b++) {
		if (dark[b] && !(b > b0 && !dark[b - 1]) && !(b < b1 && !dark[b + 1]))
			continue;
		uint32_t j0 = b * SCENE_GRID_BRICK, j1 = j0 + SCENE_GRID_BRICK - 1;
		j0 = j0 > jlo ? j0 : jlo;
		grid_column_mix(col, gr, j0, j1 < jhi ? j1 : jhi, mixed + j0, 1);
	}
}

/* Column col's rows, lit into canvas column out. */
static void column_rows(struct section_canvas *c, const struct grid_job *job, struct column *col, const bool *dark,
			const float *mixed, uint32_t out, const struct brightness_map *m)
{
	const struct scene_draw *d = job->draw;
	const struct scene_grid *gr = d->grid;
	const struct grid_rows *rows = job->rows;
	bool tri = d->transfer.sampling == SCENE_TRILINEAR;
	uint32_t tu = out / VOLUME_TILE;
	struct canvas_column cc = {
		c->rgb + (size_t)tu * HALFTONE_TILE_BYTES + halftone_pos(out % VOLUME_TILE),
		c->rows + tu,
		(size_t)c->tiles_x * HALFTONE_TILE_BYTES,
		c->tiles_x,
	};
	for (uint32_t v = rows->v0; v < rows->v1; v++) {
		const struct grid_row *r = &rows->row[v];
		if (dark[r->j0 / SCENE_GRID_BRICK] && dark[r->j1 / SCENE_GRID_BRICK])
			continue;
		float rgba[4] = { 0 }, val;
		if (!tri) {
			val = value_at(gr, col->i[0], r->j0, col->k[0], rgba);
		} else if (gr->type != SCENE_GRID_RGBA8) {
			val = lerp(mixed[r->j0], mixed[r->j1], r->t);
		} else {
			col->t[1] = r->t;
			const uint32_t j[2] = { r->j0, r->j1 };
			val = trilinear_rgba(gr, col->i, j, col->k, col->t, rgba);
		}
		uint8_t rgb[3];
		if (transfer(d, val, rgba, rgb))
			column_light(c, &cc, m, out, v, rgb);
	}
}

static void draw_upright(struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror,
			 const struct brightness_map *m)
{
	const struct geometry *g = &c->geom;
	const struct scene_draw *d = job->draw;
	const struct scene_grid *gr = d->grid;
	const struct grid_rows *rows = job->rows;
	bool tri = d->transfer.sampling == SCENE_TRILINEAR;
	if (rows->v0 >= rows->v1)
		return;
	/* The samples the rows read, and their bricks. */
	uint32_t ja = rows->row[rows->v0].j0, jb = rows->row[rows->v1 - 1].j0;
	uint32_t jlo = ja < jb ? ja : jb, jhi = rows->row[rows->v0].j1;
	jhi = rows->row[rows->v1 - 1].j1 > jhi ? rows->row[rows->v1 - 1].j1 : jhi;
	uint32_t b0 = jlo / SCENE_GRID_BRICK, b1 = jhi / SCENE_GRID_BRICK;
	bool dark[4096 / SCENE_GRID_BRICK + 1];
	float mixed[4096];
	/* up[0] = up[2] = 0: every row's x and z are row 0's. */
	double bx = job->off[0], bz = job->off[2];
	for (uint32_t u = 0; u < g->width; u++) {
		double s = (u + 0.5) * 2.0 / g->width - 1.0, fx = bx + s * dir[0], fz = bz + s * dir[2];
		if (!(fx >= -0.5 && fx < gr->n[0] - 0.5 && fz >= -0.5 && fz < gr->n[2] - 0.5))
			continue;
		struct column col;
		grid_column_setup(&col, gr, fx, fz, tri);
		if (grid_column_dark(&col, gr, &d->transfer, b0, b1, dark))
			continue;
		if (tri && gr->type != SCENE_GRID_RGBA8)
			mix_bricks(&col, gr, dark, b0, b1, jlo, jhi, mixed);
		column_rows(c, job, &col, dark, mixed, mirror ? g->width - 1 - u : u, m);
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
	if (job->upright && job->rows && !job->reference) {
		if (grid_draw_tiles(c, job, dir, mirror, m))
			return;
		draw_upright(c, job, dir, mirror, m);
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
