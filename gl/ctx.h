/* spindle-gl: contexts (which is current on this thread), share groups,
 * and the state operations that both the wrappers and the replay of a
 * display list perform: matrices and colour. */
#ifndef SPINDLE_GL_CTX_H
#define SPINDLE_GL_CTX_H

#include "state.h"

/* The context current on this thread; with none known (a program that
 * made it current in a way the layer does not see), a default one. */
struct sgl_ctx *sgl_ctx_current(void);
/* A context the program created (share: the context it shares objects
 * with, or NULL). */
void sgl_ctx_created(void *handle, void *share);
void sgl_ctx_destroyed(void *handle);
/* handle current on this thread (NULL: none). */
void sgl_ctx_make_current(void *handle);

/* The matrix that takes object coordinates to the stage: eye space, or
 * in frustum mode clip space. */
void sgl_ctx_stage_matrix(struct sgl_ctx *c, float out[16]);
/* The top of the current matrix mode's stack, or NULL (texture, colour). */
float *sgl_ctx_matrix(struct sgl_ctx *c);
void sgl_ctx_mult(struct sgl_ctx *c, const float m[16]);
void sgl_ctx_load(struct sgl_ctx *c, const float m[16]);
void sgl_ctx_push(struct sgl_ctx *c);
void sgl_ctx_pop(struct sgl_ctx *c);
/* One matrix-stack operation (mult, load, push, pop: on the current
 * matrix mode's stack; mode: sets it), done now or replayed from a list;
 * false for any other kind. */
bool sgl_ctx_matrix_op(struct sgl_ctx *c, enum sgl_op_kind kind, const float *m, unsigned mode);
/* Whether geometry drawn now is recorded for the frame (GL_RENDER mode,
 * no shader program). */
bool sgl_ctx_drawing(struct sgl_ctx *c);

void sgl_colour_init(struct sgl_colour *cs);
/* The colour a vertex takes on the display. */
void sgl_colour_rgba(const struct sgl_colour *cs, uint8_t out[4]);
void sgl_colour_set(struct sgl_colour *cs, const float rgba[4]);
void sgl_colour_enable(struct sgl_colour *cs, GLenum cap, bool on);

struct sgl_list *sgl_ns_list(struct sgl_ns *ns, GLuint name); /* a reference, or NULL */
void sgl_list_unref(struct sgl_list *l);

#endif
