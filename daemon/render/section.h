/* Exact sectioning by one image's bow tie, and conservative rasterisation of
 * the sections into an 8-bit RGB canvas (DESIGN.md section 3).
 *
 * Image k's bow tie is two closed wedges meeting at the y axis, bounded by
 * the planes through the axis at azimuths theta_k - D/2 and theta_k + D/2:
 * lobe s >= 0 around theta_k and lobe s < 0 around theta_k + pi. A primitive
 * is clipped to each lobe, the convex piece projected to (s, y) with
 * s = p . d_k, and every pixel whose cell that piece touches is lit. */
#ifndef SPINDLE_SECTION_H
#define SPINDLE_SECTION_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry.h"
#include "volume.h"

/* An 8-bit RGB accumulation buffer for one image, stored tile by tile (32x32
 * pixels, row-major inside a tile, 3 bytes a pixel) so that halftoning and
 * clearing a tile touch one contiguous block. Only tiles flagged in touched
 * may hold non-zero bytes. */
struct section_canvas {
	struct geometry geom;
	uint32_t tiles_x, tiles_y;
	uint8_t *rgb;     /* tiles_x * tiles_y * SECTION_TILE_RGB_BYTES */
	uint8_t *touched; /* tiles_x * tiles_y flags */
};

#define SECTION_TILE_RGB_BYTES (VOLUME_TILE * VOLUME_TILE * 3)

/* The two half-spaces of image k's s >= 0 lobe, as inward normals in the xz
 * plane; the s < 0 lobe is their negation. */
struct section_wedge {
	uint32_t image;    /* k, in volume images */
	double dx, dz;     /* d_k */
	double n1x, n1z;   /* plane at theta_k - D/2 */
	double n2x, n2z;   /* plane at theta_k + D/2 */
};

/* Allocates a zeroed canvas. Returns 0 or -ENOMEM. */
int section_canvas_init(struct section_canvas *c, const struct geometry *g);
void section_canvas_finish(struct section_canvas *c);

/* Zeroes tile t and clears its touched flag. */
void section_canvas_clear_tile(struct section_canvas *c, uint32_t t);

void section_wedge_init(struct section_wedge *w, const struct geometry *g, uint32_t k);

/* Lights columns u0..u1 of row v by per-channel MAX with rgb. */
void section_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1,
		  const uint8_t rgb[3]);

/* Sections a segment (n = 2) or triangle (n = 3), vertices in volume space
 * and finite, by both lobes of the wedge's image and lights what it touches,
 * clamped to the image. Degenerate primitives light their section too. */
void section_prim(struct section_canvas *c, const struct section_wedge *w,
		  const double (*v)[3], int n, const uint8_t rgb[3]);

/* Lights point p in the wedge's image if it owns p by the azimuth rule of
 * DESIGN.md (one voxel per owning lobe, clamped). Returns whether it did. */
bool section_point(struct section_canvas *c, const struct section_wedge *w,
		   const double p[3], const uint8_t rgb[3]);

/* The volume images that own point p (its s >= 0 and s < 0 lobes); equal
 * when the device is mirrored, except on a rounding tie. */
void section_point_images(const struct geometry *g, const double p[3], uint32_t out[2]);

#endif
