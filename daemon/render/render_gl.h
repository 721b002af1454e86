/* The GL renderer (render_gl.c, gl_pack.c). */
#ifndef SPINDLE_RENDER_GL_H
#define SPINDLE_RENDER_GL_H

#include "renderer.h"

/* The GL pipeline of docs/design.md section 5 on an EGL (surfaceless or device)
 * or OSMesa context. NULL + errno when there is no usable context or a
 * shader does not build (ENOENT: backend not built in), with a log line
 * saying why. After a failure while rendering (context lost, GL error, a
 * fence that never signals) it logs why and renders on the CPU from then
 * on, unless opts->no_fallback.
 *
 * A scene with any draw whose turn (scene.h) is not 0 is rendered whole by
 * the CPU fallback, even with opts->no_fallback: the volume is the CPU
 * renderer's and stats.engine says RENDER_ENGINE_CPU. The GL pipeline does
 * not draw turns (yet); a scene without turns is unaffected. */
struct renderer *render_gl_create(const struct geometry *geom, const struct render_gl_options *opts);
/* GL_RENDERER and GL_VERSION of a GL renderer's context ("" otherwise). */
const char *render_gl_describe(const struct renderer *r);

#endif
