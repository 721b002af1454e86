/* A headless GL context for the GL renderers: OpenGL ES 3.1+ on an EGL
 * device or surfaceless display, or desktop OpenGL 4.3+ core on OSMesa
 * (where shaders are written in GLSL ES 3.10 through
 * ARB_ES3_1_compatibility, so both run the same source). Rendering goes to
 * framebuffer objects only: no window system, no default framebuffer. */
#ifndef SPINDLE_GL_CONTEXT_H
#define SPINDLE_GL_CONTEXT_H

#include <stdbool.h>

#include "gl_api.h"

enum gl_backend {
	GL_BACKEND_EGL,
	GL_BACKEND_OSMESA,
};

struct gl_context {
	enum gl_backend backend;
	struct gl_api gl;
	char renderer[128]; /* GL_RENDERER */
	char version[128];  /* GL_VERSION */
	bool hardware;      /* not a software rasterizer (llvmpipe, softpipe, swrast) */
	bool robust;        /* reset notification was granted: GetGraphicsResetStatus means something */
	struct gl_context_priv *priv;
};

/* Test hook: SPINDLE_GL_FAULT=display makes context creation fail as if
 * there were no EGL display (or no OSMesa), "shader" breaks every shader's
 * source, "lost" reports a context reset after the first volume. */
enum gl_fault {
	GL_FAULT_NONE,
	GL_FAULT_DISPLAY,
	GL_FAULT_SHADER,
	GL_FAULT_LOST,
};
enum gl_fault gl_fault_from_env(void);

/* Creates a context and makes it current on the calling thread. Returns 0
 * or a negative errno (-ENODEV: no display/device; -ENOTSUP: no context of
 * a version with compute shaders; -ENOENT: backend not built), with a log
 * line saying why. */
int gl_context_create(struct gl_context *c, enum gl_backend backend);
/* Makes c current on the calling thread / releases it from it. 0 or -EIO. */
int gl_context_bind(struct gl_context *c);
void gl_context_unbind(struct gl_context *c);
/* Releases and destroys; accepts a context whose creation failed. */
void gl_context_destroy(struct gl_context *c);

/* Compiles src (with "#error" appended when broken, the injected fault),
 * or links shaders (any 0 fails) into a program and deletes the shaders.
 * 0 on failure, with the info log in a warning naming what. */
GLuint gl_shader_compile(const struct gl_api *gl, GLenum type, const char *src, const char *what, bool broken);
GLuint gl_program_link(const struct gl_api *gl, const GLuint *shaders, int n, const char *what);

/* "egl", "osmesa" */
const char *gl_backend_name(enum gl_backend b);

#endif
