/* spindle-gl: recorded geometry. The primitive assembler turns what
 * glBegin/glEnd and the array draws give, in any mode, into points, line
 * segments and triangles of SPINDLE_XYZ_RGBA8 vertices: strips, loops,
 * fans, quads, quad strips and polygons are split here. */
#ifndef SPINDLE_GL_GEOM_H
#define SPINDLE_GL_GEOM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* The most vertices one geometry holds (per frame, or per display list
 * segment); what comes after is dropped. */
#define SGL_GEOM_MAX (4u << 20)

/* SPINDLE_XYZ_RGBA8. */
struct sgl_vertex {
	float xyz[3];
	uint8_t rgba[4];
};

enum sgl_kind { SGL_POINTS, SGL_LINES, SGL_TRIS, SGL_KINDS };

struct sgl_geom {
	struct sgl_vertex *v[SGL_KINDS];
	uint32_t n[SGL_KINDS], cap[SGL_KINDS];
	float lo[3], hi[3]; /* bounds; lo > hi when empty */
	bool overflow;      /* something was dropped over SGL_GEOM_MAX */
};

void sgl_geom_init(struct sgl_geom *g);
/* Empties it, keeping the memory. */
void sgl_geom_reset(struct sgl_geom *g);
void sgl_geom_free(struct sgl_geom *g);
uint32_t sgl_geom_count(const struct sgl_geom *g);
bool sgl_geom_empty(const struct sgl_geom *g);
/* Adds one primitive of kind k (1, 2 or 3 vertices). */
void sgl_geom_add(struct sgl_geom *g, enum sgl_kind k, const struct sgl_vertex *v);
/* Every primitive of src, each vertex through m (column-major 4x4, with
 * the divide by w; primitives with a vertex at w <= 0 are dropped). rgba:
 * replaces the colour of every vertex when not NULL. */
void sgl_geom_append(struct sgl_geom *dst, const struct sgl_geom *src, const float m[16], const uint8_t *rgba);
bool sgl_geom_equal(const struct sgl_geom *a, const struct sgl_geom *b);
/* Deep copy into dst (its memory reused). */
void sgl_geom_copy(struct sgl_geom *dst, const struct sgl_geom *src);

/* A vertex as the assembler gets it: homogeneous position, colour, and
 * whether its colour is inherited (a display list drawing before it set
 * any colour takes the caller's). */
struct sgl_avertex {
	float pos[4];
	uint8_t rgba[4];
	bool inherit;
};

struct sgl_asm {
	unsigned mode; /* GL_POINTS .. GL_POLYGON */
	uint32_t count;
	bool flat;
	struct sgl_avertex first, prev[3];
	struct sgl_geom *own, *inherit; /* inherit NULL: all go to own */
};

/* Starts a primitive sequence of a glBegin mode (false: not a mode). */
bool sgl_asm_begin(struct sgl_asm *a, unsigned mode, bool flat, struct sgl_geom *own, struct sgl_geom *inherit);
void sgl_asm_vertex(struct sgl_asm *a, const struct sgl_avertex *v);
/* Closes a line loop. */
void sgl_asm_end(struct sgl_asm *a);

#endif
