/* Building a draw's vertex data from a client's buffers: vertex formats,
 * indices, line strips and per-vertex colour. The result is what the
 * renderers take (scene.h): plain points, segments or triangles, with one
 * colour per primitive when the vertices carry colours. Everything is
 * copied out of the client's memory once, and checked on the copy, so
 * nothing the client writes later can change it. */
#ifndef SPINDLE_DRAW_H
#define SPINDLE_DRAW_H

#include <stdbool.h>
#include <stdint.h>

#include "scene.h"

/* A volume's samples in the renderers' layout (scene.h, scene_grid),
 * counted: the volume object holds a reference and each draw of it one
 * (through its vdata). gone: the object was destroyed; its draws show
 * nothing from the next scene on. Main thread only. */
struct vgrid {
	unsigned refs;
	bool gone;
	uint64_t id;    /* scene_draw.grid_id: given by the first snapshot that draws it */
	uint64_t bytes; /* of samples and brick maxima, counted against the budgets */
	struct scene_grid grid;
	void *samples;    /* grid.data */
	float *brick_max; /* grid.brick_max */
};

struct vgrid *vgrid_ref(struct vgrid *g);
void vgrid_unref(struct vgrid *g);

/* Vertex data of one draw; shared by the pending and committed states
 * and by scene snapshots, hence counted. Main thread only. A grid draw
 * (prim SCENE_GRID) has no vertices: its grid, holding a reference, and
 * its transfer function, whose lookup table (if any) it owns. */
struct vdata {
	unsigned refs;
	uint64_t id; /* scene_draw.data_id: 0 until first drawn (snapshot.c) */
	enum scene_prim prim;
	uint32_t count;    /* vertices in xyz */
	uint32_t prims;    /* primitives they make */
	uint8_t *prim_rgb; /* NULL, or 3 bytes per primitive (alpha applied) */
	struct vgrid *grid;
	struct scene_transfer transfer;
	/* The vertices' bounding box, when every coordinate is finite
	 * (bounded): where a lifted render may be shifted (snapshot.c). */
	bool bounded;
	float lo[3], hi[3];
	float xyz[];
};

struct vdata *vdata_ref(struct vdata *v);
void vdata_unref(struct vdata *v);

/* Vertex layouts: the protocol's list.vertex_format values. */
enum draw_format {
	DRAW_XYZ = 0,
	DRAW_XYZ_RGBA8 = 1,
	DRAW_XYZ_RGBA_FLOAT = 2,
};

/* Draw modes: the protocol's list.mode values. */
enum draw_mode {
	DRAW_POINTS = 0,
	DRAW_LINES = 1,
	DRAW_TRIANGLES = 2,
	DRAW_LINE_STRIP = 3,
};

/* Bytes of one vertex of a format (0: unknown format). */
uint32_t draw_format_size(uint32_t format);

/* Where a draw reads: vertex i at base + i * stride (i < vertex_count),
 * and, when index is not NULL, the index_count indices there, of
 * index_size bytes (2 or 4), picking the vertices in order. The caller
 * has checked that every byte named lies inside its buffer. */
struct draw_source {
	enum draw_mode mode;
	enum draw_format format;
	const uint8_t *base;
	uint32_t stride;
	uint32_t vertex_count;
	const uint8_t *index;
	uint32_t index_count;
	uint32_t index_size;
};

/* Why a draw was refused. */
enum draw_error {
	DRAW_OK = 0,
	DRAW_BAD_COUNT, /* the vertices do not make whole primitives */
	DRAW_BAD_INDEX, /* an index at or past vertex_count */
	DRAW_TOO_MANY,  /* more vertices than max_vertices */
	DRAW_NO_MEMORY,
};

/* Builds the vertex data of a draw, at most max_vertices vertices after
 * expansion (strips to segments, colour subdivision). On DRAW_BAD_INDEX,
 * *bad_index gets the position of the first bad index. *out is NULL for a
 * draw of no primitives. */
enum draw_error draw_build(const struct draw_source *src, uint64_t max_vertices, struct vdata **out,
			   uint32_t *bad_index);

#endif
