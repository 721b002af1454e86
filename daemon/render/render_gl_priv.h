/* The GL renderer's state, shared by render_gl.c (set-up, upload, drawing,
 * the render) and gl_pack.c (gl_pack.h: the GPU halftone + pack pass and
 * reading its output back). Private to daemon/render/. */
#ifndef SPINDLE_RENDER_GL_PRIV_H
#define SPINDLE_RENDER_GL_PRIV_H

#include <stdbool.h>
#include <stdint.h>

#include "bin.h"
#include "brightness.h"
#include "gl_context.h"
#include "renderer.h"

_Static_assert(sizeof(struct bin_prim) == 11 * 4, "bin_prim is 9 vertex words and 2 more");
_Static_assert(sizeof(struct bin_point) == 2 * 4, "the point attribute is two words");

/* Desktop OpenGL only (OSMesa): there a vertex shader's gl_PointSize counts
 * only while GL_PROGRAM_POINT_SIZE is enabled, and the point size range is
 * GL_POINT_SIZE_RANGE; OpenGL ES always takes gl_PointSize and names the
 * range GL_ALIASED_POINT_SIZE_RANGE. */
#ifndef GL_PROGRAM_POINT_SIZE
#define GL_PROGRAM_POINT_SIZE 0x8642
#endif
#ifndef GL_POINT_SIZE_RANGE
#define GL_POINT_SIZE_RANGE 0x0B12
#endif

#define GL_MAX_BATCH 16
#define GL_PRIM_TEXELS 3 /* RGBA32UI texels per primitive (gl_shaders.h) */
/* u_frame.w of the section program: which of a primitive's 16 vertex
 * slots a draw covers (gl_shaders.h). */
#define GL_SECTION_SLOTS 0.0f /* 0-3: sections, 4 vertices a primitive */
#define GL_EDGE_SLOTS 1.0f    /* 4-15: triangle edges, 12 a primitive */
/* Half thickness of the slab the fragment shader accepts on the axis, in
 * pixels: the b of t^2 <= (s tau)^2 + b^2. */
#define GL_AXIS_BIAS_PX 0.25
/* The same where the brightness model thins (render_gl.bright_on): none.
 * Sections and edges keep the axis connected without it, and the bias lit
 * a surface at a small angle to the slice plane out to about b / tan a
 * from the axis in several neighbouring images (docs/rendering.md), light
 * the CPU renderer does not give and the models do not weight away (a
 * wall through the axis: 2 to 6 times the CPU's light 1 to 8 px from the
 * axis at the small profile). */
#define GL_BRIGHT_AXIS_BIAS_PX 0.0
/* Jitter of the sample grid, at most this many pixels either way. */
#define GL_JITTER_PX 0.25
#define GL_FENCE_TIMEOUT_NS 5000000000ull

enum { UNI_IMAGE, UNI_SLICE, UNI_EYE, UNI_FRAME, UNI_PRIMS, UNI_TILE, UNI_COUNT };

/* Texture unit of the brightness rates (u_bright, gl_shaders.h) for the
 * fragment shaders: units 0 and 1 hold the primitives and, in the pack
 * pass, the atlas. */
#define GL_BRIGHT_UNIT 2
/* Rows of the brightness tables' texture: rate[u] and line_rate[u] (float
 * bits). */
#define GL_BRIGHT_ROWS 2

struct gl_program {
	GLuint id;
	GLint uni[UNI_COUNT];
};

/* One batch's output on the GPU, and what the CPU needs to collect it. */
struct gl_batch {
	GLuint tiles, ids; /* shader storage: packed tiles; count + tile ids */
	GLsync fence;      /* NULL when nothing is pending */
	uint32_t first, n; /* volume images first .. first + n - 1 */
};

/* Texture units of the grid pass (gl_grid.c): a grid's samples and the
 * lookup tables of the volume's grid draws. */
#define GL_GRID_UNIT 3
#define GL_LUT_UNIT 4
#define GL_LUT_WIDTH 64 /* lookup table entries a row of their texture */
/* Bytes of grid textures one volume may need (render_gl_options
 * .max_grid_bytes sets less): a volume whose grids need more, or one
 * larger than GL_MAX_3D_TEXTURE_SIZE, renders on the CPU. */
#define GL_GRID_BUDGET (1ull << 30)
/* Renders a texture of a grid with an id (scene_draw.grid_id) is kept
 * while no render draws it (the object cache renders a scene's objects
 * one by one); one known by its address only is deleted at once. */
#define GL_GRID_KEEP 8

enum {
	GRID_UNI_RECT,
	GRID_UNI_OFF,
	GRID_UNI_DIR,
	GRID_UNI_UP,
	GRID_UNI_N,
	GRID_UNI_TF,
	GRID_UNI_COL,
	GRID_UNI_LUT,
	GRID_UNI_COUNT
};

/* A grid's samples as a 3-D texture, kept from one render to the next
 * while the grid is drawn (gl_grid.c, GL_GRID_KEEP). */
struct gl_grid_tex {
	uint64_t id; /* scene_draw.grid_id; 0: the grid is known by grid, data, type and n */
	const struct scene_grid *grid;
	const void *data;
	uint32_t type, n[3];
	GLuint tex;
	uint64_t bytes;
	uint64_t last; /* the render that last drew it (render_gl.grid_renders) */
};

/* A grid draw of the render in progress: volume space to its voxel
 * coordinates (grid_prepare()), its texture and its lookup table's first
 * entry in lut_tex. */
struct gl_grid_draw {
	const struct scene_draw *draw;
	double lin[3][3], off[3];
	uint32_t tex, lut;
};

struct render_gl {
	struct renderer base;
	struct render_gl_options opts;
	struct gl_context ctx;
	bool have_ctx;
	bool have_api; /* the context was made and its entry points loaded */
	enum gl_fault fault;
	const struct gl_api *gl;
	struct pool *pool;
	struct bin_set bins;
	uint32_t images, tiles_per_image, batch;

	struct gl_program face, section, point;
	GLuint pack, list;
	GLint pack_uni, pack_colour, list_count;
	/* The brightness model (geometry.brightness); bright_on: it thins
	 * something, and the programs were built with BRIGHT (gl_shaders.h). */
	struct brightness_map bright;
	bool bright_on;
	GLuint bright_tex; /* its rates (GL_BRIGHT_ROWS), R32UI, for the fragment shaders */
	GLuint bright_buf; /* n[u], phase[]: shader storage for the pack pass */
	GLuint vao, point_buf, prim_tex, atlas, fbo;
	GLuint touched, tile_list; /* tile marks of a batch; touched tiles as a list */
	bool atlas_dirty;          /* a render stopped half-way: clear first */
	uint32_t tex_width, tex_shift, tex_rows;
	uint32_t *staging;  /* primitives in the texture's layout */
	uint32_t triangles; /* of them, triangles: the edge draws are skipped without */
	size_t staging_cap; /* primitives */
	/* The primitive texture and point buffer hold r->bins as last built:
	 * kept bins (bin_set.keep) are not uploaded again. */
	bool uploaded;
	struct gl_batch out[2];
	int32_t *slot_of; /* per tile of a batch: its slot in the output, or -1 */
	uint8_t *rgba;    /* naive: one image read back */
	uint64_t volumes;

	/* Grids (gl_grid.c): the program and its uniforms, the textures
	 * kept, this render's grid draws and their lookup tables. */
	struct gl_program grid;
	GLint grid_uni[GRID_UNI_COUNT];
	GLuint grid_vao, lut_tex;
	uint32_t lut_rows;
	GLint max_3d;          /* GL_MAX_3D_TEXTURE_SIZE */
	uint64_t grid_renders; /* renders prepared, this one included */
	struct gl_grid_tex *grid_tex;
	uint32_t grid_tex_count, grid_tex_cap;
	struct gl_grid_draw *grid_draws;
	uint32_t grid_draw_count, grid_draw_cap;
	uint8_t *lut_staging;
	size_t lut_staging_cap; /* entries */
	uint32_t *grid_marks;   /* a batch's tile marks (gl_grid_mark()) */
	size_t grid_marks_cap;  /* words */
	bool told_grid_too_big;

	struct renderer *cpu;  /* renders what GL cannot, created when first needed */
	bool gl_dead;          /* GL failed: every volume renders on the CPU */
	bool told_too_big;     /* logged that a scene exceeds the texture */
	char description[300]; /* GL_RENDERER, GL_VERSION */
	/* Per render: */
	struct volume *vol;
	uint64_t wait_ns, copy_ns;
};

#endif
