/* Grids (scene.h, SCENE_GRID) on the CPU renderer: each image samples a
 * grid at the centre of every pixel whose centre lies in the grid's box,
 * where the image's slice plane crosses it (docs/rendering.md, "Grids").
 * This is the scalar reference path: a sample is the grid's value at the
 * pixel centre's place in the grid, by nearest or trilinear sampling, made
 * a colour by the draw's transfer function, weighted by the brightness
 * model as a surface crossing the slices is, and combined by MAX. */
#ifndef SPINDLE_GRID_H
#define SPINDLE_GRID_H

#include <stdbool.h>
#include <stdint.h>

#include "scene.h"
#include "section.h"

/* One grid draw, prepared once per render: volume space to the grid's
 * voxel coordinates (voxel (i, j, k) centred at integers), an affine map
 * f = lin p + off. */
struct grid_job {
	const struct scene_draw *draw;
	double lin[3][3], off[3];
	bool upright;   /* the grid's up axis is the display's: column by column */
	bool reference; /* draw by the reference loop anyway (tests) */
	/* NULL, or (nearest sampling of u8, u16 or i16 samples) each value's
	 * colour by the transfer, 4 bytes R, G, B, lit; at value + 32768 for
	 * i16 (grid_colours()). Not owned. */
	const uint8_t *colours;
};

/* Prepares d (SCENE_GRID). false: its transform cannot be inverted (or
 * is not finite), and it lights nothing. */
bool grid_prepare(struct grid_job *job, const struct scene_draw *d);

/* Lights, in c, what job's grid shows in the slice plane of volume image
 * src (its angle), columns mirrored (u -> W-1-u) when mirror: image k of a
 * draw turned so that geometry_turn_source() gives src and mirror, or
 * image src itself unturned. */
void grid_draw_image(struct section_canvas *c, const struct grid_job *job, uint32_t src, bool mirror);

/* The colour of the grid's sample at voxel coordinates f (inside the box:
 * -0.5 <= f[a] < n[a] - 0.5), by the draw's transfer. false: dark. */
bool grid_sample(const struct scene_draw *d, const double f[3], uint8_t out[3]);

/* The largest sample (RGBA8: alpha) of each line of g along its up axis,
 * out[k * n[0] + i]; NaN samples left out (-inf for a line of them):
 * scene_grid.line_max, which lets the renderer skip dark columns. */
void grid_line_max(const struct scene_grid *g, float *out);

/* Entries of d's colour table (65536 for u16 and i16, 256 for u8), or 0
 * when it has none (trilinear, f32, RGBA8); and the table: what the
 * transfer gives each value, so looked up it lights what sampling does. */
size_t grid_colours_size(const struct scene_draw *d);
void grid_colours(const struct scene_draw *d, uint8_t *out);

#endif
