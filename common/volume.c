#include "volume.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

struct volume *volume_create(const struct geometry *geom)
{
	if (geometry_validate(geom) < 0) {
		errno = EINVAL;
		return NULL;
	}
	struct volume *vol = calloc(1, sizeof(*vol));
	if (!vol)
		return NULL;
	vol->geom = *geom;
	vol->image_count = geometry_images_per_volume(geom);
	vol->tiles_x = volume_tiles_across(geom->width);
	vol->tiles_y = volume_tiles_across(geom->height);
	vol->mask_bytes = (vol->tiles_x * vol->tiles_y + 7) / 8;
	vol->images = calloc(vol->image_count, sizeof(*vol->images));
	uint8_t *masks = calloc(vol->image_count, vol->mask_bytes);
	if (!vol->images || !masks) {
		free(masks);
		free(vol->images);
		free(vol);
		errno = ENOMEM;
		return NULL;
	}
	for (uint32_t k = 0; k < vol->image_count; k++)
		vol->images[k].mask = masks + (size_t)k * vol->mask_bytes;
	return vol;
}

void volume_destroy(struct volume *vol)
{
	if (!vol)
		return;
	for (uint32_t k = 0; k < vol->image_count; k++)
		free(vol->images[k].tiles);
	if (vol->image_count)
		free(vol->images[0].mask);
	free(vol->images);
	free(vol);
}

uint64_t volume_new_stamp(void)
{
	static atomic_uint_fast64_t stamps;
	return atomic_fetch_add(&stamps, 1) + 1;
}

void volume_clear(struct volume *vol)
{
	memset(vol->images[0].mask, 0, (size_t)vol->image_count * vol->mask_bytes);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		vol->images[k].tile_count = vol->images[k].next_tile = 0;
		vol->images[k].stamp = 0;
	}
	vol->seq = 0;
	vol->shown_ns = 0;
	vol->origin = 0;
}

void volume_image_clear(struct volume *vol, uint32_t k)
{
	memset(vol->images[k].mask, 0, vol->mask_bytes);
	vol->images[k].tile_count = vol->images[k].next_tile = 0;
	vol->images[k].stamp = 0;
	vol->origin = 0;
}

void volume_image_exchange(struct volume *a, uint32_t ka, struct volume *b, uint32_t kb)
{
	struct volume_image *x = &a->images[ka], *y = &b->images[kb];
	a->origin = b->origin = 0;
	/* The masks stay where they are (one block per volume); their bytes
	 * move. */
	for (uint32_t i = 0; i < a->mask_bytes; i++) {
		uint8_t m = x->mask[i];
		x->mask[i] = y->mask[i];
		y->mask[i] = m;
	}
	struct volume_image t = *x;
	x->tile_count = y->tile_count;
	x->tile_cap = y->tile_cap;
	x->next_tile = y->next_tile;
	x->tiles = y->tiles;
	x->stamp = y->stamp;
	y->tile_count = t.tile_count;
	y->tile_cap = t.tile_cap;
	y->next_tile = t.next_tile;
	y->tiles = t.tiles;
	y->stamp = t.stamp;
}

int volume_image_reserve(struct volume *vol, uint32_t k, uint32_t n)
{
	struct volume_image *img = &vol->images[k];
	if (n <= img->tile_cap)
		return 0;
	uint32_t cap = img->tile_cap ? img->tile_cap : 4;
	while (cap < n)
		cap *= 2;
	if (cap > volume_tiles_per_image(vol))
		cap = volume_tiles_per_image(vol);
	uint8_t *tiles = realloc(img->tiles, (size_t)cap * VOLUME_TILE_BYTES);
	if (!tiles)
		return -ENOMEM;
	img->tiles = tiles;
	img->tile_cap = cap;
	return 0;
}

bool volume_all_zero(const uint8_t *p, size_t n)
{
	uint64_t any = 0;
	size_t i = 0;
	for (; i + 8 <= n; i += 8) {
		uint64_t w;
		memcpy(&w, p + i, sizeof(w));
		any |= w;
	}
	for (; i < n; i++)
		any |= p[i];
	return any == 0;
}

int volume_image_append(struct volume *vol, uint32_t k, uint32_t t, const uint8_t *data)
{
	if (k >= vol->image_count || t >= volume_tiles_per_image(vol))
		return -EINVAL;
	struct volume_image *img = &vol->images[k];
	if (t < img->next_tile)
		return -EINVAL; /* out of order */
	if (volume_all_zero(data, VOLUME_TILE_BYTES))
		return 0;
	uint8_t *dst = volume_image_next(vol, k);
	if (!dst)
		return -ENOMEM;
	volume_tile_copy(dst, data);
	return volume_image_push(vol, k, t);
}

uint8_t *volume_image_next(struct volume *vol, uint32_t k)
{
	struct volume_image *img = &vol->images[k];
	if (volume_image_reserve(vol, k, img->tile_count + 1) < 0)
		return NULL;
	return img->tiles + (size_t)img->tile_count * VOLUME_TILE_BYTES;
}

int volume_image_push(struct volume *vol, uint32_t k, uint32_t t)
{
	if (k >= vol->image_count || t >= volume_tiles_per_image(vol))
		return -EINVAL;
	struct volume_image *img = &vol->images[k];
	if (t < img->next_tile || img->tile_count >= img->tile_cap)
		return -EINVAL;
	img->tile_count++;
	img->next_tile = t + 1;
	img->mask[t / 8] |= (uint8_t)(1u << (t % 8));
	img->stamp = 0;
	if (vol->origin) /* not written when it is already 0: the line stays shared */
		vol->origin = 0;
	return 0;
}

int volume_image_set(struct volume *vol, uint32_t k, const uint8_t *mask, uint32_t count)
{
	if (k >= vol->image_count)
		return -EINVAL;
	struct volume_image *img = &vol->images[k];
	uint32_t tiles = volume_tiles_per_image(vol), n = 0, last = 0;
	for (uint32_t i = 0; i < vol->mask_bytes; i++) {
		n += volume_mask_bits(mask[i]);
		if (mask[i])
			last = 8 * i + 31 - (uint32_t)__builtin_clz(mask[i]);
	}
	if (n != count || count > img->tile_cap || (count && last >= tiles))
		return -EINVAL;
	memcpy(img->mask, mask, vol->mask_bytes);
	img->tile_count = count;
	img->next_tile = count ? last + 1 : 0;
	img->stamp = 0;
	if (vol->origin)
		vol->origin = 0;
	return 0;
}

int volume_copy_image(struct volume *dst, uint32_t k, const struct volume *src)
{
	if (dst->image_count != src->image_count || dst->mask_bytes != src->mask_bytes || k >= src->image_count)
		return -EINVAL;
	const struct volume_image *s = &src->images[k];
	struct volume_image *d = &dst->images[k];
	int r = volume_image_reserve(dst, k, s->tile_count);
	if (r < 0)
		return r;
	memcpy(d->mask, s->mask, src->mask_bytes);
	if (s->tile_count)
		memcpy(d->tiles, s->tiles, (size_t)s->tile_count * VOLUME_TILE_BYTES);
	d->tile_count = s->tile_count;
	d->next_tile = s->next_tile;
	d->stamp = s->stamp;
	dst->origin = 0;
	return 0;
}

uint32_t volume_mask_count(const uint8_t *mask, size_t bytes)
{
	uint32_t n = 0;
	for (uint32_t w = 0; w < volume_mask_words((uint32_t)bytes); w++)
		n += volume_word_bits(volume_mask_word(mask, (uint32_t)bytes, w));
	return n;
}

uint32_t volume_stored_index(const uint8_t *mask, uint32_t t)
{
	uint32_t i = volume_mask_count(mask, t / 8);
	return t % 8 ? i + volume_mask_bits(mask[t / 8] & ((1u << (t % 8)) - 1)) : i;
}

/* The highest tile of a mask that is not empty. */
static uint32_t last_tile(const uint8_t *mask, uint32_t bytes)
{
	uint32_t b = bytes - 1;
	while (!mask[b])
		b--;
	return b * 8 + 31 - (uint32_t)__builtin_clz(mask[b]);
}

/* The bits of mask byte b that lie in tiles first..last. */
static uint8_t range_bits(uint32_t b, uint32_t first, uint32_t last)
{
	uint32_t lo = b * 8 < first ? first - b * 8 : 0, hi = b * 8 + 7 > last ? last - b * 8 : 7;
	return (uint8_t)(((2u << hi) - 1) & ~((1u << lo) - 1));
}

/* How many of tiles first..last mask holds. */
static uint32_t range_count(const uint8_t *mask, uint32_t first, uint32_t last)
{
	uint32_t n = 0;
	for (uint32_t b = first / 8; b <= last / 8; b++)
		n += volume_mask_bits(mask[b] & range_bits(b, first, last));
	return n;
}

int volume_image_splice(struct volume *vol, uint32_t k, uint32_t first, uint32_t last, const uint8_t *mask,
			const uint8_t *run)
{
	if (k >= vol->image_count || first > last || last >= volume_tiles_per_image(vol))
		return -EINVAL;
	struct volume_image *img = &vol->images[k];
	uint32_t at = volume_stored_index(img->mask, first), end = at + range_count(img->mask, first, last);
	uint32_t n = range_count(mask, first, last);
	uint32_t count = img->tile_count - (end - at) + n;
	int r = volume_image_reserve(vol, k, count);
	if (r < 0)
		return r;
	uint8_t *place = img->tiles + (size_t)at * VOLUME_TILE_BYTES;
	memmove(place + (size_t)n * VOLUME_TILE_BYTES, img->tiles + (size_t)end * VOLUME_TILE_BYTES,
		(size_t)(img->tile_count - end) * VOLUME_TILE_BYTES);
	memcpy(place, run, (size_t)n * VOLUME_TILE_BYTES);
	for (uint32_t b = first / 8; b <= last / 8; b++) {
		uint8_t m = range_bits(b, first, last);
		img->mask[b] = (uint8_t)((img->mask[b] & ~m) | (mask[b] & m));
	}
	img->tile_count = count;
	img->next_tile = count ? last_tile(img->mask, vol->mask_bytes) + 1 : 0;
	img->stamp = 0;
	vol->origin = 0;
	return 0;
}

int volume_copy(struct volume *dst, const struct volume *src)
{
	if (dst->image_count != src->image_count || dst->mask_bytes != src->mask_bytes)
		return -EINVAL;
	for (uint32_t k = 0; k < src->image_count; k++) {
		int r = volume_copy_image(dst, k, src);
		if (r < 0)
			return r;
	}
	dst->seq = src->seq;
	dst->shown_ns = src->shown_ns;
	dst->origin = 0;
	return 0;
}

size_t volume_dense_image_bytes(const struct volume *vol)
{
	return 3 * (size_t)vol->geom.height * geometry_row_bytes(&vol->geom);
}

void volume_image_to_dense(const struct volume *vol, uint32_t k, uint8_t *out)
{
	const struct volume_image *img = &vol->images[k];
	uint32_t rb = geometry_row_bytes(&vol->geom);
	uint32_t w = vol->geom.width, h = vol->geom.height;
	size_t plane = (size_t)h * rb;
	memset(out, 0, 3 * plane);
	const uint8_t *tile = img->tiles;
	for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
		if (!volume_tile_present(img, t))
			continue;
		uint32_t x0 = (t % vol->tiles_x) * VOLUME_TILE, y0 = (t / vol->tiles_x) * VOLUME_TILE;
		for (int c = 0; c < 3; c++) {
			const uint8_t *src = tile + c * VOLUME_TILE_PLANE_BYTES;
			for (uint32_t r = 0; r < VOLUME_TILE && y0 + r < h; r++) {
				uint8_t *dst = out + c * plane + (size_t)(y0 + r) * rb + x0 / 8;
				uint32_t n = (w - x0 + 7) / 8;
				if (n > 4)
					n = 4;
				memcpy(dst, src + r * 4, n);
			}
		}
		tile += VOLUME_TILE_BYTES;
	}
}

int volume_pixel(const struct volume *vol, uint32_t k, uint32_t u, uint32_t v, int c)
{
	const struct volume_image *img = &vol->images[k];
	uint32_t t = (v / VOLUME_TILE) * vol->tiles_x + u / VOLUME_TILE;
	if (!volume_tile_present(img, t))
		return 0;
	const uint8_t *plane = img->tiles + (size_t)volume_stored_index(img->mask, t) * VOLUME_TILE_BYTES +
			       c * VOLUME_TILE_PLANE_BYTES;
	uint32_t x = u % VOLUME_TILE, y = v % VOLUME_TILE;
	return (plane[y * 4 + x / 8] >> (7 - x % 8)) & 1;
}

uint64_t volume_tile_count(const struct volume *vol)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < vol->image_count; k++)
		n += vol->images[k].tile_count;
	return n;
}

uint64_t volume_sparse_bytes(const struct volume *vol)
{
	return (uint64_t)vol->image_count * vol->mask_bytes + volume_tile_count(vol) * VOLUME_TILE_BYTES;
}

uint64_t volume_held_bytes(const struct volume *vol)
{
	uint64_t b = (uint64_t)vol->image_count * (sizeof(*vol->images) + vol->mask_bytes);
	for (uint32_t k = 0; k < vol->image_count; k++)
		b += (uint64_t)vol->images[k].tile_cap * VOLUME_TILE_BYTES;
	return b;
}
