/* A picture of a volume as a person standing beside the display sees it:
 * every lit voxel is the light of one pixel flashed for one slice period,
 * spread over its world cell (docs/design.md section 3), seen in perspective
 * through the transparent, emissive volume, added up and tone-mapped onto a
 * dark background.
 *
 * Voxel (k, u, v) of stored image k has s = ((u + 0.5) / W) * 2 - 1 and
 * y = h - (v + 0.5) / H * 2h. Its light is spread evenly along the arc
 * s * (cos a, 0, sin a) + y * (0, 1, 0), a from theta_k - D/2 to
 * theta_k + D/2 (D = 2 pi / N; for s < 0 that is the lobe about
 * theta_k + pi), and over its pixel's width and height (a tent filter one
 * pixel pitch wide). Every voxel carries the same light wherever it is, with
 * no weight for its radius: cells are r * D deep at radius r, so a surface
 * that every slice crosses collects light as 1/r and glows at the axis, as
 * on the display. The eye receives a voxel's light by the inverse square law
 * (the weight (distance / |p - eye|)^2, 1 at the display's centre), so an
 * evenly lit surface looks as bright far as near. Light L becomes
 * bg + (255 - bg) * (1 - e^(-gain * L)) per channel over the background bg,
 * the gain taken from the lit pixels (the 99th percentile of their light at
 * 86%, and the median at least at 63%, so a hot spot saturates rather than
 * darkening the rest). Each stored image covers both lobes of its bow tie,
 * so a mirrored volume (N/2 images) is drawn image by image once, like an
 * unmirrored one. */
#ifndef SPINDLE_TOOLS_PREVIEW_H
#define SPINDLE_TOOLS_PREVIEW_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "volume.h"

struct preview_options {
	uint32_t width, height; /* picture size, pixels (default 640 x 640) */
	double distance;        /* eye distance from the centre, radii (3.2) */
	double elevation_deg;   /* eye above the horizon (20) */
	double azimuth_deg;     /* eye azimuth from +x towards +z (90: on +z) */
	bool outline;           /* faint outline of the display cylinder (true) */
	/* NULL (the default), or where to say how far a preview that takes
	 * over a second has got: "NAME: drawing, image K of M, T s so far"
	 * after 1 s and then every 2 s, and how long it took. */
	FILE *progress;
	const char *progress_name; /* NAME above ("preview" when NULL) */
	double progress_after;     /* the first line after this many seconds (1) */
};

/* Fills in the defaults above. */
void preview_default_options(struct preview_options *opt);

/* Renders vol into rgb, opt->width * opt->height * 3 bytes, rows top to
 * bottom. The view is framed so the whole display cylinder just fits.
 * 0, -EINVAL for bad options (size 0 or over 16384, distance not outside
 * the cylinder), or -ENOMEM. */
int preview_render(const struct volume *vol, const struct preview_options *opt, uint8_t *rgb);

/* Where volume-space point p lands in the picture preview_render() makes of
 * a volume with half height h: pixel coordinates (x right, y down, pixel
 * centres at +0.5). 0, or -EINVAL for bad options or a point behind the eye. */
int preview_project(const struct preview_options *opt, double h, const double p[3], double *x, double *y);

/* Writes an 8-bit RGB PNG. 0 or negative errno (-EIO for a libpng error). */
int preview_write_png(const char *path, const uint8_t *rgb, uint32_t width, uint32_t height);

/* preview_render() + preview_write_png(). opt NULL means defaults. */
int preview_volume_to_png(const struct volume *vol, const struct preview_options *opt, const char *path);

#endif
