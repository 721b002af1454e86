/* Composition of packed volumes, plain or in the compressed form the
 * object cache keeps them in (rle.h).
 *
 * Overlapping primitives and layers combine per channel by MAX before the
 * halftone, and a pixel of value c is lit iff c > its threshold, so for one
 * image and pixel threshold(max(a, b)) = threshold(a) OR threshold(b): the
 * volume of a scene is exactly the OR of the volumes of any split of its
 * draws, rendered apart by the same renderer (docs/design.md sections 3 and 5).
 * Composition is that OR, tile by tile.
 *
 * A composition can also be patched: given the previous composition and
 * the tiles that may have changed (a dirty mask per image), only those
 * tiles are composed anew, and images with none are not touched. */
#ifndef SPINDLE_COMPOSE_H
#define SPINDLE_COMPOSE_H

#include <stdbool.h>
#include <stdint.h>

#include "rle.h"
#include "tile_set.h"
#include "volume.h"

struct pool;

/* Expands r into out (same geometry; cleared first). 0 or -ENOMEM/-EINVAL. */
int rle_volume_decode(const struct rle_volume *r, struct volume *out);
/* One input of a composition: a packed volume or a compressed one. */
struct compose_source {
	const struct volume *vol;
	const struct rle_volume *rle;
};

struct compose;

/* Scratch for composing volumes of geom (one dense image per worker of
 * pool, or one when pool is NULL; pool stays the caller's). NULL + errno. */
struct compose *compose_create(const struct geometry *geom, struct pool *pool);
/* Accepts NULL. */
void compose_destroy(struct compose *c);

/* out = the OR of the n sources, image by image and tile by tile (out is
 * cleared first and must not be one of them). 0 or -ENOMEM/-EINVAL. */
int compose_volumes(struct compose *c, struct volume *out, const struct compose_source *src, unsigned n);

/* Runs c's work on pool from now on, when it has as many workers as the
 * pool c was made with (compose_create()); whether it does. awake: its
 * workers have just worked (pool.h: they look for work a while before they
 * sleep), so that smaller patches are worth handing them. */
bool compose_use_pool(struct compose *c, struct pool *pool, bool awake);
/* Patches of at most this many dirty tiles run on the calling thread,
 * the workers asleep or awake (defaults in compose.c; 0: every patch on
 * the pool, as tests ask). */
void compose_set_few_tiles(struct compose *c, uint32_t cold, uint32_t awake);
/* Patches the composition vol: the tiles marked in dirty (of vol's
 * tiling) become the OR of the n sources' tiles there; the others stay.
 * Images with no dirty tile are not touched, so the cost is that of the
 * dirty images. vol must not be a source. 0 or -ENOMEM/-EINVAL (vol is
 * then unusable). */
int compose_patch(struct compose *c, struct volume *vol, const struct tile_set *dirty, const struct compose_source *src,
		  unsigned n);
/* The tiles the last compose_patch() or compose_volumes() composed (its
 * dirty ones; every tile of the volume for the latter). */
uint64_t compose_last_tiles(const struct compose *c);

/* A canvas volume (an object rendered unturned, before the halftone)
 * shown turned about the axis by turn images, as scene.h defines a draw's
 * turn: image k of it is image j = k - turn of the canvas, j brought into
 * the volume's images by adding or subtracting the image count M, each
 * time mirrored (columns u -> W-1-u) on a mirrored geometry (M = N/2), and
 * halftoned at image k's phase; and lifted by lift rows, as scene.h
 * defines a draw's lift: row v of it is row v + lift of the canvas. */
struct turned_source {
	const struct rle_volume *canvas;
	uint32_t turn;
	int32_t lift;
};

/* Whether compose_turned() can turn canvases of this geometry: on a
 * mirrored one the width must be whole tiles. */
bool compose_can_turn(const struct compose *c);
/* out = the OR of the n turned sources (out is cleared first). 0 or
 * -ENOMEM/-EINVAL. */
int compose_turned(struct compose *c, struct volume *out, const struct turned_source *src, unsigned n);

/* Canvas tile src, at tile row ty of an image height rows high, lifted by
 * lift rows (its row v lands on row v - lift): the at most two canvas tiles
 * its rows land in, in out[i] (row mask first, zero where nothing landed)
 * with their tile rows in out_ty[i]; rows that leave the image are dropped.
 * Returns how many (0 .. 2). */
unsigned canvas_tile_lift(const uint8_t *src, uint32_t ty, int32_t lift, uint32_t height,
			  uint8_t out[2][CANVAS_TILE_BYTES], uint32_t out_ty[2]);

/* dirty |= the footprint of src (its masks), image by image. */
void compose_add_footprint(struct tile_set *dirty, const struct compose_source *src);

#endif
