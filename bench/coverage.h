/* Compares a renderer's volume with the exact reference's, voxel by voxel
 * with a one-voxel tolerance: how much of the reference a renderer lights
 * (coverage) and how much it lights that the reference does not (stray).
 *
 * Two voxels are within one voxel when their images, columns and rows each
 * differ by at most 1 (the 3x3x3 neighbourhood in (k, u, v)). Images wrap
 * around the revolution: on a mirrored device the neighbour after the last
 * image of the volume is image 0 mirrored (u -> W-1-u), since image N/2 is
 * image 0 mirrored; unmirrored, it is image 0. Colour channels are compared
 * separately: a voxel lit in R is covered by a lit R voxel only.
 *
 * The work is per tile: tiles empty in the volume being checked cost
 * nothing, and a lit voxel's neighbourhood is looked up 32 pixels at a time
 * in the other volume's tiles. */
#ifndef SPINDLE_BENCH_COVERAGE_H
#define SPINDLE_BENCH_COVERAGE_H

#include <stdbool.h>
#include <stdint.h>

#include "volume.h"

struct coverage {
	bool identical;          /* every voxel equal */
	uint64_t ref_lit[3];     /* lit voxels of the reference, per channel R, G, B */
	uint64_t ref_covered[3]; /* of those, with a lit test voxel within one voxel */
	uint64_t test_lit[3];    /* lit voxels of the volume under test */
	uint64_t test_stray[3];  /* of those, with no lit reference voxel within one voxel */
};

/* Compares test against ref, two volumes of the same geometry. Returns 0,
 * -EINVAL (geometries differ) or -ENOMEM. */
int coverage_compare(const struct volume *ref, const struct volume *test, struct coverage *out);

/* Over all channels: covered / lit of the reference (1 when it lights
 * nothing), and stray / lit of the test (0 when it lights nothing). */
double coverage_score(const struct coverage *c);
double coverage_stray(const struct coverage *c);

#endif
