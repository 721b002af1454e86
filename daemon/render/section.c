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
	c->rgb = calloc(tiles, SECTION_TILE_RGB_BYTES);
	c->touched = calloc(tiles, 1);
	if (!c->rgb || !c->touched) {
		section_canvas_finish(c);
		return -ENOMEM;
	}
	return 0;
}

void section_canvas_finish(struct section_canvas *c)
{
	free(c->rgb);
	free(c->touched);
	c->rgb = NULL;
	c->touched = NULL;
}

void section_canvas_clear_tile(struct section_canvas *c, uint32_t t)
{
	memset(c->rgb + (size_t)t * SECTION_TILE_RGB_BYTES, 0, SECTION_TILE_RGB_BYTES);
	c->touched[t] = 0;
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

static inline void light_px(uint8_t *px, const uint8_t rgb[3])
{
	for (int i = 0; i < 3; i++)
		if (px[i] < rgb[i])
			px[i] = rgb[i];
}

void section_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1,
		  const uint8_t rgb[3])
{
	uint32_t row = (v / 32) * c->tiles_x;
	for (uint32_t u = u0; u <= u1;) {
		uint32_t t = row + u / 32;
		uint32_t end = (u | 31) < u1 ? (u | 31) : u1;
		uint8_t *base = c->rgb + (size_t)t * SECTION_TILE_RGB_BYTES + (v % 32) * 32 * 3;
		for (; u <= end; u++)
			light_px(base + (u % 32) * 3, rgb);
		c->touched[t] = 1;
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

void section_point_images(const struct geometry *g, const double p[3], uint32_t out[2])
{
	uint32_t m = geometry_images_per_volume(g);
	double phi = atan2(p[2], p[0]);
	out[0] = geometry_image_of_azimuth(g, phi) % m;
	out[1] = geometry_image_of_azimuth_back(g, phi) % m;
}

bool section_point(struct section_canvas *c, const struct section_wedge *w,
		   const double p[3], const uint8_t rgb[3])
{
	uint32_t img[2];
	section_point_images(&c->geom, p, img);
	if (img[0] != w->image && img[1] != w->image)
		return false;
	/* Both lobes of one volume image map p to the same voxel. */
	uint32_t u = geometry_column(&c->geom, p[0] * w->dx + p[2] * w->dz);
	uint32_t v = geometry_row(&c->geom, p[1]);
	section_span(c, v, u, u, rgb);
	return true;
}
