/* The GL renderer's input (gl_upload.c): the binned primitives staged in
 * the primitive texture's layout (gl_shaders.h) and uploaded with the
 * points, and the textures the renderer makes. On the state of
 * render_gl_priv.h. Private to daemon/render/. */
#ifndef SPINDLE_GL_UPLOAD_H
#define SPINDLE_GL_UPLOAD_H

#include <stdint.h>

#include "gl_api.h"

struct render_gl;

/* A w x h texture of format fmt, nearest filtering, bound. */
GLuint gl_make_texture(const struct gl_api *gl, GLenum fmt, uint32_t w, uint32_t h);
/* Uploads the binned primitives (r->bins) and points, unless the bins were
 * kept and are there already (r->uploaded). 0, -E2BIG (more primitives
 * than the texture holds, or than max_prims) or -ENOMEM. */
int gl_upload(struct render_gl *r);

#endif
