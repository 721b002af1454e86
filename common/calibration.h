/* Display calibration (docs/rendering.md, "Calibration"): where the images
 * a real projector shows land against the reference frame of docs/design.md
 * section 3, and how the renderers correct for it. The reference frame
 * stays the same; the calibration changes which voxels show it:
 *
 * - phase: the screen has turned phase degrees past image k's nominal
 *   angle 2 pi k / N (towards increasing angles) when image k is shown, so
 *   image k shows the section at angle 2 pi k / N + phase;
 * - vertical scale s and offset o: a point at height y is drawn at height
 *   s y + o (s > 1 when the projector's image came out smaller than
 *   nominal; o, in volume units, moves the picture by a fraction of a row
 *   where the axis offset below moves it by whole rows);
 * - axis offset (u, v): the projector's pixel (W/2 + u, H/2 + v) shows the
 *   axis centre: every image is shifted by u columns and v rows, and what
 *   leaves the image is dropped. On a mirrored device the half turn that
 *   shows images mirrored mirrors them about that axis column (as the
 *   optics that turn the image with the screen do), so both half turns
 *   take the same shift.
 *
 * The phase and the vertical scale are a transform of volume space applied
 * before every layer's own (calibration_transform()); both commute with
 * turns about the axis, so the object cache's turned reuse stays exact.
 * The offset is a whole-pixel shift of the rendered volume
 * (volume_shift()), so a calibrated volume is bit for bit the uncalibrated
 * render of the pre-transformed scene, shifted. */
#ifndef SPINDLE_CALIBRATION_H
#define SPINDLE_CALIBRATION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "geometry.h"

/* The keys, by their config and spindlectl names; the numbers are the
 * protocol's (display.calibrate, enum calibration_key). */
enum calibration_key {
	CALIBRATION_PHASE = 0,           /* "phase-offset", degrees, -180 .. 180 */
	CALIBRATION_AXIS_U = 1,          /* "axis-offset-u", whole pixels */
	CALIBRATION_AXIS_V = 2,          /* "axis-offset-v", whole pixels */
	CALIBRATION_VERTICAL_SCALE = 3,  /* "vertical-scale", 0.5 .. 2 */
	CALIBRATION_VERTICAL_OFFSET = 4, /* "vertical-offset", volume units, -0.5 .. 0.5 */
	CALIBRATION_KEYS = 5,
};

/* Whole-pixel offsets a calibration may hold, whatever the profile; a
 * daemon takes at most a quarter of its image (calibration_check()). */
#define CALIBRATION_MAX_OFFSET 4096

struct calibration {
	float phase_deg;
	int32_t axis_u, axis_v;
	float vertical_scale;
	float vertical_offset;
};

/* No correction. */
void calibration_identity(struct calibration *c);
/* The key's name ("phase-offset", ...), NULL for none; a name's key, or
 * -ENOENT. */
const char *calibration_key_name(unsigned key);
int calibration_key_from_name(const char *name);
/* Sets one key; value checked against the key's range (offsets whole
 * numbers within CALIBRATION_MAX_OFFSET). 0, or -EINVAL (unknown key,
 * NaN or out of range): c unchanged. */
int calibration_set(struct calibration *c, unsigned key, double value);
/* Parses "value" for key (a config line, spindlectl's argument). 0 or
 * -EINVAL. */
int calibration_set_text(struct calibration *c, unsigned key, const char *value);
double calibration_get(const struct calibration *c, unsigned key);
/* The value as the config file holds it ("%g", or a whole number). */
void calibration_format(const struct calibration *c, unsigned key, char *out, size_t size);
/* Whether c fits geometry g: offsets within a quarter of the image. 0 or
 * -EINVAL. */
int calibration_check(const struct calibration *c, const struct geometry *g);

/* Whether c turns, scales or lifts volume space (phase, vertical scale or
 * offset). */
bool calibration_has_transform(const struct calibration *c);
/* The volume-space transform applied after every layer's: a turn by
 * -phase about the y axis (azimuths decreasing: x' = x cos a + z sin a,
 * z' = -x sin a + z cos a, a = phase) with y' = s y + o (the vertical
 * scale and offset). Column-major 4x4. */
void calibration_transform(const struct calibration *c, float m[16]);

#endif
