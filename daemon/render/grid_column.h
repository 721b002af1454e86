/* Grids on the CPU renderer, what grid.c and grid_tiles.c share: a
 * prepared grid draw (struct grid_job), the sampling arithmetic every path
 * does the same way (so that every path equals the reference loop bit for
 * bit), and one pixel column of an upright grid: its lines, which of their
 * bricks may light, their samples as the rows read them. */
#ifndef SPINDLE_GRID_COLUMN_H
#define SPINDLE_GRID_COLUMN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scene.h"

/* One grid draw, prepared once per render: volume space to the grid's
 * voxel coordinates (voxel (i, j, k) centred at integers), an affine map
 * f = lin p + off. */
struct grid_job {
	const struct scene_draw *draw;
	double lin[3][3], off[3];
	bool upright;   /* the grid's up axis is the display's: column by column */
	bool reference; /* draw by the reference loop anyway (tests) */
	bool columns;   /* upright: column by column, never by tiles (tests) */
	/* NULL, or (upright only; grid_prepare_rows()) where each row of an
	 * image samples: the same for every image and column, as the grid's
	 * up axis is the display's. Owned: grid_job_finish() frees it. */
	struct grid_rows *rows;
};

/* Row v of an upright grid's images samples j0 (nearest: the sample) and,
 * trilinear, j1 = j0 + 1 (clamped) with weight t; rows v0 .. v1 - 1 lie in
 * the grid's box (none when v0 >= v1). */
struct grid_row {
	uint32_t j0, j1;
	float t;
};
struct grid_rows {
	uint32_t v0, v1;
	struct grid_row row[];
};

static inline float lerp(float a, float b, float t)
{
	return a * (1.0f - t) + b * t;
}

/* i clamped to 0 .. n - 1: the edge samples repeated. */
static inline uint32_t grid_clamp_index(int64_t i, uint32_t n)
{
	return i < 0 ? 0 : i >= (int64_t)n ? n - 1 : (uint32_t)i;
}

/* One pixel column of an upright grid: the one line (nearest) or four
 * lines (trilinear) of samples it reads, with what sample_at() works out
 * per axis for x and z, done once. */
struct column {
	uint32_t i[2], k[2]; /* sample indices (clamped), the second of each pair for trilinear */
	float t[3];          /* trilinear weights along x and z (t[1]: the row's) */
	size_t line[4];      /* where line (i[b & 1], k[b >> 1]) starts */
	int lines;           /* 1 (nearest) or 4 */
};

/* The column at grid coordinates fx, fz (inside the box). */
void grid_column_setup(struct column *col, const struct scene_grid *gr, double fx, double fz, bool tri);

/* Which bricks b0 .. b1 of the column hold nothing that lights: every
 * sample its lines have there below the threshold, by the bricks' maxima
 * (none known: none dark), in dark[b]. Trilinear mixes may round a hair
 * above their largest sample: a margin of 1e-5 of it. Returns whether all
 * are dark. */
bool grid_column_dark(const struct column *col, const struct scene_grid *gr, const struct scene_transfer *tf,
		      uint32_t b0, uint32_t b1, bool *dark);

/* A scalar grid's samples j0 .. j1 of col as the rows read them, at out[(j
 * - j0) stride]: trilinear, its lines mixed along x and z (what the
 * reference computes at row j before mixing along y); nearest, its line's
 * samples as numbers. */
void grid_column_mix(const struct column *col, const struct scene_grid *gr, uint32_t j0, uint32_t j1, float *out,
		     size_t stride);

#endif
