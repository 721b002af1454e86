/* Composition of packed volumes, and the compressed form the object cache
 * keeps them in.
 *
 * Overlapping primitives and layers combine per channel by MAX before the
 * halftone, and a pixel of value c is lit iff c > its threshold, so for one
 * image and pixel threshold(max(a, b)) = threshold(a) OR threshold(b): the
 * volume of a scene is exactly the OR of the volumes of any split of its
 * draws, rendered apart by the same renderer (DESIGN.md sections 3 and 5).
 * Composition is that OR, tile by tile.
 *
 * The compressed form (struct rle_volume) keeps, per image, the occupancy
 * mask and each stored tile's 384 bytes run-length coded on their own: a
 * control byte c < 128 is followed by c + 1 literal bytes, c >= 128 stands
 * for c - 127 zero bytes. A surface crossing a tile lights a few of its
 * pixels, so most of a stored tile is zero. */
#ifndef SPINDLE_COMPOSE_H
#define SPINDLE_COMPOSE_H

#include <stdbool.h>
#include <stdint.h>

#include "volume.h"

struct pool;

struct rle_image {
	uint32_t tile_count;
	uint32_t len;  /* bytes of data */
	uint8_t *data; /* mask (the volume's mask_bytes), then the coded tiles in order */
};

struct rle_volume {
	uint32_t image_count, mask_bytes, tiles_per_image;
	uint64_t tiles;        /* stored tiles, all images */
	uint64_t bytes;        /* memory held, structures included */
	uint64_t packed_bytes; /* what the tiles take packed (tiles * 384) */
	struct rle_image *images;
};

/* Compresses vol. NULL + errno (ENOMEM). */
struct rle_volume *rle_volume_encode(const struct volume *vol);
/* Accepts NULL. */
void rle_volume_free(struct rle_volume *r);
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

#endif
