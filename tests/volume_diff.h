/* Which tiles two volumes of one tiling differ in, counted the plain way
 * (tile by tile, both masks walked), for the tests that check what an
 * upload sends or may skip. */
#ifndef SPINDLE_TEST_VOLUME_DIFF_H
#define SPINDLE_TEST_VOLUME_DIFF_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "volume.h"

/* The tiles where a and b differ (one of them lacks it, or its bytes),
 * but for those marked in except (a mask per image, or NULL): how many;
 * marked in diff too (a mask per image, zeroed by the caller, or NULL);
 * *both (or NULL) counts those both volumes hold. */
static inline uint64_t volume_differences(const struct volume *a, const struct volume *b, const uint8_t *except,
					  uint8_t *diff, uint64_t *both)
{
	uint64_t n = 0, in_both = 0;
	for (uint32_t k = 0; k < a->image_count; k++) {
		const struct volume_image *x = &a->images[k], *y = &b->images[k];
		const uint8_t *px = x->tiles, *py = y->tiles;
		size_t at = (size_t)k * a->mask_bytes;
		for (uint32_t t = 0; t < volume_tiles_per_image(a); t++) {
			bool in_x = volume_tile_present(x, t), in_y = volume_tile_present(y, t);
			bool differ = in_x != in_y || (in_x && memcmp(px, py, VOLUME_TILE_BYTES));
			uint8_t bit = (uint8_t)(1u << (t % 8));
			px += in_x ? VOLUME_TILE_BYTES : 0;
			py += in_y ? VOLUME_TILE_BYTES : 0;
			if (!differ || (except && (except[at + t / 8] & bit)))
				continue;
			n++;
			in_both += in_x && in_y;
			if (diff)
				diff[at + t / 8] |= bit;
		}
	}
	if (both)
		*both = in_both;
	return n;
}

#endif
