/* Random sparse volumes and comparison, shared by the driver tests. */
#ifndef SPINDLE_TEST_VOLUME_UTIL_H
#define SPINDLE_TEST_VOLUME_UTIL_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "volume.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static inline uint32_t rnd(void)
{
	/* xorshift64*: deterministic, so failures reproduce. */
	rng_state ^= rng_state >> 12;
	rng_state ^= rng_state << 25;
	rng_state ^= rng_state >> 27;
	return (uint32_t)((rng_state * 0x2545f4914f6cdd1dull) >> 32);
}

static inline uint32_t rnd_below(uint32_t n)
{
	return rnd() % n;
}

/* One random tile of image area: only pixels inside W x H, never all zero. */
static inline void random_tile(const struct volume *vol, uint32_t t, uint8_t *tile)
{
	uint32_t x0 = (t % vol->tiles_x) * VOLUME_TILE, y0 = (t / vol->tiles_x) * VOLUME_TILE;
	uint32_t cols = vol->geom.width - x0, rows = vol->geom.height - y0;
	for (;;) {
		memset(tile, 0, VOLUME_TILE_BYTES);
		bool any = false;
		for (uint32_t c = 0; c < 3; c++)
			for (uint32_t v = 0; v < VOLUME_TILE && v < rows; v++)
				for (uint32_t u = 0; u < VOLUME_TILE && u < cols; u++)
					if (rnd_below(8) == 0) {
						tile[c * VOLUME_TILE_PLANE_BYTES + v * 4 + u / 8] |=
							(uint8_t)(0x80 >> (u % 8));
						any = true;
					}
		if (any)
			return;
	}
}

/* Fills vol with random tiles: each image empty with probability 1/4, else
 * each tile present with probability density/8. */
static inline void random_volume(struct volume *vol, uint32_t density, uint64_t seq)
{
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_clear(vol);
	vol->seq = seq;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		if (rnd_below(4) == 0)
			continue;
		for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
			if (rnd_below(8) >= density)
				continue;
			random_tile(vol, t, tile);
			CHECK_EQ(volume_image_append(vol, k, t, tile), 0);
		}
	}
}

/* dst = src with about permille/1000 of its tiles changed: of the changed
 * ones, a third removed and the rest redrawn; as many new tiles added
 * elsewhere as were removed. */
static inline void mutate_volume(struct volume *dst, const struct volume *src, uint32_t permille, uint64_t seq)
{
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_clear(dst);
	dst->seq = seq;
	for (uint32_t k = 0; k < src->image_count; k++) {
		const struct volume_image *img = &src->images[k];
		const uint8_t *p = img->tiles;
		for (uint32_t t = 0; t < volume_tiles_per_image(src); t++) {
			bool had = volume_tile_present(img, t);
			uint32_t roll = rnd_below(3000);
			if (had && roll < permille) {
				/* removed */
			} else if (had && roll < 3 * permille) {
				random_tile(dst, t, tile);
				CHECK_EQ(volume_image_append(dst, k, t, tile), 0);
			} else if (had) {
				CHECK_EQ(volume_image_append(dst, k, t, p), 0);
			} else if (img->tile_count && roll < permille / 4) {
				random_tile(dst, t, tile);
				CHECK_EQ(volume_image_append(dst, k, t, tile), 0);
			}
			p += had ? VOLUME_TILE_BYTES : 0;
		}
	}
}

static inline bool volumes_equal(const struct volume *a, const struct volume *b)
{
	if (a->image_count != b->image_count || a->mask_bytes != b->mask_bytes || a->seq != b->seq)
		return false;
	for (uint32_t k = 0; k < a->image_count; k++) {
		const struct volume_image *x = &a->images[k], *y = &b->images[k];
		if (x->tile_count != y->tile_count || memcmp(x->mask, y->mask, a->mask_bytes))
			return false;
		if (x->tile_count && memcmp(x->tiles, y->tiles, (size_t)x->tile_count * VOLUME_TILE_BYTES))
			return false;
	}
	return true;
}

#endif
