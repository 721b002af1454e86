/* Geometry for the benchmark scenes: growable vertex arrays, wireframe
 * shapes with exactly known segment counts, a small closed mesh, and affine
 * transforms in the column-major layout of struct scene_draw. */
#ifndef SPINDLE_BENCH_SHAPES_H
#define SPINDLE_BENCH_SHAPES_H

#include <stdbool.h>
#include <stdint.h>

/* Vertices, 3 floats each. On allocation failure oom is set and further
 * vertices are dropped. */
struct vbuf {
	float *xyz;
	uint32_t count;
	uint32_t cap;
	bool oom;
};

void vbuf_add(struct vbuf *b, double x, double y, double z);
/* Accepts an empty buffer. */
void vbuf_free(struct vbuf *b);

/* Each shape appends its primitives (segments as vertex pairs, triangles as
 * vertex triples) centred on the origin and returns how many it added. */

/* The edges of a latitude-longitude sphere of radius r: slices meridians
 * from pole to pole in stacks steps, and the stacks - 1 parallels between:
 * slices * (2 * stacks - 1) segments. */
uint32_t shape_sphere_edges(struct vbuf *b, double r, uint32_t slices, uint32_t stacks);

/* The edges of a torus about the y axis, ring radius R, tube radius r, with
 * major steps around the ring and minor around the tube: 2 * major * minor
 * segments. */
uint32_t shape_torus_edges(struct vbuf *b, double R, double r, uint32_t major, uint32_t minor);

/* A helix about the y axis, radius r, from y = -height/2 to height/2 over
 * turns turns, as segments segments. */
uint32_t shape_helix(struct vbuf *b, double r, double height, double turns, uint32_t segments);

/* A regular icosahedron of circumradius r: 20 triangles. */
uint32_t shape_icosahedron(struct vbuf *b, double r);

/* The largest sphere (slices = 2 * stacks) and torus (major = 2 * minor)
 * resolutions whose segment counts fit in budget (at least 3 and 2 steps). */
void shape_sphere_fit(uint32_t budget, uint32_t *slices, uint32_t *stacks);
void shape_torus_fit(uint32_t budget, uint32_t *major, uint32_t *minor);

/* out = translate(t) * rotate_y(ay) * rotate_x(ax) * scale(s), column-major
 * (angles in radians). */
void mat4_pose(float out[16], const double t[3], double ax, double ay, double s);

#endif
