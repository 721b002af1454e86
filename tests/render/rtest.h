/* Helpers shared by the renderer tests: geometries, scenes and meshes, and
 * reading rendered volumes back. Expectations are computed by the tests from
 * docs/design.md section 3 and common/geometry.c, never from the renderer's code. */
#ifndef SPINDLE_RTEST_H
#define SPINDLE_RTEST_H

#include <stdbool.h>
#include <stdint.h>

#include "render.h"

/* x as the renderer sees it: scene vertices are floats. */
#define F(x) ((double)(float)(x))

/* The `small` profile (128x128, N = 128 mirrored, h = 1). */
struct geometry rtest_small(void);
/* Not mirrored, odd sizes (edge tiles, W not a multiple of 8), h != 1:
 * 100x72, N = 50, h = 0.75. */
struct geometry rtest_odd(void);

/* A growable vertex list. */
struct rtest_mesh {
	float *xyz;
	uint32_t count; /* vertices */
	uint32_t cap;
};

void rtest_mesh_add(struct rtest_mesh *m, double x, double y, double z);
void rtest_mesh_free(struct rtest_mesh *m);
/* Triangles of a UV sphere at the origin: slices around, stacks pole to pole. */
void rtest_sphere(struct rtest_mesh *m, double r, int slices, int stacks);
/* Triangle fan of a horizontal disk of radius r at height y, centre on the axis. */
void rtest_disk(struct rtest_mesh *m, double r, double y, int segments);
/* Two triangles of the rectangle |x| <= a, |y| <= b in the plane z = 0. */
void rtest_wall(struct rtest_mesh *m, double a, double b);

/* Points at, next to and beyond (clamped) the edges and corners of the
 * image, and beside the axis: each on the plane of its own image angle
 * 2 pi j / N (j < N/2), at the centre of the pixel it aims at, so that no
 * two lie in one volume image and none lies on a column, row or image
 * boundary; and one on the axis (image 0, column W/2, row 5). Returns how
 * many were added. */
uint32_t rtest_edge_points(const struct geometry *g, struct rtest_mesh *m);

/* The voxels of point p in its two images, lobe s >= 0 then s < 0
 * (docs/design.md section 3: image round(phi / D) mod N, folded onto the volume's
 * images when mirrored; column of s = p . d_k in volume image k, row of y),
 * computed from the formulas, not with common/geometry.c. On a mirrored
 * device the two are usually the same voxel. */
struct rtest_voxel {
	uint32_t k, u, v;
};
void rtest_point_voxels(const struct geometry *g, const float p[3], struct rtest_voxel out[2]);

/* xorshift64: the next of *state's numbers, uniform in [0, 1), the same
 * on every machine; and one in [a, b). */
double rtest_rnd(uint64_t *state);
double rtest_range(uint64_t *state, double a, double b);

/* Colour i of a fixed spread of values, dark and bright; and the seven
 * saturated colours (channels 0 or 255), one channel pattern each. */
void rtest_colour(uint32_t i, uint8_t out[3]);
void rtest_saturated(uint32_t i, uint8_t out[3]);

/* A draw of m with the identity transform. */
struct scene_draw rtest_draw(enum scene_prim prim, const struct rtest_mesh *m, uint8_t r, uint8_t g, uint8_t b);
void rtest_identity(float t[16]);
/* Inverse of the affine column-major m into inv (column-major), by
 * Gauss-Jordan elimination with partial pivoting on the 4x4: independent
 * of the renderers' own inversion. Aborts when m is singular. */
void rtest_invert(const float m[16], double inv[16]);
/* Whether GL renderer backend ("egl", "osmesa") can be made at g: false
 * (a skip, said on stdout) only when the build has no OSMesa; any other
 * failure ends the test (exit 1). */
bool rtest_have_gl(const struct geometry *g, const char *backend);

/* Renders draws with a fresh CPU renderer; aborts on failure. */
struct volume *rtest_render(const struct geometry *g, const struct scene_draw *draws, uint32_t n, unsigned threads);

/* Pixel (u, v) of channel c of image k, and whether any channel is lit. */
bool rtest_lit(const struct volume *vol, uint32_t k, uint32_t u, uint32_t v, int c);
/* Lit pixels of channel c in image k, or in the whole volume. */
uint64_t rtest_count_image(const struct volume *vol, uint32_t k, int c);
uint64_t rtest_count(const struct volume *vol, int c);
/* Whether two volumes hold the same masks, tile bytes and next_tile. */
bool rtest_same(const struct volume *a, const struct volume *b);

/* Whether every pixel past W or H in edge tiles is 0 (volume.h's rule). */
bool rtest_padding_clear(const struct volume *vol);

/* Left and right edge (in s) of column u, top and bottom (in y) of row v. */
double rtest_col_s0(const struct geometry *g, uint32_t u);
double rtest_col_s1(const struct geometry *g, uint32_t u);
double rtest_row_y0(const struct geometry *g, uint32_t v);
double rtest_row_y1(const struct geometry *g, uint32_t v);
/* Height at the middle of row v. */
double rtest_row_mid(const struct geometry *g, uint32_t v);

#endif
