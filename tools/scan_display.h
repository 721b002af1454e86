/* A scan placed on the display (docs/volumes.md, "spindlectl show of a
 * scan"): its voxel axes put on the display's axes, its samples in the
 * order protocol 6 takes them, the transform that fits it into the
 * cylinder, and the figures a window is chosen from.
 *
 * Orientation. The display (volume space, docs/design.md section 3: y up
 * the rotation axis) shows a patient upright and facing +z:
 *
 *   display +x = patient left (-R),  +y = superior (+S),  +z = anterior (+A)
 *
 * a proper rotation of RAS, so that a viewer on the +z side (where
 * spindlectl preview and spindle-view look from by default) faces the
 * patient, whose left is on the viewer's right, as radiology shows an
 * axial image. Each voxel axis goes to the display axis nearest it, with
 * the sign that keeps it pointing that way: of the six ways to put three
 * voxel axes on three display axes the one whose axes agree best (the
 * largest sum of |cos| of the angles between them), as a "closest
 * canonical" reorientation does. What is left over, an oblique or
 * sheared acquisition's tilt, is ignored (oblique_deg says how much):
 * the voxels are shown on a straight grid, never resampled. */
#ifndef SPINDLE_TOOLS_SCAN_DISPLAY_H
#define SPINDLE_TOOLS_SCAN_DISPLAY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scan.h"

#ifdef __cplusplus
extern "C" {
#endif

struct scan_layout {
	uint32_t dims[3];   /* samples along display x, y (up), z */
	double spacing[3];  /* mm between them */
	unsigned axis[3];   /* display axis a holds voxel axis axis[a] (0: i, 1: j, 2: k) */
	bool flip[3];       /* ... running against the display axis */
	double oblique_deg; /* the largest angle between a voxel axis and its display axis */
};

/* The layout of a scan of dims voxels (i, j, k) with its voxel-to-RAS
 * transform (column-major 4x4, scan.h) and spacing. */
void scan_layout_of(const uint32_t dims[3], const double spacing[3], const double to_ras[16], struct scan_layout *out);

/* The index of s's voxel that the layout puts at display sample (x, y, z). */
size_t scan_layout_source(const struct scan_layout *l, const uint32_t scan_dims[3], uint32_t x, uint32_t y, uint32_t z);

/* s's samples in the layout's order (display x fastest, then y, then z,
 * as display.create_volume takes them) written to fd (a pipe: short
 * writes and EINTR handled) through a buffer of a few MiB. 0 or -errno. */
int scan_layout_write(const struct scan *s, const struct scan_layout *l, int fd);

/* The draw transform (column-major 4x4) from the layout's model units
 * (mm: sample (x, y, z) centred at ((x + 0.5) sx, ...), the box of all of
 * them from 0 to dims * spacing) to volume space: the box's centre at the
 * origin, scaled alike on all axes so that the whole box lies within
 * margin (0 < margin <= 1) of the display, x^2 + z^2 <= margin^2 and |y|
 * <= margin * half_height. */
void scan_layout_fit(const struct scan_layout *l, float half_height, float margin, float m[16]);

/* What a window is chosen from: over every sample of a scalar scan, the
 * smallest value, and the 1st and 99th percentiles of the non-zero ones
 * (NaN and infinities left out; for float32 within 1/65536 of their
 * range). */
struct scan_stats {
	double min;         /* of every finite sample; 0 when none */
	double p1, p99;     /* of the finite non-zero samples */
	uint64_t nonzero;   /* how many there are (0: p1 and p99 are 0) */
	bool looks_like_ct; /* int16 with values below -500 (Hounsfield units: air) */
};

/* The figures of count samples of type (not RGBA8) at data. 0, -EINVAL
 * for RGBA8 or an unknown type, -ENOMEM. */
int scan_stats_of(enum scan_type type, const void *data, size_t count, struct scan_stats *out);

#ifdef __cplusplus
}
#endif

#endif
