/* spindle-gl: the frame being recorded, its end (glXSwapBuffers,
 * eglSwapBuffers; glFlush and glFinish in a context that never swapped),
 * and the mapping from the program's view to the display volume
 * (docs/opengl.md): fit, frustum or fixed. */
#ifndef SPINDLE_GL_FRAME_H
#define SPINDLE_GL_FRAME_H

#include "state.h"

/* Puts a display list segment into the frame, drawn with the current
 * stage matrix and colour. */
void sgl_frame_add_call(struct sgl_ctx *c, struct sgl_list *l, struct sgl_seg *seg);
/* Ends the frame: shows it if it can, and starts the next. */
void sgl_frame_end(struct sgl_ctx *c, const char *why);
/* Empties the frame (dropping its references). */
void sgl_frame_clear(struct sgl_frame *f);

/* The stage-to-volume mapping for a frame whose stage bounds are lo..hi
 * (lo > hi: empty), h the display's half height; updates the fit. */
void sgl_frame_mapping(struct sgl_fit *fit, const float lo[3], const float hi[3], float h, float map[16]);

#endif
