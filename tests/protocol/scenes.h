/* Shapes, checks and helpers shared by the protocol test programs: the
 * small profile's geometry (docs/design.md section 3, computed here, not by
 * spindled), shapes as vertex arrays, and libspindle shorthands. */
#ifndef SPINDLE_TEST_SCENES_H
#define SPINDLE_TEST_SCENES_H

#include "harness.h"

#define W 128
#define H 128
#define NV 64 /* images per volume: N = 128, mirrored */

struct geometry small(void);
/* Column of volume-space s, row of height y, at the small profile, under
 * the suite's calibration (test_calibration(): the column moved by its U,
 * the height y made SCALE y + OFFSET and the row moved by its V); and back,
 * the s and height of the centre of column u and row v. Columns and rows
 * of an axis-symmetric shape: the phase does not move it. */
int col(double s);
int row(double y);
double col_s(int u);
double row_y(int v);

/* Shapes: vertices written to v, their count returned. The axis from
 * y -0.6 to 0.6 as one line; a horizontal disk of radius r at height y as
 * a fan of segs triangles; a sphere of radius r about the origin. */
uint32_t axis_line(float *v);
uint32_t disk(float *v, double r, double y, int segs);
uint32_t sphere(float *v, double r, int slices, int stacks);

/* Channel c of vol shows axis_line() and nothing else. */
void check_axis_line(const struct volume *vol, int c);
/* The next volume shown (captured) is axis_line() in white. */
void check_shows_axis_line(struct spindle *sp);

uint64_t mono_ns(void);

/* Lit pixels of channel c in image k, and in the whole volume. */
uint64_t count_lit_image(const struct volume *vol, uint32_t k, int c);
uint64_t count_lit(const struct volume *vol, int c);

extern const float identity[16];
/* Identity moved by dx along x. */
void shift_x(float m[16], float dx);

/* n triangle vertices v in one colour on a layer of their own, committed
 * and shown; frame says by which volume. */
struct spindle_layer *show_triangles(struct spindle *sp, struct spindle_frame *frame, const float *v, uint32_t n,
				     uint8_t r, uint8_t g, uint8_t b);

struct spindle_status status_of(struct spindle *sp);

/* A test program's tests by name: runs the one named in argv[1] (every
 * one without an argument), printing "ok NAME" after each; returns the
 * exit status. */
struct named_test {
	const char *name;
	void (*run)(void);
};
int run_named_tests(const struct named_test *tests, size_t count, int argc, char **argv);

#endif
