/* Light per unit area against the distance from the rotation axis, measured
 * on a captured volume of one known shape (issue "Even brightness"; the
 * brightness models of docs/rendering.md, "Brightness").
 *
 * Each lit voxel (image k, column u, row v; any of R, G, B set counts once)
 * is one unit of light. It is counted in the radial band of its column's
 * radius r = |u + 0.5 - W/2| pixels; the bands are [0,1), [1,2), [2,4),
 * [4,8), ... doubling, the last one ending at the rim W/2. A band's light
 * per area is its lit voxels (over every image of the file) divided by the
 * shape's surface area inside that band, in square pixels: the shape as
 * drawn in pixel space, where a pixel is 2/W volume units horizontally and
 * 2h/H vertically (a horizontal disk of radius R pixels has pi R^2 px^2, a
 * vertical wall w pixels wide and rows high has w * rows). Relative values
 * are against the band that holds r0 = N / (2 pi) pixels (geometry_r0_px()).
 *
 * In the exact brightness model a surface that every slice crosses (a
 * horizontal disk, a tube about the axis) gets r0 / r voxels per px^2: the
 * glow of the axis. A plane through the axis (a wall) lies in one slice and
 * gets 1 at every radius.
 *
 * Pure computation: no I/O, no allocation. */
#ifndef SPINDLE_BENCH_LIGHT_PROFILE_H
#define SPINDLE_BENCH_LIGHT_PROFILE_H

#include <stddef.h>
#include <stdint.h>

/* Bands for W up to 2^(MAX-2) pixels (geometry_validate() allows 8192). */
#define LIGHT_PROFILE_MAX_BANDS 16

/* The shapes the profile knows the area of, all centred on the axis
 * (volume space: y up the axis, display radius 1). */
enum light_shape_kind {
	LIGHT_SHAPE_DISK,   /* horizontal disk, radius `radius` */
	LIGHT_SHAPE_WALL,   /* vertical rectangle through the axis, s from -radius to radius,
			     * `height` high: both sides of the axis */
	LIGHT_SHAPE_TUBE,   /* vertical cylinder, radius `radius`, `height` high (no caps) */
	LIGHT_SHAPE_SPHERE, /* sphere of radius `radius` centred on the axis */
	LIGHT_SHAPE_RING,   /* horizontal circle of radius `radius`: a line, counted as a band
			     * one pixel (one row) high, so its value is light per pixel of length */
};

struct light_shape {
	enum light_shape_kind kind;
	double radius; /* volume units (1 = the display's radius) */
	double height; /* wall, tube: extent along y, volume units; else unused */
};

struct light_band {
	double lo, hi;   /* column radius, pixels: [lo, hi) */
	uint64_t lit;    /* lit voxels whose column is in the band */
	double area;     /* the shape's area in the band, px^2 (0: the shape is not there) */
	double value;    /* lit / area; 0 when area is 0 */
	double relative; /* value / the r0 band's value; 0 when either is unknown */
};

struct light_profile {
	/* From the file's header. */
	uint32_t width, height; /* W, H */
	uint32_t images;        /* images in the file (N/2 when mirrored) */
	uint32_t images_per_rev;
	int mirrored;
	double half_height;
	double r0_px; /* N / (2 pi) */

	unsigned band_count;
	struct light_band band[LIGHT_PROFILE_MAX_BANDS];
	int r0_band; /* the band holding r0; -1 when r0 lies past the rim */

	/* The whole shape: every lit voxel of the file over its whole area
	 * (for a tube or a ring, which lies at one radius, its one number). */
	uint64_t lit;
	double area;
	double value;
};

/* The band edges for images W pixels wide: [0,1), [1,2), [2,4), ..., the
 * last ending at W/2. Fills lo[] and hi[] (max entries each); returns the
 * band count (0 when W < 2 or max is too small). */
unsigned light_profile_bands(uint32_t width, double lo[], double hi[], unsigned max);

/* The shape's area in px^2 between column radii lo and hi pixels, on images
 * W x H with half height h. */
double light_shape_area(const struct light_shape *shape, uint32_t width, uint32_t height, double half_height, double lo,
			double hi);

/* Profiles the capture svol (size bytes, a whole .svol file: docs/formats.md)
 * of the shape. Returns 0, or -EINVAL for a buffer that is no valid .svol
 * file, a shape of no area, or images wider than the bands allow. */
int light_profile_compute(const uint8_t *svol, size_t size, const struct light_shape *shape, struct light_profile *out);

/* The largest relative value of the bands with some area whose lower edge
 * lies in [from_px, to_px] (e.g. 2 and r0: "2 px to r0", the r0 band
 * included). 0 when there is none or no r0 band. */
double light_profile_peak_relative(const struct light_profile *p, double from_px, double to_px);

#endif
