/* The compressed form the object cache keeps volumes in (compose.h
 * composes them).
 *
 * struct rle_volume keeps, per image, the occupancy mask, where each
 * stored tile's code starts, and each stored tile's bytes (384 of a
 * packed tile, CANVAS_TILE_BYTES of a canvas tile) run-length coded on
 * their own: a control byte c < 128 is followed by c + 1 literal bytes,
 * c >= 128 stands for c - 127 zero bytes. A surface crossing a tile lights
 * a few of its pixels, so most of a stored tile is zero; any one tile can
 * be read without the others. */
#ifndef SPINDLE_RLE_H
#define SPINDLE_RLE_H

#include <stddef.h>
#include <stdint.h>

#include "volume.h"

/* Mask bytes first..last (inclusive): every set bit of an image's mask
 * lies in them. */
struct rle_span {
	uint32_t first, last;
};

struct rle_image {
	uint32_t tile_count;
	uint32_t len;         /* bytes of data */
	uint8_t *data;        /* mask (the volume's mask_bytes), a uint32_t offset per
			* stored tile (from the first code), the coded tiles in order */
	struct rle_span span; /* of its mask, when it has tiles */
};

struct rle_volume {
	uint32_t image_count, mask_bytes, tiles_per_image;
	uint32_t tile_bytes;   /* VOLUME_TILE_BYTES, or CANVAS_TILE_BYTES for a canvas */
	uint64_t tiles;        /* stored tiles, all images */
	uint64_t bytes;        /* memory held, structures included */
	uint64_t packed_bytes; /* what the tiles take uncoded (tiles * tile_bytes) */
	struct rle_image *images;
	/* The images with tiles, in order (rle_volume_sum()), or NULL. */
	uint32_t *lit, lit_count;
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
/* The occupancy mask of image k. */
static inline const uint8_t *rle_image_mask(const struct rle_volume *r, uint32_t k)
{
	return r->images[k].data; /* NULL when the image is empty */
}

/* The stored tiles of canvas image k of r, decoded one at a time: fn(arg,
 * t, tile) gets tile index t and the whole canvas tile (CANVAS_TILE_BYTES,
 * its row mask first). 0, or -EINVAL when the code is broken. */
typedef void (*canvas_tile_fn)(void *arg, uint32_t t, const uint8_t *tile);
int rle_canvas_each(const struct rle_volume *r, uint32_t k, canvas_tile_fn fn, void *arg);

/* ORs one coded tile of size bytes (the code at in, avail bytes of it)
 * into dst; returns the coded bytes read, or 0 when the code is broken
 * (it never is for what rle_volume_set_image() wrote). */
size_t rle_or_coded(const uint8_t *in, size_t avail, uint8_t *dst, size_t size);

#endif
