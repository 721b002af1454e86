/* Composition of packed volumes, and the compressed form the object cache
 * keeps them in.
 *
 * Overlapping primitives and layers combine per channel by MAX before the
 * halftone, and a pixel of value c is lit iff c > its threshold, so for one
 * image and pixel threshold(max(a, b)) = threshold(a) OR threshold(b): the
 * volume of a scene is exactly the OR of the volumes of any split of its
 * draws, rendered apart by the same renderer (docs/design.md sections 3 and 5).
 * Composition is that OR, tile by tile.
 *
 * The compressed form (struct rle_volume) keeps, per image, the occupancy
 * mask, where each stored tile's code starts, and each stored tile's 384
 * bytes run-length coded on their own: a control byte c < 128 is followed
 * by c + 1 literal bytes, c >= 128 stands for c - 127 zero bytes. A surface
 * crossing a tile lights a few of its pixels, so most of a stored tile is
 * zero; any one tile can be read without the others.
 *
 * A composition can also be patched: given the previous composition and
 * the tiles that may have changed (a dirty mask per image), only those
 * tiles are composed anew, and images with none are not touched. */
#ifndef SPINDLE_COMPOSE_H
#define SPINDLE_COMPOSE_H

#include <stdbool.h>
#include <stdint.h>

#include "volume.h"

struct pool;

struct rle_image {
	uint32_t tile_count;
	uint32_t len;  /* bytes of data */
	uint8_t *data; /* mask (the volume's mask_bytes), a uint32_t offset per
			* stored tile (from the first code), the coded tiles in order */
};

struct rle_volume {
	uint32_t image_count, mask_bytes, tiles_per_image;
	uint32_t tile_bytes;   /* VOLUME_TILE_BYTES, or CANVAS_TILE_BYTES for a canvas */
	uint64_t tiles;        /* stored tiles, all images */
	uint64_t bytes;        /* memory held, structures included */
	uint64_t packed_bytes; /* what the tiles take uncoded (tiles * tile_bytes) */
	struct rle_image *images;
	/* The images with tiles, in order (rle_volume_sum()), or NULL; and
	 * for each, the mask bytes its tiles lie between. */
	uint32_t *lit, lit_count;
	struct rle_span *lit_span;
};

/* Mask bytes first..last (inclusive): every set bit of an image's mask
 * lies in them. */
struct rle_span {
	uint32_t first, last;
};

/* A tile of a canvas volume: an object rendered before the halftone, as
 * the CPU renderer's canvas holds it (halftone.h: planes R, G, B of 32
 * rows of 32 bytes, pixel x at byte x ^ 7), after a uint32_t whose bit y
 * says row y may be non-zero. */
#define CANVAS_TILE_BYTES (4 + 3 * 32 * 32)

/* Compresses vol. NULL + errno (ENOMEM). */
struct rle_volume *rle_volume_encode(const struct volume *vol);

/* An empty coded volume with tiles of tile_bytes, filled image by image
 * with rle_volume_set_image() (from several threads, each its own
 * images), then rle_volume_sum(). NULL on failure. */
struct rle_volume *rle_volume_new(uint32_t image_count, uint32_t mask_bytes, uint32_t tiles_per_image,
				  uint32_t tile_bytes);
/* Work space for coding, kept between calls; free(buf) when done. */
struct rle_scratch {
	uint8_t *buf;
	size_t cap;
};
/* Image k: count tiles (count * tile_bytes bytes) in the order of mask's
 * set bits. 0 or -ENOMEM. */
int rle_volume_set_image(struct rle_volume *r, uint32_t k, const uint8_t *mask, const uint8_t *tiles, uint32_t count,
			 struct rle_scratch *s);
/* Counts tiles and bytes once every image is set. */
void rle_volume_sum(struct rle_volume *r);
/* Accepts NULL. */
void rle_volume_free(struct rle_volume *r);
/* Expands r into out (same geometry; cleared first). 0 or -ENOMEM/-EINVAL. */
int rle_volume_decode(const struct rle_volume *r, struct volume *out);
/* The occupancy mask of image k. */
static inline const uint8_t *rle_image_mask(const struct rle_volume *r, uint32_t k)
{
	return r->images[k].data; /* NULL when the image is empty */
}

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

/* Patches the composition vol: in each image k, the tiles whose bit is set
 * in dirty + k * vol->mask_bytes become the OR of the n sources' tiles
 * there; the others stay. Images with no dirty tile are not touched, so
 * the cost is that of the dirty images. vol must not be a source. 0 or
 * -ENOMEM/-EINVAL (vol is then unusable). */
int compose_patch(struct compose *c, struct volume *vol, const uint8_t *dirty, const struct compose_source *src,
		  unsigned n);

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

/* The stored tiles of canvas image k of r, decoded one at a time: fn(arg,
 * t, tile) gets tile index t and the whole canvas tile (CANVAS_TILE_BYTES,
 * its row mask first). 0, or -EINVAL when the code is broken. */
typedef void (*canvas_tile_fn)(void *arg, uint32_t t, const uint8_t *tile);
int rle_canvas_each(const struct rle_volume *r, uint32_t k, canvas_tile_fn fn, void *arg);

/* Canvas tile src, at tile row ty of an image height rows high, lifted by
 * lift rows (its row v lands on row v - lift): the at most two canvas tiles
 * its rows land in, in out[i] (row mask first, zero where nothing landed)
 * with their tile rows in out_ty[i]; rows that leave the image are dropped.
 * Returns how many (0 .. 2). */
unsigned canvas_tile_lift(const uint8_t *src, uint32_t ty, int32_t lift, uint32_t height,
			  uint8_t out[2][CANVAS_TILE_BYTES], uint32_t out_ty[2]);

/* dirty |= the footprint of src (its masks), image by image. */
void compose_add_footprint(uint8_t *dirty, uint32_t image_count, uint32_t mask_bytes, const struct compose_source *src);

#endif
