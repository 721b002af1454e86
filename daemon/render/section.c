#include "section.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Clipping a triangle by two planes yields at most 5 vertices; Sutherland-
 * Hodgman on degenerate input can repeat some, never more than double. */
#define SECTION_MAX_VERTS 12

int section_canvas_init(struct section_canvas *c, const struct geometry *g)
{
	c->geom = *g;
	c->tiles_x = (g->width + VOLUME_TILE - 1) / VOLUME_TILE;
	c->tiles_y = (g->height + VOLUME_TILE - 1) / VOLUME_TILE;
	size_t tiles = (size_t)c->tiles_x * c->tiles_y;
	c->rgb = calloc(tiles, HALFTONE_TILE_BYTES);
	c->rows = calloc(tiles, sizeof(*c->rows));
	if (!c->rgb || !c->rows) {
		section_canvas_finish(c);
		return -ENOMEM;
	}
	return 0;
}

void section_canvas_finish(struct section_canvas *c)
{
	free(c->rgb);
	free(c->rows);
	c->rgb = NULL;
	c->rows = NULL;
}

void section_canvas_clear_tile(struct section_canvas *c, uint32_t t)
{
	uint8_t *tile = c->rgb + (size_t)t * HALFTONE_TILE_BYTES;
	uint32_t rows = c->rows[t];
	if (rows == UINT32_MAX) {
		memset(tile, 0, HALFTONE_TILE_BYTES);
	} else {
		for (; rows; rows &= rows - 1) {
			uint32_t y = (uint32_t)__builtin_ctz(rows);
			for (int p = 0; p < 3; p++)
				memset(tile + p * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES, 0, HALFTONE_ROW_BYTES);
		}
	}
	c->rows[t] = 0;
}

void section_wedge_init(struct section_wedge *w, const struct geometry *g, uint32_t k)
{
	double n = g->images_per_rev;
	double theta = geometry_image_angle(g, k);
	double a = 2.0 * M_PI * (k - 0.5) / n, b = 2.0 * M_PI * (k + 0.5) / n;
	w->image = k;
	w->dx = cos(theta);
	w->dz = sin(theta);
	/* sin(phi - a) >= 0 and sin(b - phi) >= 0, times the radius. */
	w->n1x = -sin(a);
	w->n1z = cos(a);
	w->n2x = sin(b);
	w->n2z = -cos(b);
}

/* Per-channel MAX over bytes [a, b] of a canvas row (canvas order). */
static inline void max_bytes(uint8_t *row, uint32_t a, uint32_t b, uint8_t value)
{
	for (uint32_t j = a; j <= b; j++)
		row[j] = row[j] < value ? value : row[j];
}

void section_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1,
		  const uint8_t rgb[3])
{
	uint32_t row = (v / VOLUME_TILE) * c->tiles_x, y = v % VOLUME_TILE;
	for (uint32_t u = u0; u <= u1;) {
		uint32_t t = row + u / VOLUME_TILE;
		uint32_t a = u % VOLUME_TILE, b = (u | 31) < u1 ? 31 : u1 % VOLUME_TILE;
		uint8_t *base = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + y * HALFTONE_ROW_BYTES;
		for (int i = 0; i < 3; i++) {
			if (!rgb[i])
				continue;
			uint8_t *r = base + i * HALFTONE_PLANE_BYTES;
			/* Pixels a..b are bytes a^7..b^7: whole groups of 8
			 * stay whole, partial groups at the ends reverse. */
			uint32_t ga = a & ~7u, gb = b & ~7u;
			if (ga == gb) {
				max_bytes(r, ga + 7 - (b & 7), ga + 7 - (a & 7), rgb[i]);
			} else {
				max_bytes(r, ga, ga + 7 - (a & 7), rgb[i]);
				if (gb > ga + 8)
					max_bytes(r, ga + 8, gb - 1, rgb[i]);
				max_bytes(r, gb + 7 - (b & 7), gb + 7, rgb[i]);
			}
		}
		c->rows[t] |= 1u << y;
		u += b - a + 1;
	}
}

/* One Sutherland-Hodgman pass keeping sign * (nx x + nz z) >= 0 (closed, so
 * geometry on the axis survives every wedge). Returns the vertex count. */
static int clip_plane(const double (*in)[3], int n, double (*out)[3], double nx, double nz)
{
	int m = 0;
	for (int i = 0; i < n; i++) {
		const double *p = in[i], *q = in[(i + 1) % n];
		double dp = nx * p[0] + nz * p[2], dq = nx * q[0] + nz * q[2];
		if (dp >= 0.0)
			memcpy(out[m++], p, sizeof(out[0]));
		if ((dp >= 0.0) != (dq >= 0.0)) {
			double t = dp / (dp - dq);
			for (int j = 0; j < 3; j++)
				out[m][j] = p[j] + t * (q[j] - p[j]);
			m++;
		}
	}
	return m;
}

/* Widens [*lo, *hi] by the s values of edge a-b inside rows' slab
 * ylo <= y <= yhi (either may be infinite). */
static void edge_in_slab(const double a[2], const double b[2], double ylo, double yhi,
			 double *lo, double *hi)
{
	double t0 = 0.0, t1 = 1.0, dy = b[1] - a[1];
	if (dy == 0.0) {
		if (a[1] < ylo || a[1] > yhi)
			return;
	} else {
		double ta = (ylo - a[1]) / dy, tb = (yhi - a[1]) / dy;
		t0 = fmax(0.0, fmin(ta, tb));
		t1 = fmin(1.0, fmax(ta, tb));
		if (t0 > t1)
			return;
	}
	double s0 = a[0] + t0 * (b[0] - a[0]), s1 = a[0] + t1 * (b[0] - a[0]);
	*lo = fmin(*lo, fmin(s0, s1));
	*hi = fmax(*hi, fmax(s0, s1));
}

/* Conservative rasterisation of a convex polygon in (s, y): per row, the s
 * range of the polygon within the row's slab gives the columns. The outer
 * rows' slabs extend to infinity: that is the clamp to the image. */
static void raster_convex(struct section_canvas *c, const double (*q)[2], int n,
			  const uint8_t rgb[3])
{
	const struct geometry *g = &c->geom;
	if (n <= 0)
		return;
	double ymin = q[0][1], ymax = q[0][1];
	for (int i = 1; i < n; i++) {
		ymin = fmin(ymin, q[i][1]);
		ymax = fmax(ymax, q[i][1]);
	}
	double h = g->half_height, row_h = 2.0 * h / g->height;
	/* A hair of slack so rounding at a row edge never loses a touch. */
	double eps = 1e-9 * row_h;
	uint32_t v0 = geometry_row(g, ymax), v1 = geometry_row(g, ymin);
	for (uint32_t v = v0; v <= v1; v++) {
		double yhi = v == 0 ? INFINITY : h - v * row_h + eps;
		double ylo = v == g->height - 1 ? -INFINITY : h - (v + 1) * row_h - eps;
		double lo = INFINITY, hi = -INFINITY;
		for (int i = 0; i < n; i++)
			edge_in_slab(q[i], q[(i + 1) % n], ylo, yhi, &lo, &hi);
		if (lo <= hi)
			section_span(c, v, geometry_column(g, lo), geometry_column(g, hi), rgb);
	}
}

static void section_lobe(struct section_canvas *c, const struct section_wedge *w,
			 const double (*v)[3], int n, double sign, const uint8_t rgb[3])
{
	double a[SECTION_MAX_VERTS][3], b[SECTION_MAX_VERTS][3], q[SECTION_MAX_VERTS][2];
	int m = clip_plane(v, n, a, sign * w->n1x, sign * w->n1z);
	if (m == 0)
		return;
	m = clip_plane((const double (*)[3])a, m, b, sign * w->n2x, sign * w->n2z);
	if (m == 0)
		return;
	for (int i = 0; i < m; i++) {
		q[i][0] = b[i][0] * w->dx + b[i][2] * w->dz;
		q[i][1] = b[i][1];
	}
	raster_convex(c, (const double (*)[2])q, m, rgb);
}

void section_prim(struct section_canvas *c, const struct section_wedge *w,
		  const double (*v)[3], int n, const uint8_t rgb[3])
{
	section_lobe(c, w, v, n, 1.0, rgb);
	section_lobe(c, w, v, n, -1.0, rgb);
}

