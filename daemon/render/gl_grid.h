/* Grids (scene.h, SCENE_GRID) on the GL renderers (gl_grid.c): each grid
 * a 3-D texture kept from render to render while it is drawn, and per
 * image and grid draw a quad whose fragment shader samples the grid where
 * the image's plane crosses it (gl_shaders.h, gl_grid_fs), as grid.c does
 * on the CPU. On the state of render_gl_priv.h, with the context current.
 * Private to daemon/render/. */
#ifndef SPINDLE_GL_GRID_H
#define SPINDLE_GL_GRID_H

#include <stdbool.h>
#include <stdint.h>

struct render_gl;
struct scene;

/* Looks up the grid program's uniforms (r->grid, built by render_gl.c),
 * makes its vertex array and reads GL_MAX_3D_TEXTURE_SIZE. 0 or -EIO. */
int gl_grid_create(struct render_gl *r);
/* The grid draws of scene, prepared for gl_grid_draw(): the textures of
 * grids it does not draw are deleted (after GL_GRID_KEEP renders for a
 * grid with an id, sooner to make room), those of new grids made and
 * uploaded, the draws' lookup tables uploaded. 0; -EFBIG: a grid larger
 * than GL_MAX_3D_TEXTURE_SIZE or grids beyond the budget (GL_GRID_BUDGET,
 * render_gl_options.max_grid_bytes), or no memory for a texture: this
 * volume renders on the CPU; -ENOMEM. */
int gl_grid_prepare(struct render_gl *r, const struct scene *scene);
/* Marks, in the tile marks (render_gl.touched), every row of every tile
 * that the prepared grid draws may light in volume images first .. first
 * + n - 1 (batch slots 0 .. n - 1): uploaded before the batch is drawn,
 * in place of a mark by each fragment (an atomic, which costs llvmpipe
 * more than the sampling). 0 or -ENOMEM. */
int gl_grid_mark(struct render_gl *r, uint32_t first, uint32_t n);
/* Draws the prepared grid draws into image k at batch slot `slot` (tile:
 * the u_tile uniform, gl_shaders.h). Leaves r->vao bound and texture
 * unit 0 active. */
void gl_grid_draw(struct render_gl *r, uint32_t k, uint32_t slot, const uint32_t tile[4]);
/* Deletes every grid texture (with the GL objects of gl_grid_create()
 * too when all). */
void gl_grid_release(struct render_gl *r, bool all);
/* Frees the CPU side (the context may be gone). */
void gl_grid_free(struct render_gl *r);

#endif
