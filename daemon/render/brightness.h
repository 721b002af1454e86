/* The brightness models of geometry.h (docs/rendering.md, "Brightness"):
 * how much of its light a primitive gives each voxel it touches, and the
 * threshold that halftones the result.
 *
 * A lit voxel's light covers its world cell: one pixel wide and r * D deep
 * at radius r pixels (D = 2 pi / N). A surface that every slice crosses
 * lights one voxel per image at each radius, so inside r0 = 1 / D pixels
 * the cells of neighbouring images overlap and its light per unit area
 * rises as 1 / r; a surface lying in a slice plane lights one image only
 * and stays even. The EVEN and UNIFORM models weight a primitive's colour
 * per voxel by
 *
 *     w = min(1, wall / p_wall, rate[u] / p_cross)
 *
 * where p_cross is how much the primitive crosses image k's slice plane
 * (triangles: |n x e_k| = the length of the normal's part in the plane,
 * with e_k the plane's normal; segments: |t . e_k| of the direction t) and
 * p_wall = sqrt(1 - p_cross^2) how much it lies in it; rate[u] = n[u] / M
 * is the share of the M images of a volume in which a crossing primitive
 * lights column u. The weighted value goes into the canvas (per-channel
 * MAX, so the object cache's compositing stays exact) and is halftoned
 * against a threshold that, inside the thinned band, is a Bresenham
 * pattern over the image index: a crossing white primitive at column u is
 * lit in exactly n[u] of every M consecutive images, evenly spaced, so
 * thinning never opens a gap of more than ceil(M / n[u]) images.
 *
 * EVEN: n[u] = min(M, max(1, round(M r_u D))) (r_u: the column's centre radius in
 * pixels), wall = 1: inside r0 each pixel-sized cell of world space is lit
 * about once per half turn whatever the orientation; columns at r0 and
 * beyond, and primitives lying in the slice plane, are untouched.
 * UNIFORM: every orientation and radius at the density a crossing surface
 * has at the rim, d = r0 / R per square pixel (R = W / 2): rate[u] =
 * d r_u D unrounded, n[u] = max(1, round(M d r_u D)), wall = d. A line has no area to even out:
 * in UNIFORM, segments keep EVEN's weights (line_rate), so that thin lines
 * are not broken into dashes. */
#ifndef SPINDLE_BRIGHTNESS_H
#define SPINDLE_BRIGHTNESS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "halftone.h"

struct brightness_map {
	uint8_t model;    /* enum geometry_brightness */
	uint32_t width;   /* W */
	uint32_t images;  /* M: images per volume, the pattern's period */
	uint32_t band_lo; /* columns band_lo..band_hi are thinned (rate < 1 or */
	uint32_t band_hi; /* wall < 1); band_lo > band_hi: none (EXACT) */
	double band_s;    /* |s| of the band's outer column edges (s = p . d_k) */
	double band_d;    /* 2 sin(pi / N) band_s (and a hair): the same against
			   * the sum of a point's distances to a wedge's two
			   * planes, which is 2 sin(pi / N) s (section.c) */
	float wall;       /* the weight of a primitive lying in the plane */
	float *rate;      /* per column: n[u] / M (UNIFORM: d r_u D) */
	float *line_rate; /* per column: segments' rate (EVEN's) */
	uint16_t *n;      /* per column: images of M a crossing primitive lights */
	uint16_t *phase;  /* per radius index i and row v % 16: the pattern's
			    * offset, phase[i * 16 + v % 16] in 0..M-1 */
	uint32_t *solid;  /* per column: brightness_solid_mul() */

	/* Per tile column (32 pixel columns): how a solid weighs it. */
	struct brightness_lanes *lanes;
};

/* How a solid weighs the 32 pixel columns of a tile column, in canvas
 * order (lane p: column 32 tu + (p ^ 7)): every lane as it is (neither
 * weight nor mul), by 16-bit multipliers (mul; bit p of keep: lane p as it
 * is), or by floats (weight) where some lane has no multiplier. */
struct brightness_lanes {
	bool weighed, by_mul;
	uint32_t keep;
	uint16_t mul[32];
	float weight[32];
};

/* brightness_map.solid[u]: how a solid (a grid, crossing every slice: a
 * crossing weight of 1) weighs column u. BRIGHTNESS_KEEP: every byte as it
 * is; m <= 65535: (c * m) >> 16 is brightness_apply()'s value of every
 * byte c, so that a vector can weigh 32 bytes by one 16-bit multiply;
 * BRIGHTNESS_FLOAT: no such m, only brightness_apply()'s floats. */
#define BRIGHTNESS_KEEP 65536u
#define BRIGHTNESS_FLOAT UINT32_MAX

/* Makes g's map (g->brightness). Returns 0 or -ENOMEM. */
int brightness_map_init(struct brightness_map *m, const struct geometry *g);
void brightness_map_finish(struct brightness_map *m);

/* Whether the model changes anything (not EXACT). */
static inline bool brightness_active(const struct brightness_map *m)
{
	return m->band_lo <= m->band_hi;
}

/* Radius index of column u: 0 for the columns either side of the axis, so
 * that u and W-1-u (the mirrored column) share it. */
static inline uint32_t brightness_radius_index(uint32_t width, uint32_t u)
{
	return 2 * u >= width ? u - width / 2 : (width - 1) / 2 - u;
}

/* The threshold (0..254) of pixel (u, v) of volume image k: the ordered
 * dither of halftone.h outside the band, the per-column Bresenham pattern
 * inside it. A value c is lit iff c > threshold. */
uint8_t brightness_threshold(const struct brightness_map *m, uint32_t k, uint32_t u, uint32_t v);

/* A primitive's weights in one image: w(u) = min(kw, rate[u] * inv_cross). */
struct brightness_weight {
	const float *rate; /* the map's rate or line_rate */
	float kw;          /* min(1, wall / p_wall) */
	float inv_cross;   /* 1 / p_cross (a huge value for 0) */
};

/* The weights of the segment (n = 2) or triangle (n = 3) v in the image
 * whose plane has the in-plane direction (dx, 0, dz). A degenerate triangle
 * is its longest side; a segment of no length weighs 1 everywhere. */
void brightness_weight_of(const struct brightness_map *m, const double (*v)[3], int n, double dx, double dz,
			  struct brightness_weight *out);

/* c weighted at column u (c * w(u), rounded down, by a rule the tables
 * above make exact for crossing white primitives). */
static inline uint8_t brightness_apply(const struct brightness_map *m, const struct brightness_weight *wt, uint32_t u,
				       uint8_t c)
{
	float w = wt->rate[u] * wt->inv_cross;
	if (w > wt->kw)
		w = wt->kw;
	if (w >= 1.0f)
		return c;
	return (uint8_t)((float)c * w + 1e-3f);
}

/* Every volume image's halftone tables under a map: halftone.h's table for
 * most tiles, and one of their own for each tile column of the band. */
struct brightness_tables {
	uint32_t images, band_tx0, band_tiles;
	struct halftone_table *base; /* per image */
	struct halftone_table *band; /* per image, band_tiles each */
};

/* Makes the tables of m (band tables only where m is active). Returns 0 or
 * -ENOMEM. */
int brightness_tables_init(struct brightness_tables *t, const struct brightness_map *m);
void brightness_tables_finish(struct brightness_tables *t);

/* The table of image k's tiles in tile column tx. */
static inline const struct halftone_table *brightness_table(const struct brightness_tables *t, uint32_t k, uint32_t tx)
{
	uint32_t b = tx - t->band_tx0;
	return b < t->band_tiles ? &t->band[(size_t)k * t->band_tiles + b] : &t->base[k];
}

#endif
