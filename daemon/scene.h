/* An immutable snapshot of everything committed by every client, taken once
 * per volume: what renderers draw. Flattened to draws in model space with
 * their final model -> volume transform; renderers transform vertices. */
#ifndef SPINDLE_SCENE_H
#define SPINDLE_SCENE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

enum scene_prim {
	SCENE_POINTS = 0,    /* count points */
	SCENE_LINES = 1,     /* count / 2 segments, vertices 2i, 2i+1 */
	SCENE_TRIANGLES = 2, /* count / 3 triangles, vertices 3i..3i+2 */
	SCENE_GRID = 3,      /* a sampled 3-D grid (grid, transfer); count 0 */
};

/* A grid's sample types: the protocol's volume types. */
enum scene_grid_type {
	SCENE_GRID_U8 = 1,
	SCENE_GRID_U16 = 2,
	SCENE_GRID_I16 = 3,
	SCENE_GRID_F32 = 4,
	SCENE_GRID_RGBA8 = 5, /* 4 bytes R, G, B, A */
};

/* A 3-D grid of samples (medical and scientific volumes, docs/volumes.md),
 * immutable while a scene holds it. Voxel (i, j, k) is centred at model
 * point ((i + 0.5) sx, (j + 0.5) sy, (k + 0.5) sz) and fills the box of
 * half a voxel around it; j is the grid's up axis and varies fastest in
 * memory: sample (i, j, k) is element (k * n[0] + i) * n[1] + j. */
struct scene_grid {
	uint32_t type;    /* enum scene_grid_type */
	uint32_t n[3];    /* samples along i, j, k, each >= 1 */
	float spacing[3]; /* sx, sy, sz: model units between centres, > 0 */
	const void *data; /* n[0] n[1] n[2] samples, host byte order */
	/* NULL, or the largest sample (RGBA8: alpha) of each brick, NaN left
	 * out: brick b of line (i, k) is samples j = b SCENE_GRID_BRICK .. (b
	 * + 1) SCENE_GRID_BRICK - 1 (fewer at the top), its maximum at
	 * brick_max[(k * n[0] + i) * scene_grid_bricks(n[1]) + b]
	 * (grid_brick_max()): a renderer skips what stays below a threshold. */
	const float *brick_max;
};

/* Samples per brick along a grid's up axis; bricks per line of n1. */
#define SCENE_GRID_BRICK 32u
static inline uint32_t scene_grid_bricks(uint32_t n1)
{
	return (n1 + SCENE_GRID_BRICK - 1) / SCENE_GRID_BRICK;
}

enum scene_sampling {
	SCENE_NEAREST = 0,   /* the sample whose box holds the point */
	SCENE_TRILINEAR = 1, /* the 8 around it weighted (edges repeated) */
};

/* How a grid's values become colours. Scalar value v (RGBA8: its alpha)
 * below threshold (or not a number) lights nothing; else g = (v - lo) (1
 * / (hi - lo)), in float, clamped to 0..1 picks the colour: the draw's rgb
 * times g (rounded to nearest), or lut entry round(g (lut_count - 1)). An
 * RGBA8 sample is its own colour times its alpha. */
struct scene_transfer {
	float threshold;
	float lo, hi;       /* lo < hi: the window */
	uint32_t sampling;  /* enum scene_sampling */
	const uint8_t *lut; /* NULL, or lut_count RGB entries (alpha applied) */
	uint32_t lut_count; /* 2 .. 4096 with a lut */
};

struct scene_draw {
	enum scene_prim prim;
	uint32_t count;                 /* vertices; a multiple of 2 (lines) or 3 (triangles) */
	const float *xyz;               /* count * 3 floats, immutable while the scene lives */
	float transform[16];            /* column-major 4x4, model -> volume space (affine) */
	uint8_t rgb[3];                 /* colour, alpha already applied (emissive) */
	uint8_t point_size;             /* points: each lights a point_size x point_size
				* pixel square around its voxel (columns
				* u - (s-1)/2 .. u + s/2, rows likewise, clipped
				* to the image); 0 counts as 1. At most 16. */
	uint16_t turn;                  /* 0 .. N-1: shown turned about the y axis by
				* turn * 2 pi / N (azimuths increasing:
				* x' = x cos a - z sin a, z' = x sin a + z cos a),
				* as an image index shift (below); more than
				* N-1 counts modulo N. 0: as it is. */
	int16_t lift;                   /* rows: shown moved up the axis by lift
				 * whole image rows (down when negative), as a
				 * row shift (below). 0: as it is. */
	const uint8_t *prim_rgb;        /* NULL, or one colour per primitive (3 bytes
				  * each, alpha applied) used instead of rgb;
				  * immutable while the scene lives */
	const struct scene_grid *grid;  /* SCENE_GRID: the grid, and how */
	struct scene_transfer transfer; /* its values show */
	/* SCENE_GRID: a number naming the grid for the daemon's life, never
	 * reused (snapshot.c), by which a renderer keeps what it made of the
	 * grid from one render to the next (the GL renderers' textures); 0:
	 * none (tests, the benchmark), and the grid is known by its address,
	 * its data's and its size, which the caller must not give another
	 * grid while the renderer may still hold the first (render_gl.h). */
	uint64_t grid_id;
	/* Lines, triangles and points: a number naming the contents of xyz
	 * and prim_rgb for the daemon's life, never given to other contents
	 * (snapshot.c numbers each vertex data when first drawn; draws
	 * sharing one data share its number), by which the CPU renderer keeps
	 * its binning of a scene whose draws are all the same from one render
	 * to the next (render_cpu.c). 0: none, and nothing is kept. */
	uint64_t data_id;
};

/* A draw with lift L lights, in row v of each image, what it would light
 * with lift 0 in row v + L of that image, before the halftone; rows v + L
 * outside the image light nothing. Turns and lifts commute (one moves
 * images and columns, the other rows). The daemon lifts a draw only where
 * its lifted and unlifted renders both lie wholly inside the image rows
 * (snapshot.c), so that the shift loses nothing a render of the moved
 * draw would show. The CPU renderer draws lifted draws into canvases of
 * their own and merges them shifted (render_cpu.c); the GL renderers hand
 * such scenes to their CPU fallback, as they do turns.
 *
 * A draw with turn m lights, in volume image k, exactly what it would light
 * with turn 0 in image j = k - m (docs/rendering.md, "Turns"): unmirrored,
 * j is taken mod N; mirrored (M = N/2 images a volume), j is brought into
 * [0, M) by adding or subtracting M, each time flipping the mirror, and
 * when the flips are odd the columns are mirrored (u -> W-1-u). Rows never
 * change. Its colours combine by MAX with everything else before the
 * halftone, which keeps image k's phase. So a render of an object unturned
 * gives its render at any turn, bit for bit, by shifting (and mirroring)
 * images, as long as its colours' halftone does not depend on the phase
 * (channels 0 or 255) or the unturned canvas is kept. The GL renderers
 * hand a scene with any turn or lift to their CPU fallback (render_gl.h):
 * scene_has_turn() counts both. */
static inline bool scene_has_turn(const struct scene_draw *draws, uint32_t n)
{
	for (uint32_t i = 0; i < n; i++)
		if (draws[i].turn || draws[i].lift)
			return true;
	return false;
}

static inline bool scene_has_lift(const struct scene_draw *draws, uint32_t n)
{
	for (uint32_t i = 0; i < n; i++)
		if (draws[i].lift)
			return true;
	return false;
}

static inline bool scene_has_grid(const struct scene_draw *draws, uint32_t n)
{
	for (uint32_t i = 0; i < n; i++)
		if (draws[i].prim == SCENE_GRID)
			return true;
	return false;
}

/* Whether a and b draw the same grid the same way (a->prim == SCENE_GRID). */
static inline bool scene_grid_same(const struct scene_draw *a, const struct scene_draw *b)
{
	const struct scene_transfer *x = &a->transfer, *y = &b->transfer;
	return a->grid == b->grid && x->threshold == y->threshold && x->lo == y->lo && x->hi == y->hi &&
	       x->sampling == y->sampling && x->lut == y->lut && x->lut_count == y->lut_count;
}

/* Whether a and b draw the same but perhaps for their turn and lift: the
 * same primitives of the same data (address, per-primitive colours and
 * number), placed and coloured the same. Callers hold the data (the
 * daemon's references), or compare numbers (scene_draw.data_id). */
static inline bool scene_draw_alike(const struct scene_draw *a, const struct scene_draw *b)
{
	return a->prim == b->prim && a->count == b->count && a->xyz == b->xyz && a->prim_rgb == b->prim_rgb &&
	       a->data_id == b->data_id && a->point_size == b->point_size &&
	       memcmp(a->transform, b->transform, sizeof(a->transform)) == 0 &&
	       memcmp(a->rgb, b->rgb, sizeof(a->rgb)) == 0 && (a->prim != SCENE_GRID || scene_grid_same(a, b));
}

/* The same, turn and lift included. */
static inline bool scene_draw_same(const struct scene_draw *a, const struct scene_draw *b)
{
	return scene_draw_alike(a, b) && a->turn == b->turn && a->lift == b->lift;
}

/* A retained object: the draws of one layer (its list placed by its
 * transform), the unit the object cache keeps (cache.h). Renderers draw
 * the draws and ignore the objects. */
struct scene_object {
	uint64_t key;        /* the same while the object lives (its layer's serial), never 0 */
	uint32_t first_draw; /* its draws are draws[first_draw, first_draw + draw_count) */
	uint32_t draw_count;
};

struct scene {
	uint32_t draw_count;
	const struct scene_draw *draws;
	uint32_t object_count; /* 0: the draws are no objects (one render) */
	const struct scene_object *objects;
};

#endif
