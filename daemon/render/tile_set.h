/* Sets of tiles of a volume's tiling, as the compositor marks the tiles
 * to compose anew (compose.h) and the object cache those each composition
 * changed (cache.h). */
#ifndef SPINDLE_TILE_SET_H
#define SPINDLE_TILE_SET_H

#include <stdbool.h>
#include <stdint.h>

/* Tiles marked in a volume's tiling: a mask per image (image_count *
 * mask_bytes, bit t of image k's for its tile t) and, per image, whether
 * its mask may have a bit (a zero flag means a zero mask); the flagged
 * images are also listed, in the order they were flagged (list[0 ..
 * listed)). What walks the marks walks the list, and so pays for the
 * images flagged, not for all: a small object marks a few. */
struct tile_set {
	uint32_t image_count, tiles_per_image, mask_bytes;
	uint8_t *mask;
	uint8_t *images;
	uint32_t *list, listed;
};

/* Empty, for a volume of image_count images of tiles_per_image tiles
 * (mask_bytes as volume.h's); 0 or -ENOMEM. */
int tile_set_init(struct tile_set *s, uint32_t image_count, uint32_t tiles_per_image);
/* Accepts a zeroed one. */
void tile_set_finish(struct tile_set *s);
/* Every tile marked (no bit past the last tile of an image). */
void tile_set_fill(struct tile_set *s);
/* Nothing marked (the flagged images' masks zeroed). */
void tile_set_clear(struct tile_set *s);
/* dst (of the same tiling) becomes src. */
void tile_set_copy(struct tile_set *dst, const struct tile_set *src);
/* dst (of the same tiling) |= src. */
void tile_set_or(struct tile_set *dst, const struct tile_set *src);
/* Image k flagged (and listed), its mask left as it is; returns the mask. */
uint8_t *tile_set_flag(struct tile_set *s, uint32_t k);
/* How many tiles are marked. */
uint64_t tile_set_count(const struct tile_set *s);
/* Whether image k has a mark (its flag, then its mask). */
bool tile_set_image_any(const struct tile_set *s, uint32_t k);

#endif
