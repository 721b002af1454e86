/* Grids (scene.h, SCENE_GRID) on the CPU renderer: each image samples a
 * grid at the centre of every pixel whose centre lies in the grid's box,
 * where the image's slice plane crosses it (docs/rendering.md, "Grids"):
 * the grid's value at the pixel centre's place in the grid, by nearest or
 * trilinear sampling, made a colour by the draw's transfer function,
 * weighted by the brightness model as a surface crossing the slices is,
 * and combined by MAX. Three paths light the same bytes: the reference
 * loop (any transform, pixel by pixel); for a grid whose up axis is the
 * display's, the column path (each pixel column's lines once, the rows
 * through a table, bricks below the threshold skipped) and the tile path
 * (grid_tiles.h: RGBA8 aside, 32 columns at a time, rows in vectors). */
#ifndef SPINDLE_GRID_H
#define SPINDLE_GRID_H

#include <stdbool.h>
#include <stdint.h>

#include "grid_column.h"
#include "scene.h"
#include "section.h"

/* Prepares d (SCENE_GRID). false: its transform cannot be inverted (or
 * is not finite), and it lights nothing. */
bool grid_prepare(struct grid_job *job, const struct scene_draw *d);

/* Makes job->rows for images of geometry g when the grid is upright (the
 * upright path needs them; without them, every image is drawn by the
 * reference loop). false: out of memory. */
bool grid_prepare_rows(struct grid_job *job, const struct geometry *g);
/* Frees what grid_prepare_rows() made. */
void grid_job_finish(struct grid_job *job);

/* Lights, in c, what job's grid shows in the slice plane of volume image
 * src (its angle), columns mirrored (u -> W-1-u) when mirror: image k of a
 * draw turned so that geometry_turn_source() gives src and mirror, or
 * image src itself unturned. */
void grid_draw_image(struct section_canvas *c, const struct grid_job *job, uint32_t src, bool mirror);

/* The colour of the grid's sample at voxel coordinates f (inside the box:
 * -0.5 <= f[a] < n[a] - 0.5), by the draw's transfer. false: dark. */
bool grid_sample(const struct scene_draw *d, const double f[3], uint8_t out[3]);

/* The largest sample (RGBA8: alpha) of each brick of g (scene.h,
 * scene_grid.brick_max), grid_brick_count(g) of them; NaN samples left
 * out (-inf for a brick of them). */
void grid_brick_max(const struct scene_grid *g, float *out);
/* The same for the lines of slabs k0 .. k1 - 1 only (the grid's samples
 * there made), into their places in out (the whole array). */
void grid_brick_max_slabs(const struct scene_grid *g, uint32_t k0, uint32_t k1, float *out);
static inline uint64_t grid_brick_count(const struct scene_grid *g)
{
	return (uint64_t)g->n[0] * g->n[2] * scene_grid_bricks(g->n[1]);
}

#endif
