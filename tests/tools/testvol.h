/* Test helpers: check macro and a builder that lights single voxels and
 * turns the result into a tile-sparse struct volume. */
#ifndef SPINDLE_TESTS_TOOLS_TESTVOL_H
#define SPINDLE_TESTS_TOOLS_TESTVOL_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "volume.h"

#define CHECK(cond)                                                                              \
	do {                                                                                     \
		if (!(cond)) {                                                                   \
			fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
			exit(1);                                                                 \
		}                                                                                \
	} while (0)

/* One byte per voxel and channel bit (bit c = channel c), all images. */
struct testvol {
	struct geometry geom;
	uint32_t images;
	uint8_t *bits;
};

struct testvol *testvol_create(const struct geometry *geom);
void testvol_destroy(struct testvol *tv);
/* ORs rgb_bits (bit 0 R, 1 G, 2 B) into voxel (k, u, v). */
void testvol_set(struct testvol *tv, uint32_t k, uint32_t u, uint32_t v, unsigned rgb_bits);
/* Lights the voxel owning volume-space point p in its s >= 0 lobe (docs/design.md
 * section 3 ownership; a mirrored volume stores image k + N/2 as image k). */
void testvol_light_point(struct testvol *tv, const double p[3], unsigned rgb_bits);
/* A new volume holding the lit voxels (exits on failure). */
struct volume *testvol_to_volume(const struct testvol *tv);

#endif
