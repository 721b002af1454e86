/* A packed, tile-sparse volume: what renderers produce, the projector wire
 * codec carries, and capture turns into an .svol file.
 *
 * Each image is cut into 32x32-pixel tiles, tiles_x = ceil(W/32) across and
 * tiles_y = ceil(H/32) down, numbered t = ty * tiles_x + tx. A tile holds the
 * three bit planes R, G, B in that order, each 32 rows of 4 bytes, most
 * significant bit = leftmost pixel (the dense convention of docs/design.md, cut
 * into tiles). Pixels past W or H in edge tiles are always 0. Only non-empty
 * tiles are stored, in increasing t; the occupancy mask has bit t set
 * (byte t / 8, bit t % 8) for each stored tile. */
#ifndef SPINDLE_VOLUME_H
#define SPINDLE_VOLUME_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "geometry.h"

#define VOLUME_TILE 32
#define VOLUME_TILE_PLANE_BYTES (VOLUME_TILE * VOLUME_TILE / 8) /* 128 */
#define VOLUME_TILE_BYTES (3 * VOLUME_TILE_PLANE_BYTES)         /* 384 */

struct volume_image {
	uint32_t tile_count; /* stored (non-empty) tiles */
	uint32_t tile_cap;   /* tiles the storage has room for */
	uint32_t next_tile;  /* 1 + the last stored tile's number, 0 if none */
	uint8_t *mask;       /* mask_bytes, owned by the volume */
	uint8_t *tiles;      /* tile_count * VOLUME_TILE_BYTES, owned */
	/* What a writer that knows an image's contents may mark it with
	 * (volume_new_stamp()), so that two images with the same stamp, not
	 * 0, need not be compared (the upload delta, projwire.h): every
	 * change through the calls below sets it to 0, and a copy of an image
	 * (volume_copy_image(), volume_image_exchange())
	 * takes the source's. A writer that changes an image's tiles in place
	 * sets it to 0 first. */
	uint64_t stamp;
};

struct volume {
	struct geometry geom;
	uint32_t image_count; /* images per volume (N/2 when mirrored) */
	uint32_t tiles_x, tiles_y;
	uint32_t mask_bytes; /* ceil(tiles_x * tiles_y / 8) */
	uint64_t seq;        /* volume sequence number */
	uint64_t shown_ns;   /* CLOCK_MONOTONIC when first shown, 0 if never */
	/* What a writer may mark its contents with, to know them again
	 * (the object cache's compositions); every change through the calls
	 * below resets it to 0. */
	uint64_t origin;
	struct volume_image *images;
};

/* A stamp no image has had (struct volume_image), never 0. Thread-safe. */
uint64_t volume_new_stamp(void);

/* Creates an empty volume (every image has no tiles). NULL + errno on
 * failure. */
struct volume *volume_create(const struct geometry *geom);
/* Accepts NULL. */
void volume_destroy(struct volume *vol);

/* Empties every image; keeps storage. */
void volume_clear(struct volume *vol);

/* A packed tile copied, or zeroed, in 16-byte moves: a fixed-size memcpy
 * or memset of it compiles to rep movs / rep stos, whose start costs more
 * than the tile. */
typedef uint8_t volume_chunk __attribute__((vector_size(16), aligned(1)));

static inline void volume_tile_copy(uint8_t *restrict dst, const uint8_t *restrict src)
{
	for (size_t i = 0; i < VOLUME_TILE_BYTES; i += sizeof(volume_chunk))
		*(volume_chunk *)(dst + i) = *(const volume_chunk *)(src + i);
}

static inline void volume_tile_zero(uint8_t *dst)
{
	for (size_t i = 0; i < VOLUME_TILE_BYTES; i += sizeof(volume_chunk))
		*(volume_chunk *)(dst + i) = (volume_chunk){ 0 };
}

/* dst |= src over a packed tile, in 16-byte moves (the composition of
 * lit bits: compose.h). */
static inline void volume_tile_or(uint8_t *restrict dst, const uint8_t *restrict src)
{
	for (size_t i = 0; i < VOLUME_TILE_BYTES; i += sizeof(volume_chunk))
		*(volume_chunk *)(dst + i) |= *(const volume_chunk *)(src + i);
}

/* Tiles across n pixels: ceil(n / VOLUME_TILE). */
static inline uint32_t volume_tiles_across(uint32_t n)
{
	return (n + VOLUME_TILE - 1) / VOLUME_TILE;
}

/* Tiles of an image of geometry g: tiles_x * tiles_y. */
static inline uint32_t volume_geometry_tiles(const struct geometry *g)
{
	return volume_tiles_across(g->width) * volume_tiles_across(g->height);
}

static inline uint32_t volume_tiles_per_image(const struct volume *vol)
{
	return vol->tiles_x * vol->tiles_y;
}

/* Set bits of a mask byte (without the library call __builtin_popcount
 * becomes where the CPU baseline has no POPCNT instruction). */
static inline uint32_t volume_mask_bits(uint32_t byte)
{
	byte = byte - ((byte >> 1) & 0x55);
	byte = (byte & 0x33) + ((byte >> 2) & 0x33);
	return (byte + (byte >> 4)) & 0x0f;
}

/* Set bits of a 64-bit word, the same way. */
static inline uint32_t volume_word_bits(uint64_t x)
{
	x = x - ((x >> 1) & 0x5555555555555555ull);
	x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
	x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
	return (uint32_t)((x * 0x0101010101010101ull) >> 56);
}

/* Tiles 64 w .. 64 w + 63 of a mask of bytes bytes as one word: bit i is
 * tile 64 w + i (byte b's bit j is tile 8 b + j), 0 past the mask's end.
 * The mask loops go a word at a time: a byte at a time, an image's 72
 * bytes cost more than the few tiles a small object changes. */
static inline uint64_t volume_mask_word(const uint8_t *mask, uint32_t bytes, uint32_t w)
{
	uint32_t at = 8 * w;
	uint64_t x = 0;
	if (bytes - at >= 8) {
		memcpy(&x, mask + at, sizeof(x));
#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
		x = __builtin_bswap64(x);
#endif
		return x;
	}
	for (uint32_t i = 0; at + i < bytes; i++)
		x |= (uint64_t)mask[at + i] << (8 * i);
	return x;
}

/* Words of a mask of bytes bytes (volume_mask_word()). */
static inline uint32_t volume_mask_words(uint32_t bytes)
{
	return (bytes + 7) / 8;
}

/* Whether n bytes are all zero (eight at a time). */
bool volume_all_zero(const uint8_t *p, size_t n);

static inline int volume_tile_present(const struct volume_image *img, uint32_t t)
{
	return (img->mask[t / 8] >> (t % 8)) & 1;
}

/* Makes room for at least n tiles in image k. Returns 0 or -ENOMEM. */
int volume_image_reserve(struct volume *vol, uint32_t k, uint32_t n);

/* Appends tile t (which must be greater than every stored tile) to image k,
 * copying VOLUME_TILE_BYTES from data, unless those bytes are all zero.
 * Returns 0, or -ENOMEM, or -EINVAL if t is out of range or out of order. */
int volume_image_append(struct volume *vol, uint32_t k, uint32_t t, const uint8_t *data);

/* Appending in place, for renderers: the storage for image k's next tile
 * (VOLUME_TILE_BYTES to fill), or NULL when out of memory. Nothing is
 * stored until volume_image_push() commits it as tile t. */
uint8_t *volume_image_next(struct volume *vol, uint32_t k);
/* Commits the bytes at volume_image_next(vol, k) as tile t, which must be
 * greater than every stored tile and not all zero. 0 or -EINVAL. */
int volume_image_push(struct volume *vol, uint32_t k, uint32_t t);
/* Sets image k whole, for a writer that fills its storage alone (room
 * made with volume_image_reserve()): its first count stored tiles are the
 * tiles set in mask, in increasing order, none all zero. It writes the
 * image's fields and mask once, where volume_image_push() writes them a
 * tile at a time (they share cache lines with the next image's, which
 * another thread may be writing). 0 or -EINVAL (count is not the number of
 * tiles in mask, or more than the room). */
int volume_image_set(struct volume *vol, uint32_t k, const uint8_t *mask, uint32_t count);

/* Empties image k; keeps its storage. */
void volume_image_clear(struct volume *vol, uint32_t k);
/* Exchanges the contents of image ka of a and image kb of b (volumes of the
 * same geometry): tiles, mask and counts, without copying tiles. */
void volume_image_exchange(struct volume *a, uint32_t ka, struct volume *b, uint32_t kb);

/* The set bits of the first bytes bytes of mask (eight at a time). */
uint32_t volume_mask_count(const uint8_t *mask, size_t bytes);
/* The stored index of tile t in an image with this mask: how many of its
 * tiles come before t (t up to tiles per image: all of them). */
uint32_t volume_stored_index(const uint8_t *mask, uint32_t t);

/* Tiles first..last of image k become the tiles whose bits are set in
 * mask's first..last, stored in that order at run (not all zero, and not
 * in vol's storage): the stored tiles before first stay where they are,
 * those after last move by one memmove, and the mask, counts and next
 * tile follow. So a few tiles that come or go cost the tiles between
 * them and one move, not a copy of the image. 0 or -ENOMEM/-EINVAL. */
int volume_image_splice(struct volume *vol, uint32_t k, uint32_t first, uint32_t last, const uint8_t *mask,
			const uint8_t *run);

/* Deep copy of src into dst of the same geometry. 0 or -ENOMEM/-EINVAL. */
int volume_copy(struct volume *dst, const struct volume *src);
/* Image k of src copied into image k of dst (same geometry); nothing
 * else. 0 or -ENOMEM/-EINVAL. */
int volume_copy_image(struct volume *dst, uint32_t k, const struct volume *src);

/* dst (same size as src, not src) becomes src moved by du columns and dv
 * rows: pixel (u, v) of dst is pixel (u - du, v - dv) of src, dark where
 * that is outside the image (calibration.h's axis offset). seq and
 * shown_ns are copied. 0, -ENOMEM or -EINVAL. */
int volume_shift(struct volume *dst, const struct volume *src, int32_t du, int32_t dv);
/* The same without SIMD (volume_shift() takes AVX2 where the CPU has it),
 * bit for bit: for tests and benchmarks. */
int volume_shift_scalar(struct volume *dst, const struct volume *src, int32_t du, int32_t dv);

/* Bytes of image k if stored dense: 3 planes of H rows of ceil(W/8). */
size_t volume_dense_image_bytes(const struct volume *vol);

/* Writes image k dense (plane R, G, B; H rows of ceil(W/8) bytes; MSB =
 * leftmost) into out, which has volume_dense_image_bytes() bytes. */
void volume_image_to_dense(const struct volume *vol, uint32_t k, uint8_t *out);

/* Value (0/1) of pixel (u, v) of channel c (0 R, 1 G, 2 B) of image k. */
int volume_pixel(const struct volume *vol, uint32_t k, uint32_t u, uint32_t v, int c);

/* Total stored tiles, and the sparse payload bytes (masks + tiles). */
uint64_t volume_tile_count(const struct volume *vol);
uint64_t volume_sparse_bytes(const struct volume *vol);
/* Bytes the volume holds in memory: its images, masks and tile storage
 * (what it has room for, not only what is stored). */
uint64_t volume_held_bytes(const struct volume *vol);

#endif
