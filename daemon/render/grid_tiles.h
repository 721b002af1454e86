/* Upright scalar grids a tile column at a time, rows in vectors (AVX-512,
 * AVX2 or GCC's generic vectors, picked at run time): grid_tiles.c. */
#ifndef SPINDLE_GRID_TILES_H
#define SPINDLE_GRID_TILES_H

#include <stdbool.h>

#include "brightness.h"
#include "grid_column.h"
#include "section.h"

/* Draws job's grid (upright, with its rows: grid_prepare_rows()) in image
 * plane direction dir as grid.c's column path does, byte for byte,
 * weighted by m (NULL, or an active brightness map) as grid.c's light()
 * weighs. false: not for this draw (RGBA8, job->columns, or no scratch
 * memory): draw it column by column. */
bool grid_draw_tiles(struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror,
		     const struct brightness_map *m);

/* The variants of the tile path (grid_tiles.c) this machine runs, best
 * first: i = 0, 1, ... until NULL ("avx512", "avx2", "generic"). */
const char *grid_tiles_variant(unsigned i);
/* Makes every later draw use that variant (tests, benchmarks): false if
 * it does not run here. */
bool grid_tiles_use(const char *name);

#endif
