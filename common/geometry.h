/* Device geometry and the volume-space conventions of docs/design.md section 3.
 *
 * Volume space: right-handed, y up along the rotation axis, unit = display
 * radius. Image k of N is shown at theta_k = 2*pi*k/N (from +x towards +z);
 * its in-plane horizontal direction is d_k = (cos theta_k, 0, sin theta_k). */
#ifndef SPINDLE_GEOMETRY_H
#define SPINDLE_GEOMETRY_H

#include <stdbool.h>
#include <stdint.h>

/* How the renderers spread light near the axis (docs/rendering.md,
 * "Brightness"). A lit voxel's light covers its world cell, a wedge one
 * pixel wide and r * D deep at radius r: inside r0 = 1 / D pixels of the
 * axis the cells of neighbouring images overlap. */
enum geometry_brightness {
	/* Every voxel a primitive touches is lit: docs/design.md section 3 as
	 * it stands, the fidelity reference (a surface crossing the slices
	 * glows as 1/r inside r0). */
	GEOMETRY_BRIGHTNESS_EXACT = 0,
	/* Inside r0, a primitive lights each pixel-sized cell of world space
	 * about once per half turn (the daemon's default). */
	GEOMETRY_BRIGHTNESS_EVEN = 1,
	/* The same light per unit area at every radius and orientation, at
	 * the price of brightness where slices are sparse. */
	GEOMETRY_BRIGHTNESS_UNIFORM = 2,
};

struct geometry {
	uint32_t width;          /* W, pixels per image row */
	uint32_t height;         /* H, rows per image */
	uint32_t images_per_rev; /* N, images shown per revolution */
	bool mirrored;           /* image k + N/2 is image k mirrored (N even) */
	float half_height;       /* h, half height / radius */
	float rpm;               /* nominal rotor speed */
	/* enum geometry_brightness: a render setting every stage that
	 * halftones needs, so it travels with the geometry; profiles give
	 * EXACT (0) and the daemon sets its configured one. */
	uint8_t brightness;
};

/* "exact", "even", "uniform"; NULL for an unknown value. */
const char *geometry_brightness_name(unsigned brightness);
/* Parses one of those names. Returns 0, or -EINVAL. */
int geometry_brightness_parse(const char *name, uint8_t *out);

/* r0 = 1 / D = N / (2 pi): the radius in pixels of an image inside which the
 * cells of neighbouring images overlap. */
double geometry_r0_px(const struct geometry *g);

/* Named profiles ("perspecta", "small"). Returns 0, or -ENOENT. */
int geometry_from_profile(const char *name, struct geometry *out);

/* Checks a geometry for sanity (sizes in range, N even when mirrored).
 * Returns 0 or -EINVAL. */
int geometry_validate(const struct geometry *g);

/* Images in one volume: N/2 when mirrored, else N. */
uint32_t geometry_images_per_volume(const struct geometry *g);

/* A turn about the axis by t images (t < N) as an image shift: the volume
 * image whose unturned content volume image k shows, and in *mirror
 * whether mirrored (u -> W-1-u): j = k - t mod N; on a mirrored device
 * j >= M is image j - M mirrored (scene.h, scene_draw.turn). */
uint32_t geometry_turn_source(const struct geometry *g, uint32_t k, uint32_t t, bool *mirror);

/* Angle of image k and its in-plane direction. */
double geometry_image_angle(const struct geometry *g, uint32_t k);

/* Column of signed in-plane coordinate s, row of height y, both clamped:
 * floor(f) clamped to 0..n-1, where truncation is floor for f >= 0 and
 * everything below 0 clamps to 0 anyway. */
static inline uint32_t geometry_clamp_index_(double f, uint32_t n)
{
	if (!(f >= 0.0)) /* also catches NaN */
		return 0;
	if (f >= (double)n)
		return n - 1;
	return (uint32_t)f;
}

static inline uint32_t geometry_column(const struct geometry *g, double s)
{
	return geometry_clamp_index_((s + 1.0) / 2.0 * g->width, g->width);
}

static inline uint32_t geometry_row(const struct geometry *g, double y)
{
	double h = g->half_height;
	return geometry_clamp_index_((h - y) / (2.0 * h) * g->height, g->height);
}

/* Image index lighting azimuth phi = atan2(z, x) with its s >= 0 lobe, and
 * with its s < 0 lobe (round((phi - pi) / D) mod N). */
uint32_t geometry_image_of_azimuth(const struct geometry *g, double phi);
uint32_t geometry_image_of_azimuth_back(const struct geometry *g, double phi);

/* Bytes of one bit plane row, ceil(W/8). */
static inline uint32_t geometry_row_bytes(const struct geometry *g)
{
	return (g->width + 7) / 8;
}

#endif
