/* spindle-gl: display lists, recorded as they are compiled (each GL call
 * the list holds, as an op or as geometry in a segment) and replayed by
 * glCallList against the context's state, which puts every segment drawn
 * into the frame as a call: a reference, not a copy. */
#ifndef SPINDLE_GL_LIST_H
#define SPINDLE_GL_LIST_H

#include "state.h"

/* glNewList / glEndList. */
void sgl_rec_begin(struct sgl_ctx *c, GLuint name, GLenum mode);
void sgl_rec_end(struct sgl_ctx *c);
/* Drops a list being compiled (the context goes). */
void sgl_rec_abandon(struct sgl_ctx *c);
/* The segment that geometry compiled now goes to (opened if none is). */
struct sgl_seg *sgl_rec_segment(struct sgl_rec *r);
/* Whether a vertex compiled now has its colour from the list (else it
 * inherits the caller's). */
bool sgl_rec_colour_known(const struct sgl_rec *r);
/* Compiled matrix calls: SGL_OP_MULT, _LOAD (m), _PUSH, _POP, _MODE (mode). */
void sgl_rec_matrix(struct sgl_rec *r, enum sgl_op_kind kind, const float *m, GLenum mode);
/* Compiled colour state: SGL_OP_COLOR, _MATERIAL (v), _ENABLE (a cap,
 * b on), _SHADE (a flat), _COLOR_MATERIAL (a mode). */
void sgl_rec_state(struct sgl_rec *r, enum sgl_op_kind kind, uint32_t a, uint32_t b, const float *v);
/* Compiled glCallList (add_base: glCallLists, offset by the base at
 * execution) and glListBase. */
void sgl_rec_call(struct sgl_rec *r, GLuint name, bool add_base);
void sgl_rec_base(struct sgl_rec *r, GLuint base);

/* glCallList: replays the list (depth: nesting, up to SGL_CALL_DEPTH). */
void sgl_list_call(struct sgl_ctx *c, GLuint name, int depth);
void sgl_lists_delete(struct sgl_ctx *c, GLuint first, GLsizei range);

#endif
