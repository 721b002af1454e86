/* spindle-view: the lit voxels of a volume as a point cloud.
 *
 * Voxel (k, u, v) of stored image k stands at s * d_k + y * (0, 1, 0), with
 * d_k = (cos theta_k, 0, sin theta_k), theta_k = 2 pi k / N,
 * s = ((u + 0.5) / W) * 2 - 1 and y = h - (v + 0.5) / H * 2h
 * (docs/design.md section 3). A mirrored volume holds N/2 images, each
 * lighting both lobes of its bow tie: s runs over -1..1, so every stored
 * voxel is one point, once. Its colour is its R, G, B bits. */
#ifndef SPINDLE_TOOLS_VIEW_POINTS_H
#define SPINDLE_TOOLS_VIEW_POINTS_H

#include <stddef.h>
#include <stdint.h>

#include "volume.h"

struct view_point {
	float x, y, z;
	uint8_t rgba[4]; /* each channel 0 or 255; alpha 255 */
};

struct view_points {
	struct view_point *p;
	size_t count, cap;
	uint64_t lit;      /* lit voxels in the volume (count may be fewer) */
	uint32_t stride;   /* every stride-th lit voxel kept */
	float half_height; /* h */
	uint64_t seq;
};

/* Fills pts from vol: every lit voxel, or every stride-th when there are
 * more than max_points (0: no limit). 0 or -ENOMEM. */
int view_points_from_volume(struct view_points *pts, const struct volume *vol, size_t max_points);
void view_points_free(struct view_points *pts);

#endif
