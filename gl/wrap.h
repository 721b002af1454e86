/* spindle-gl: what the entry points share: the vertex path (glBegin,
 * glVertex, glEnd, and the array draws through them) and the reports of
 * what is not covered. */
#ifndef SPINDLE_GL_WRAP_H
#define SPINDLE_GL_WRAP_H

#include "state.h"

void sgl_begin(struct sgl_ctx *c, GLenum mode);
void sgl_vertex(struct sgl_ctx *c, float x, float y, float z, float w);
void sgl_end(struct sgl_ctx *c);
/* glColor and glMaterial's diffuse: compiled or done. */
void sgl_color(struct sgl_ctx *c, const float rgba[4]);

/* Reports once that something is passed through but not shown. */
void sgl_uncovered(const char *what);

#endif
