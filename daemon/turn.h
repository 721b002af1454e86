/* Turns about the axis by whole images, and lifts along it by whole rows:
 * recognising that a layer's new transform is its earlier one turned about
 * the y axis by m image steps (2 pi m / N) and moved along it by L image
 * rows, so that the object cache can reuse the layer's render at an image
 * index shift (scene_draw.turn) and a row shift (scene_draw.lift) instead
 * of rendering it again.
 *
 * A layer keeps a base transform, a turn and a lift. A new transform T
 * that is, to TURN_TOLERANCE, Y(L h) R_y(2 pi m / N) * base (Y: a move up
 * the axis, h the height of a row) keeps the base and takes turn m and
 * lift L; any other T becomes the base, with turn and lift 0. Both are
 * measured against the base, never against the last transform, so errors
 * do not add up: what is shown is Y(L h) R_y(2 pi m / N) * base exactly,
 * within the tolerance of what the client asked for. */
#ifndef SPINDLE_TURN_H
#define SPINDLE_TURN_H

#include <stdbool.h>
#include <stdint.h>

/* Largest difference, per matrix element, between T and the turned base,
 * relative to the largest element of T (or 1): a twenty-fifth of a voxel
 * (1/384 of the radius at perspecta), and room for a client that turns its
 * float matrix a step at a time for a revolution (unit-turn). */
#define TURN_TOLERANCE 1e-4

/* Whether t is base turned about y by a whole number of images of n per
 * revolution (azimuths increasing: x' = x cos a - z sin a, z' = x sin a +
 * z cos a); the number, 0 .. n-1, in *steps. Matrices are column-major
 * affine 4x4. False when base has nothing off the axis to turn (its xz
 * part is 0: any turn would fit). */
bool turn_find(const float base[16], const float t[16], uint32_t n, uint32_t *steps);

/* Largest lift, in rows, either way: scene_draw.lift's range. */
#define TURN_MAX_LIFT 32767

/* The same, t also moved along the y axis by a whole number of rows of
 * row_h (0: no lift allowed), at most TURN_MAX_LIFT: the number in *lift
 * (positive: up). */
bool turn_find_lift(const float base[16], const float t[16], uint32_t n, double row_h, uint32_t *steps, int32_t *lift);

#endif
