/* What spindle-bench-brightness (brightness.c) measures, and how it is
 * judged and printed (brightness_report.c): a result per shape shown, the
 * summary over them, the checks of the daemon's brightness models, the
 * tables and the JSON object. */
#ifndef SPINDLE_BENCH_BRIGHTNESS_REPORT_H
#define SPINDLE_BENCH_BRIGHTNESS_REPORT_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "brightness_shapes.h"
#include "light_profile.h"

enum shape { SHAPE_DISK, SHAPE_WALL, SHAPE_TUBES, SHAPE_RING, SHAPE_SPHERE, SHAPE_COUNT };

extern const char *const shape_names[SHAPE_COUNT];
/* The default: the surfaces the checks are written for. `all` adds the
 * extras: the ring (a line: its value is light per pixel of length, left
 * out of the checks) and the sphere (a surface: checked like the others). */
#define DEFAULT_SHAPES ((1u << SHAPE_DISK) | (1u << SHAPE_WALL) | (1u << SHAPE_TUBES))
#define ALL_SHAPES ((1u << SHAPE_COUNT) - 1)

enum check { CHECK_NONE = -1, CHECK_EXACT, CHECK_EVEN, CHECK_UNIFORM };
extern const char *const check_names[3];

struct result {
	enum shape shape;
	double nominal_px, radius_px; /* tubes, ring, sphere: asked for and drawn */
	struct light_shape ls;
	struct light_profile prof;
	double relative; /* tubes: value / the r0 tube's value (0: unknown) */
};

struct run {
	struct spindle *sp;
	struct spindle_layer *layer;
	struct light_device dev;
	struct result *results;
	size_t count, cap;
};

/* Radius at the centre of the pixel column that holds r_px: a tube there
 * lights one column a row on each side of the axis, never two. */
static inline double column_centre(double r_px)
{
	return floor(r_px) + 0.5;
}

/* Prints what run measured of the shapes asked for (tables and a summary,
 * or, json, one JSON object) and judges it by check (enum check;
 * CHECK_NONE: not judged). Whether the check passed; where it did not,
 * why, in msg (size bytes). */
bool report_run(const struct run *run, unsigned shapes, int check, bool json, char *msg, size_t size);

#endif
