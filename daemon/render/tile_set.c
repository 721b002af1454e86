/* Sets of tiles (tile_set.h). */
#include "tile_set.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "volume.h"

int tile_set_init(struct tile_set *s, uint32_t image_count, uint32_t tiles_per_image)
{
	uint32_t mask_bytes = (tiles_per_image + 7) / 8;
	*s = (struct tile_set){ .image_count = image_count,
				.tiles_per_image = tiles_per_image,
				.mask_bytes = mask_bytes };
	s->mask = calloc(image_count, mask_bytes);
	s->images = calloc(image_count, 1);
	s->list = calloc(image_count ? image_count : 1, sizeof(*s->list));
	if (s->mask && s->images && s->list)
		return 0;
	tile_set_finish(s);
	return -ENOMEM;
}

void tile_set_finish(struct tile_set *s)
{
	free(s->mask);
	free(s->images);
	free(s->list);
	*s = (struct tile_set){ 0 };
}

void tile_set_fill(struct tile_set *s)
{
	uint32_t full = s->tiles_per_image / 8, rest = s->tiles_per_image % 8;
	for (uint32_t k = 0; k < s->image_count; k++) {
		uint8_t *m = s->mask + (size_t)k * s->mask_bytes;
		memset(m, 0xff, full);
		if (rest)
			m[full] = (uint8_t)((1u << rest) - 1);
	}
	memset(s->images, 1, s->image_count);
	for (uint32_t k = 0; k < s->image_count; k++)
		s->list[k] = k;
	s->listed = s->image_count;
}

void tile_set_clear(struct tile_set *s)
{
	for (uint32_t p = 0; p < s->listed; p++) {
		uint32_t k = s->list[p];
		memset(s->mask + (size_t)k * s->mask_bytes, 0, s->mask_bytes);
		s->images[k] = 0;
	}
	s->listed = 0;
}

uint8_t *tile_set_flag(struct tile_set *s, uint32_t k)
{
	if (!s->images[k]) {
		s->images[k] = 1;
		s->list[s->listed++] = k;
	}
	return s->mask + (size_t)k * s->mask_bytes;
}

void tile_set_or(struct tile_set *dst, const struct tile_set *src)
{
	for (uint32_t p = 0; p < src->listed; p++) {
		uint32_t k = src->list[p];
		const uint8_t *m = src->mask + (size_t)k * src->mask_bytes;
		uint8_t *d = tile_set_flag(dst, k);
		uint32_t b = 0;
		for (; b + 8 <= src->mask_bytes; b += 8) {
			uint64_t x, y;
			memcpy(&x, d + b, sizeof(x));
			memcpy(&y, m + b, sizeof(y));
			x |= y;
			memcpy(d + b, &x, sizeof(x));
		}
		for (; b < src->mask_bytes; b++)
			d[b] |= m[b];
	}
}

void tile_set_copy(struct tile_set *dst, const struct tile_set *src)
{
	tile_set_clear(dst);
	tile_set_or(dst, src);
}

uint64_t tile_set_count(const struct tile_set *s)
{
	uint64_t n = 0;
	for (uint32_t p = 0; p < s->listed; p++)
		n += volume_mask_count(s->mask + (size_t)s->list[p] * s->mask_bytes, s->mask_bytes);
	return n;
}

bool tile_set_image_any(const struct tile_set *s, uint32_t k)
{
	return s->images[k] && !volume_all_zero(s->mask + (size_t)k * s->mask_bytes, s->mask_bytes);
}
