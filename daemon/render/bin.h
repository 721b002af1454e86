/* Per-volume preparation for the CPU renderer: every draw's vertices
 * transformed to volume space once, primitives with a non-finite vertex
 * dropped, and each primitive binned to the volume images whose bow tie it
 * can reach (conservatively: never a missed image, sometimes one too many). */
#ifndef SPINDLE_BIN_H
#define SPINDLE_BIN_H

#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "scene.h"

struct bin_prim {
	double v[3][3];  /* volume-space vertices */
	uint8_t nverts;  /* 1 point, 2 segment, 3 triangle */
	uint8_t rgb[3];
};

/* Storage is kept between builds and only grows. */
struct bin_set {
	uint32_t image_count;
	uint32_t prim_count;
	size_t prim_cap;
	struct bin_prim *prims;
	uint32_t *start;  /* image_count + 1 offsets into index */
	uint32_t *index;  /* primitive numbers, grouped by image, increasing */
	size_t index_cap;
	uint32_t *stamp;  /* per image: last primitive (+1) binned there */
};

/* Returns 0 or -ENOMEM. */
int bin_init(struct bin_set *b, const struct geometry *g);
void bin_finish(struct bin_set *b);

/* Transforms and bins scene. Returns 0, or -ENOMEM / -E2BIG. */
int bin_build(struct bin_set *b, const struct geometry *g, const struct scene *scene);

/* The primitives of image k: b->index[b->start[k] .. b->start[k + 1]). */

#endif
