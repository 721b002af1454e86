/* Model files (STL, OBJ, PLY and whatever else libassimp reads) turned into
 * flat primitive arrays ready for spindle buffers, and fitted to the display.
 *
 * Coordinates are the file's own, with every node transform of the file's
 * scene graph applied. Polygons are triangulated; OBJ `l` elements become
 * line segments (a polyline of n vertices gives n-1 segments); point clouds
 * (a PLY with vertices only) and point primitives become points.
 *
 * A model file is untrusted input: model_load() parses it in a short-lived
 * child process without privileges (model_sandbox.c: nobody when started
 * as root, no_new_privs, memory and CPU limits, a seccomp filter that
 * allows reading the open file and writing the result, little else) and
 * checks what comes back again before using it: counts, indices, finite
 * coordinates. A loader that crashes, hangs or breaks the rules is an
 * error naming the file, never a crash of the caller. */
#ifndef SPINDLE_TOOLS_MODEL_H
#define SPINDLE_TOOLS_MODEL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* Colours: when the file gives any vertex a colour other than opaque white
 * (per-vertex colours: PLY red/green/blue[/alpha], assimp's first colour
 * set; else the diffuse colour of a mesh's material, assimp's default
 * material counting as white), the three colour arrays hold R, G, B, A for
 * every vertex of the matching primitive array; otherwise all three are
 * NULL. */
struct model {
	float *triangles; /* 9 floats (3 vertices x, y, z) per triangle */
	size_t triangle_count;
	float *lines; /* 6 floats (2 vertices) per segment */
	size_t line_count;
	float *points; /* 3 floats per point */
	size_t point_count;
	uint8_t *triangle_colors; /* NULL, or 12 bytes (3 x RGBA) per triangle */
	uint8_t *line_colors;     /* NULL, or 8 bytes per segment */
	uint8_t *point_colors;    /* NULL, or 4 bytes per point */
};

/* Uniform scale about a centre: v' = (v - centre) * scale. */
struct model_fit {
	float centre[3];
	float scale;
};

/* Loads a model file in the sandboxed loader. Returns a model owned by the
 * caller (free it with model_destroy()), or NULL with errno set: ENOENT
 * (and the other errors of open(2)), ENOMEM, EINVAL for a file that can't
 * be read as a model (assimp refuses it, a vertex is NaN or infinite, the
 * loader crashed, timed out or sent a malformed result), E2BIG for a model
 * over the limits of model_wire.h, ENODATA for a file with no primitives,
 * EPERM when the loader could not give up its privileges. When err is not
 * NULL it receives a one-line reason on failure naming the file
 * ("FILE: the model loader crashed (signal 11)"; NUL-terminated, cut to
 * err_size bytes). */
struct model *model_load(const char *path, char *err, size_t err_size);
/* Where model_load() says that a load taking over a second goes on (a line
 * every 2 s, and the time it took), or NULL: silent (the default). */
void model_set_progress(FILE *f);

/* Accepts NULL. */
void model_destroy(struct model *m);

/* Total vertices of all primitives. */
size_t model_vertex_count(const struct model *m);

/* Axis-aligned bounds of every vertex. 0, or -ENODATA for an empty model. */
int model_bounds(const struct model *m, float min[3], float max[3]);

/* The fit that puts the model's bounding-box centre at the origin and scales
 * it uniformly so it fills margin (0 < margin <= 1, e.g. 0.95) of the display
 * volume x^2 + z^2 <= 1, |y| <= half_height: the farthest vertex from the
 * axis ends at radius <= margin, the highest/lowest at |y| <= margin * h.
 * A model that is a single point gets scale 1. 0, -EINVAL for a bad
 * margin or half_height, or -ENODATA for an empty model. */
int model_compute_fit(const struct model *m, float half_height, float margin, struct model_fit *out);

/* Applies a fit to every vertex in place. */
void model_apply_fit(struct model *m, const struct model_fit *fit);

/* Puts each primitive array (and its colours) in spatial order: sorted by
 * the Morton code of each primitive's centroid over the array's bounding
 * box (model_morton_code()), equal codes in file order. A volume shows the
 * same whatever the order (overlaps combine by MAX), but neighbours in
 * space then sit together in memory, which the renderers' binning and
 * sectioning read faster than a file's order (docs/performance.md, "Vertex
 * order"). 0, or -ENOMEM (-E2BIG for an array of 2^32 primitives or
 * more) with the model as it was. */
int model_order_spatial(struct model *m);

/* The centroid of a primitive of verts (1 .. 3) vertices at v (x, y, z
 * each), summed in double: what model_order_spatial() sorts by. */
void model_centroid(const float *v, unsigned verts, float out[3]);

/* The Morton code (x in bit 0, y in bit 1, z in bit 2, and so on) of point
 * c on a grid of 1024 cells a side spanning lo .. hi (a flat axis: cell 0;
 * outside: the nearest cell): 30 bits. */
uint32_t model_morton_code(const float c[3], const float lo[3], const float hi[3]);

#endif
