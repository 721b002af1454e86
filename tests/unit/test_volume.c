/* common/volume: tile layout (planes R, G, B of 32 rows of 4 bytes, MSB
 * leftmost; mask bit t at byte t / 8, bit t % 8; tiles in increasing t),
 * append rules, dense round trips, and edge tiles of images whose size is
 * not a multiple of 32 (or of 8). */
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "volume.h"

static const struct geometry odd = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };

static uint32_t lcg(uint32_t *s)
{
	*s = *s * 1664525u + 1013904223u;
	return *s >> 8;
}

/* Sets pixel (x, y) of channel c in a tile buffer. */
static void tile_set(uint8_t *tile, uint32_t x, uint32_t y, int c)
{
	tile[c * VOLUME_TILE_PLANE_BYTES + y * 4 + x / 8] |= (uint8_t)(0x80u >> (x % 8));
}

static void check_create(void)
{
	struct volume *v = volume_create(&odd);
	CHECK(v && v->image_count == 50 && v->tiles_x == 4 && v->tiles_y == 3 && v->mask_bytes == 2);
	CHECK(volume_tiles_per_image(v) == 12);
	CHECK(volume_dense_image_bytes(v) == 3 * 72 * 13);
	CHECK(volume_tile_count(v) == 0 && volume_sparse_bytes(v) == 50 * 2);
	volume_destroy(v);
	struct geometry g;
	geometry_from_profile("perspecta", &g);
	v = volume_create(&g);
	CHECK(v && v->image_count == 198 && v->tiles_x == 24 && v->mask_bytes == 72);
	volume_destroy(v);
	g.images_per_rev = 397;
	errno = 0;
	CHECK(volume_create(&g) == NULL && errno == EINVAL);
	volume_destroy(NULL);
}

static void check_append(void)
{
	struct volume *v = volume_create(&odd);
	uint8_t tile[VOLUME_TILE_BYTES] = { 0 };
	CHECK(volume_image_append(v, 3, 2, tile) == 0); /* all zero: skipped */
	CHECK(v->images[3].tile_count == 0 && v->images[3].mask[0] == 0);
	tile_set(tile, 0, 0, 0);
	CHECK(volume_image_append(v, 3, 9, tile) == 0);
	CHECK(v->images[3].tile_count == 1 && v->images[3].mask[1] == 0x02 && v->images[3].mask[0] == 0);
	CHECK(volume_tile_present(&v->images[3], 9));
	CHECK(volume_image_append(v, 3, 5, tile) == -EINVAL);  /* out of order */
	CHECK(volume_image_append(v, 3, 9, tile) == -EINVAL);  /* repeated */
	CHECK(volume_image_append(v, 3, 12, tile) == -EINVAL); /* past the image */
	CHECK(volume_image_append(v, 50, 0, tile) == -EINVAL);
	CHECK(volume_image_append(v, 3, 11, tile) == 0);
	CHECK(v->images[3].mask[1] == 0x0a && v->images[3].tile_count == 2);
	CHECK(volume_tile_count(v) == 2 && volume_sparse_bytes(v) == 100 + 2 * 384);
	volume_clear(v);
	CHECK(volume_tile_count(v) == 0 && v->images[3].mask[1] == 0);
	CHECK(volume_image_append(v, 3, 0, tile) == 0);
	volume_destroy(v);
}

/* volume_image_set(): an image written in place and set at once is the
 * image appended tile by tile; a count that is not the mask's, more than
 * the room, or a mask past the image is refused and changes nothing. */
static void check_set(void)
{
	struct volume *a = volume_create(&odd), *b = volume_create(&odd);
	uint8_t tile[VOLUME_TILE_BYTES] = { 0 }, mask[2] = { 0x21, 0x08 }; /* tiles 0, 5, 11 */
	const uint32_t at[3] = { 0, 5, 11 };
	CHECK(volume_image_reserve(b, 7, 3) == 0);
	for (int i = 0; i < 3; i++) {
		memset(tile, 0, sizeof(tile));
		tile_set(tile, (uint32_t)i, 2, i);
		CHECK(volume_image_append(a, 7, at[i], tile) == 0);
		memcpy(b->images[7].tiles + (size_t)i * VOLUME_TILE_BYTES, tile, VOLUME_TILE_BYTES);
	}
	b->origin = 5;
	CHECK(volume_image_set(b, 7, mask, 2) == -EINVAL); /* not the mask's count */
	CHECK(volume_image_set(b, 7, mask, 4) == -EINVAL);
	uint8_t past[2] = { 0x21, 0x18 }; /* tile 12: past the image's 12 */
	CHECK(volume_image_set(b, 7, past, 4) == -EINVAL);
	CHECK(volume_image_set(b, 50, mask, 3) == -EINVAL);
	CHECK(b->images[7].tile_count == 0 && b->images[7].mask[0] == 0 && b->origin == 5);
	CHECK(volume_image_set(b, 7, mask, 3) == 0);
	CHECK(b->origin == 0 && b->images[7].tile_count == 3 && b->images[7].next_tile == 12);
	CHECK(memcmp(a->images[7].mask, b->images[7].mask, 2) == 0);
	CHECK(memcmp(a->images[7].tiles, b->images[7].tiles, 3 * VOLUME_TILE_BYTES) == 0);
	CHECK(volume_image_append(b, 7, 10, tile) == -EINVAL); /* in order after them */
	uint8_t few[2] = { 0x01, 0 }, none[2] = { 0, 0 };
	CHECK(volume_image_set(b, 8, few, 1) == -EINVAL); /* no room made */
	CHECK(volume_image_set(b, 7, none, 0) == 0);
	CHECK(b->images[7].tile_count == 0 && b->images[7].next_tile == 0 && volume_tile_count(b) == 0);
	volume_destroy(a);
	volume_destroy(b);
}

/* Random pixels into image k, tile by tile (never past W or H). Returns the
 * expected image as one byte per pixel and channel. */
static uint8_t *fill_random(struct volume *v, uint32_t k, uint32_t seed)
{
	uint32_t w = v->geom.width, h = v->geom.height;
	uint8_t *want = calloc((size_t)3 * w * h, 1);
	for (uint32_t t = 0; t < volume_tiles_per_image(v); t++) {
		uint8_t tile[VOLUME_TILE_BYTES] = { 0 };
		uint32_t x0 = (t % v->tiles_x) * 32, y0 = (t / v->tiles_x) * 32;
		bool empty = lcg(&seed) % 3 == 0;
		for (uint32_t y = 0; y < 32 && y0 + y < h && !empty; y++)
			for (uint32_t x = 0; x < 32 && x0 + x < w; x++)
				for (int c = 0; c < 3; c++)
					if (lcg(&seed) % 5 == 0) {
						tile_set(tile, x, y, c);
						want[((size_t)c * h + y0 + y) * w + x0 + x] = 1;
					}
		CHECK(volume_image_append(v, k, t, tile) == 0);
	}
	return want;
}

static void check_pixels_and_dense(const struct geometry *g)
{
	struct volume *v = volume_create(g);
	uint32_t k = v->image_count - 1, w = g->width, h = g->height, rb = geometry_row_bytes(g);
	uint8_t *want = fill_random(v, k, 99);
	uint8_t *dense = malloc(volume_dense_image_bytes(v));
	memset(dense, 0xee, volume_dense_image_bytes(v));
	volume_image_to_dense(v, k, dense);
	for (int c = 0; c < 3; c++)
		for (uint32_t y = 0; y < h; y++) {
			for (uint32_t x = 0; x < w; x++) {
				int bit = (dense[((size_t)c * h + y) * rb + x / 8] >> (7 - x % 8)) & 1;
				int px = want[((size_t)c * h + y) * w + x];
				CHECK(bit == px);
				CHECK(volume_pixel(v, k, x, y, c) == px);
			}
			for (uint32_t x = w; x < rb * 8; x++) /* row padding stays 0 */
				CHECK(((dense[((size_t)c * h + y) * rb + x / 8] >> (7 - x % 8)) & 1) == 0);
		}
	struct volume *copy = volume_create(g);
	CHECK(volume_copy(copy, v) == 0);
	CHECK(copy->images[k].tile_count == v->images[k].tile_count);
	CHECK(memcmp(copy->images[k].tiles, v->images[k].tiles, (size_t)v->images[k].tile_count * 384) == 0);
	CHECK(volume_pixel(copy, k, w - 1, h - 1, 2) == want[((size_t)2 * h + h - 1) * w + w - 1]);
	volume_destroy(copy);
	free(dense);
	free(want);
	volume_destroy(v);
}

/* Image 0 of v: each tile present with probability 1 / 2 (keep: the
 * tiles of base outside change stay as base has them), its bytes from
 * seed. */
static void random_image(struct volume *v, const struct volume *base, const uint8_t *change, uint32_t *seed)
{
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_image_clear(v, 0);
	for (uint32_t t = 0; t < volume_tiles_per_image(v); t++) {
		bool keep = base && !((change[t / 8] >> (t % 8)) & 1);
		if (keep && !volume_tile_present(&base->images[0], t))
			continue;
		if (keep) {
			uint32_t i = volume_stored_index(base->images[0].mask, t);
			CHECK(volume_image_append(v, 0, t, base->images[0].tiles + (size_t)i * VOLUME_TILE_BYTES) == 0);
			continue;
		}
		if (lcg(seed) % 2)
			continue;
		for (size_t i = 0; i < sizeof(tile); i++)
			tile[i] = (uint8_t)lcg(seed);
		tile[0] |= 1;
		CHECK(volume_image_append(v, 0, t, tile) == 0);
	}
}

/* Image 0 of from brought to image 0 of to, which differs at most in the
 * tiles set in change, as the compositor patches an image in place: the
 * tiles from the first whose presence differs to the last spliced in
 * (volume_image_splice()), the other changed ones written over. */
static void update_image(struct volume *from, const struct volume *to, const uint8_t *change)
{
	const struct volume_image *y = &to->images[0];
	struct volume_image *x = &from->images[0];
	uint32_t tiles = volume_tiles_per_image(to), first = tiles, last = 0;
	for (uint32_t t = 0; t < tiles; t++)
		if (volume_tile_present(x, t) != volume_tile_present(y, t)) {
			first = first < t ? first : t;
			last = t;
		}
	if (first < tiles) {
		const uint8_t *run = y->tiles + (size_t)volume_stored_index(y->mask, first) * VOLUME_TILE_BYTES;
		CHECK(volume_image_splice(from, 0, first, last, y->mask, run) == 0);
	}
	for (uint32_t t = 0; t < tiles; t++) {
		if (!((change[t / 8] >> (t % 8)) & 1) || !volume_tile_present(y, t) || (t >= first && t <= last))
			continue;
		size_t at = (size_t)volume_stored_index(y->mask, t) * VOLUME_TILE_BYTES;
		memcpy(x->tiles + at, y->tiles + at, VOLUME_TILE_BYTES);
	}
}

/* Splicing: an image brought to another that differs in some tiles
 * (present in one only, or both with other bytes), the changed mask
 * holding those and some others, is that image: mask, count, next tile,
 * bytes. */
static void check_update(const struct geometry *g)
{
	struct volume *from = volume_create(g), *to = volume_create(g);
	CHECK(from && to);
	uint32_t seed = 5, tiles = volume_tiles_per_image(from);
	uint8_t change[128];
	CHECK(from->mask_bytes <= sizeof(change));
	for (int round = 0; round < 400; round++) {
		memset(change, 0, sizeof(change));
		uint32_t spread = 1 + lcg(&seed) % tiles, at = lcg(&seed) % tiles;
		for (uint32_t n = lcg(&seed) % 6; n > 0; n--) { /* a few tiles near one another, or anywhere */
			uint32_t t = (at + lcg(&seed) % spread) % tiles;
			change[t / 8] |= (uint8_t)(1u << (t % 8));
		}
		if (round % 5 == 0) /* sometimes every tile */
			memset(change, 0xff, from->mask_bytes);
		random_image(from, NULL, NULL, &seed);
		random_image(to, from, change, &seed);
		for (uint32_t t = 0; t < tiles; t++) /* and some that did not change */
			if (lcg(&seed) % 8 == 0)
				change[t / 8] |= (uint8_t)(1u << (t % 8));
		for (uint32_t b = 0; round % 5 && b < from->mask_bytes; b++)
			change[b] &= (uint8_t)((1u << (tiles - b * 8 < 8 ? tiles - b * 8 : 8)) - 1);
		update_image(from, to, change);
		const struct volume_image *x = &from->images[0], *y = &to->images[0];
		CHECK(x->tile_count == y->tile_count && x->next_tile == y->next_tile);
		CHECK(memcmp(x->mask, y->mask, from->mask_bytes) == 0);
		CHECK(memcmp(x->tiles, y->tiles, (size_t)y->tile_count * VOLUME_TILE_BYTES) == 0);
	}
	CHECK(volume_stored_index(to->images[0].mask, tiles) == to->images[0].tile_count);
	volume_destroy(from);
	volume_destroy(to);
}

/* volume_stored_index() against a bit-by-bit count, for every tile of
 * random masks up to perspecta's 576 tiles (its word loop and the bytes
 * after it). */
static void check_stored_index(void)
{
	uint8_t mask[80];
	uint32_t seed = 11;
	for (int round = 0; round < 50; round++) {
		for (size_t b = 0; b < sizeof(mask); b++)
			mask[b] = round % 7 == 0 ? 0xff : (uint8_t)lcg(&seed);
		uint32_t want = 0;
		for (uint32_t t = 0; t <= 8 * sizeof(mask); t++) {
			CHECK_EQ(volume_stored_index(mask, t), want);
			want += t < 8 * sizeof(mask) && (mask[t / 8] >> (t % 8)) & 1;
		}
	}
}

int main(void)
{
	struct geometry small;
	geometry_from_profile("small", &small);
	check_create();
	check_append();
	check_set();
	check_stored_index();
	check_pixels_and_dense(&odd);
	check_pixels_and_dense(&small);
	check_update(&odd);
	check_update(&small);
	return check_done();
}
