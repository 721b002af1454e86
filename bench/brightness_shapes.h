/* The known shapes spindle-bench-brightness (brightness.c) shows and
 * profiles, as triangles (the ring: a line strip) in volume space, appended
 * to a vertex buffer (shapes.h), sized in the display's pixels. */
#ifndef SPINDLE_BENCH_BRIGHTNESS_SHAPES_H
#define SPINDLE_BENCH_BRIGHTNESS_SHAPES_H

#include <stdbool.h>
#include <stdint.h>

#include <spindle/spindle.h>

#include "shapes.h"

/* The display as the shapes see it. */
struct light_device {
	uint32_t w, h, n;
	bool mirrored;
	double half_height;
	double r0;    /* pixels */
	double px;    /* volume units per horizontal pixel, 2 / W */
	double row;   /* volume units per row, 2h / H */
	double y_mid; /* the middle of row H/2 */
	/* The wall's and the tubes' extent: rows v0 .. v1 - 1, whole. */
	uint32_t v0, v1;
	double y_top, y_bottom;
};

/* The device of info: r0, pixel sizes, the row of the disk, the rows of the
 * wall and the tubes. */
void light_shape_device(struct light_device *d, const struct spindle_device_info *info);
/* Height of the top of row v (fractional rows allowed). */
double light_shape_row_y(const struct light_device *d, double v);

/* A horizontal disk of radius 1 at the middle of row H/2. */
void light_shape_disk(struct vbuf *m, const struct light_device *d);
/* A vertical rectangle through the axis at azimuth theta, s from -1 to 1,
 * rows v0 .. v1 - 1. */
void light_shape_wall(struct vbuf *m, const struct light_device *d, double theta);
/* A vertical cylinder of radius r_px pixels about the axis, rows v0 .. v1 - 1. */
void light_shape_tube(struct vbuf *m, const struct light_device *d, double r_px);
/* A sphere of radius r_px pixels centred on the axis. */
void light_shape_sphere(struct vbuf *m, const struct light_device *d, double r_px);
/* A horizontal circle of radius r_px at the middle of row H/2, as a closed
 * line strip of segments about a pixel long. */
void light_shape_ring(struct vbuf *m, const struct light_device *d, double r_px);

#endif
