/* spindle-gl: the state the layer keeps beside the real GL's. Each GL
 * context has a struct sgl_ctx (its matrix stacks, current colour and
 * material, client arrays, the display list being compiled and the frame
 * being recorded); contexts sharing objects share a struct sgl_ns (the
 * display lists and buffer objects). A recorded display list is a
 * sequence of ops replayed by glCallList: matrix and colour changes, calls
 * of other lists, and segments, its geometry in runs drawn under one
 * matrix, each shown by reference as one retained Spindle list. */
#ifndef SPINDLE_GL_STATE_H
#define SPINDLE_GL_STATE_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "geom.h"
#include "glapi.h"
#include "names.h"

#define SGL_STACK_DEPTH 32  /* modelview and projection stacks, as Mesa's */
#define SGL_ATTRIB_DEPTH 16 /* glPushAttrib */
#define SGL_CALL_DEPTH 64   /* nested glCallList, GL_MAX_LIST_NESTING */
#define SGL_VARIANTS 4      /* Spindle lists per segment, one per inherited colour */

/* The state that decides a vertex's colour on the display: the current
 * colour, or with lighting on the front material's diffuse colour (which
 * GL_COLOR_MATERIAL makes follow the current colour). */
struct sgl_colour {
	float colour[4];
	float diffuse[4];
	bool lighting, color_material, flat;
	GLenum cm_mode; /* glColorMaterial's mode */
};

/* What the output keeps of a segment on the daemon (under its lock). */
struct sgl_seg_out {
	uint64_t gen; /* connection the lists belong to */
	struct sgl_variant {
		struct spindle_list *list;
		uint64_t serial; /* unique over the process, 0: none */
		uint32_t rgba;   /* the inherited colour it was made with */
		uint32_t vertices;
		uint64_t used;
	} var[SGL_VARIANTS];
};

/* A run of a list's geometry in the coordinates of the modelview at its
 * start: vertices with their own colour, and ones drawn before the list
 * set any (they take the caller's colour at each call). */
struct sgl_seg {
	uint32_t index;
	struct sgl_geom own, inherit;
	float centre[3], radius; /* a sphere around both (at glEndList) */
	struct sgl_seg_out out;
};

enum sgl_op_kind {
	SGL_OP_SEG,            /* a: segment index: drawn with the modelview here */
	SGL_OP_MULT,           /* m: multiply the current matrix */
	SGL_OP_LOAD,           /* m: load the current matrix */
	SGL_OP_PUSH,           /* glPushMatrix */
	SGL_OP_POP,            /* glPopMatrix */
	SGL_OP_MODE,           /* a: glMatrixMode */
	SGL_OP_CALL,           /* a: list name, b: 1 to add the list base */
	SGL_OP_BASE,           /* a: glListBase */
	SGL_OP_COLOR,          /* m[0..3]: glColor */
	SGL_OP_MATERIAL,       /* m[0..3]: front diffuse */
	SGL_OP_ENABLE,         /* a: GL_LIGHTING or GL_COLOR_MATERIAL, b: on */
	SGL_OP_SHADE,          /* a: flat */
	SGL_OP_COLOR_MATERIAL, /* a: glColorMaterial mode */
};

struct sgl_op {
	enum sgl_op_kind kind;
	uint32_t a, b;
	float m[16];
};

struct sgl_list {
	int refs; /* atomic: the namespace, and frames calling it */
	uint32_t name;
	struct sgl_op *ops;
	uint32_t n_ops, cap_ops;
	struct sgl_seg **segs;
	uint32_t n_segs, cap_segs;
};

/* A buffer object's contents, shadowed for client arrays in it. */
struct sgl_buffer {
	uint8_t *data;
	size_t size;
	void *mapped; /* while mapped: the pointer and range given out */
	size_t map_offset, map_length;
	bool map_writes;
};

/* Display lists and buffer objects of one share group. */
struct sgl_ns {
	pthread_mutex_t lock;
	int refs; /* contexts, under the registry lock */
	struct sgl_names lists, buffers;
};

struct sgl_array {
	bool enabled;
	GLint size;
	GLenum type;
	GLsizei stride;
	const void *pointer;
	GLuint buffer; /* bound GL_ARRAY_BUFFER at glXxxPointer: pointer is an offset */
};

/* A display list segment drawn in this frame: s the stage matrix
 * (eye space, or clip space in frustum mode) it was called with. */
struct sgl_call {
	struct sgl_list *list; /* a reference */
	struct sgl_seg *seg;
	float s[16];
	uint8_t rgba[4]; /* the colour its inherited vertices take */
};

struct sgl_frame {
	struct sgl_call *calls;
	uint32_t n_calls, cap_calls;
	struct sgl_geom imm; /* immediate geometry, stage space */
};

/* The display list being compiled. */
struct sgl_rec {
	struct sgl_list *list;
	GLenum mode;                  /* GL_COMPILE or GL_COMPILE_AND_EXECUTE */
	struct sgl_seg *seg;          /* NULL between segments */
	uint32_t anchor;              /* where the next segment starts, in ops */
	float l[SGL_STACK_DEPTH][16]; /* modelview relative to the anchor */
	int top;
	GLenum matrix_mode;
	struct sgl_colour cs;
	bool color_set, material_set; /* set in this list since its start or the last call */
};

struct sgl_attrib {
	GLbitfield mask;
	GLenum matrix_mode;
	struct sgl_colour cs;
};

/* The fitted mapping of fit mode: the box (centre c, half extents e) the
 * display volume shows, and the scale s that puts it in the cylinder. */
struct sgl_fit {
	bool valid;
	float c[3], e[3], s;
	uint32_t refits;
};

struct sgl_out;

struct sgl_ctx {
	uint32_t id;
	void *handle; /* GLXContext or EGLContext; NULL: the default context */
	struct sgl_ns *ns;
	GLenum matrix_mode;
	float mv[SGL_STACK_DEPTH][16], proj[SGL_STACK_DEPTH][16];
	int mv_top, proj_top;
	struct sgl_colour cs;
	struct sgl_array vertex, color;
	GLuint array_buffer, element_buffer;
	GLuint list_base;
	GLuint program;
	GLenum render_mode;
	bool in_begin;
	struct sgl_asm as;
	float begin_s[16];
	struct sgl_rec *rec;
	struct sgl_frame frame;
	struct sgl_attrib attribs[SGL_ATTRIB_DEPTH];
	int attrib_top;
	struct sgl_fit fit;
	bool swapped; /* has ended a frame with a swap: glFlush does not */
	bool destroyed;
	int current; /* threads it is current on (registry lock) */
	struct sgl_out *out;
	struct sgl_ctx *next;
};

#endif
