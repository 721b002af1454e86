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
 * not draw turns (yet); a scene without turns is unaffected.
 *
 * Grids (SCENE_GRID) are drawn from 3-D textures kept while their grids
 * are drawn (gl_grid.h), known by scene_draw.grid_id, or where that is 0
 * by the grid's address, its data's, its type and size: a caller giving
 * no ids must not free a grid and make another of the same type and size
 * at the same addresses between two renders that draw them. A volume
 * whose grids need more than opts->max_grid_bytes (0: 1 GiB) of textures,
 * or more than GL_MAX_3D_TEXTURE_SIZE samples a side, renders on the CPU
 * (or fails with -EFBIG under no_fallback). */
struct renderer *render_gl_create(const struct geometry *geom, const struct render_gl_options *opts);
/* GL_RENDERER and GL_VERSION of a GL renderer's context ("" otherwise). */
const char *render_gl_describe(const struct renderer *r);

#endif
