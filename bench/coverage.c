#include "coverage.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

/* Pixel windows are 34 bits, most significant first: bit 33 is the pixel
 * left of a tile, bits 32..1 the tile's 32 columns, bit 0 the pixel right
 * of it (the packed rows' MSB-first order, with one pixel either side). */
#define WINDOW_MASK ((UINT64_C(1) << 34) - 1)

/* Where each (image, tile) of a volume keeps its bytes (NULL: empty). */
struct tile_index {
	const struct volume *vol;
	int32_t tiles_x, tiles_y;
	uint32_t tiles;       /* per image */
	const uint8_t **tile; /* image_count * tiles */
};

static int index_build(struct tile_index *ix, const struct volume *vol)
{
	ix->vol = vol;
	ix->tiles_x = (int32_t)vol->tiles_x;
	ix->tiles_y = (int32_t)vol->tiles_y;
	ix->tiles = volume_tiles_per_image(vol);
	ix->tile = calloc((size_t)vol->image_count * ix->tiles, sizeof(*ix->tile));
	if (!ix->tile)
		return -ENOMEM;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const struct volume_image *img = &vol->images[k];
		const uint8_t *next = img->tiles;
		for (uint32_t t = 0; t < ix->tiles; t++) {
			if (!volume_tile_present(img, t))
				continue;
			ix->tile[(size_t)k * ix->tiles + t] = next;
			next += VOLUME_TILE_BYTES;
		}
	}
	return 0;
}

static const uint8_t *index_tile(const struct tile_index *ix, uint32_t k, int32_t tx, int32_t ty)
{
	if (tx < 0 || ty < 0 || tx >= ix->tiles_x || ty >= ix->tiles_y)
		return NULL;
	return ix->tile[(size_t)k * ix->tiles + (uint32_t)(ty * ix->tiles_x + tx)];
}

/* Row y of channel c of a packed tile, bit 31 = leftmost pixel. */
static inline uint32_t tile_row(const uint8_t *tile, int c, int y)
{
	if (!tile)
		return 0;
	const uint8_t *p = tile + c * VOLUME_TILE_PLANE_BYTES + y * 4;
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static uint64_t reverse34(uint64_t v)
{
	v = (v & 0x5555555555555555u) << 1 | ((v >> 1) & 0x5555555555555555u);
	v = (v & 0x3333333333333333u) << 2 | ((v >> 2) & 0x3333333333333333u);
	v = (v & 0x0f0f0f0f0f0f0f0fu) << 4 | ((v >> 4) & 0x0f0f0f0f0f0f0f0fu);
	v = __builtin_bswap64(v);
	return v >> 30;
}

/* Where the rows of one tile row of a neighbour image come from: three
 * consecutive tiles (96 pixels, MSB first) of which the window is bits
 * shift .. shift + 33, reversed for a mirrored neighbour. */
struct row_source {
	const uint8_t *tile[3];
	unsigned shift;
	bool reverse;
};

static int32_t floor_div32(int32_t a)
{
	return a >= 0 ? a / 32 : -((31 - a) / 32);
}

/* The source of the window around tile column tx (pixels 32 tx - 1 ..
 * 32 tx + 32) in tile row ty of image k, mirrored or not. */
static void row_source_init(struct row_source *s, const struct tile_index *ix, uint32_t k, bool mirror, int32_t tx,
			    int32_t ty)
{
	int32_t x0 = 32 * tx;
	/* First pixel of the window in image k's own columns: mirrored, the
	 * window's pixels x0 - 1 .. x0 + 32 are W - x0 .. W - x0 - 33. */
	int32_t a = mirror ? (int32_t)ix->vol->geom.width - x0 - 33 : x0 - 1;
	int32_t ta = floor_div32(a);
	for (int i = 0; i < 3; i++)
		s->tile[i] = index_tile(ix, k, ta + i, ty);
	s->shift = (unsigned)(62 - (a - 32 * ta));
	s->reverse = mirror;
}

static inline uint64_t row_source_fetch(const struct row_source *s, int c, int y)
{
	uint64_t hi = (uint64_t)tile_row(s->tile[0], c, y) << 32 | tile_row(s->tile[1], c, y);
	uint64_t lo = tile_row(s->tile[2], c, y);
	uint64_t v = s->shift <= 32 ? hi << (32 - s->shift) | lo >> s->shift : hi >> (s->shift - 32);
	v &= WINDOW_MASK;
	return s->reverse ? reverse34(v) : v;
}

/* Image k's neighbours across the revolution: k - 1, k, k + 1, and whether
 * each is seen mirrored (docs/design.md section 3, mirrored half turn). */
static void neighbours(const struct volume *vol, uint32_t k, uint32_t img[3], bool mirror[3])
{
	uint32_t n = vol->image_count;
	bool wrap_mirrors = vol->geom.mirrored;
	img[0] = k == 0 ? n - 1 : k - 1;
	mirror[0] = k == 0 && wrap_mirrors;
	img[1] = k;
	mirror[1] = false;
	img[2] = k + 1 == n ? 0 : k + 1;
	mirror[2] = k + 1 == n && wrap_mirrors;
}

/* The pixels of other within one voxel of tile (tx, ty) of image k, for each
 * channel: near[c][y] bit 31 - x is set when pixel (x, y) of the tile has a
 * lit voxel of other within one voxel. */
static void near_mask(const struct tile_index *other, uint32_t k, int32_t tx, int32_t ty, uint32_t near[3][32])
{
	uint32_t img[3];
	bool mirror[3];
	neighbours(other->vol, k, img, mirror);
	uint64_t rows[3][34] = { { 0 } }; /* tile rows -1 .. 32, all three images */
	for (int n = 0; n < 3; n++) {
		struct row_source src[3];
		for (int dy = 0; dy < 3; dy++)
			row_source_init(&src[dy], other, img[n], mirror[n], tx, ty + dy - 1);
		for (int c = 0; c < 3; c++) {
			rows[c][0] |= row_source_fetch(&src[0], c, 31);
			for (int y = 0; y < 32; y++)
				rows[c][y + 1] |= row_source_fetch(&src[1], c, y);
			rows[c][33] |= row_source_fetch(&src[2], c, 0);
		}
	}
	for (int c = 0; c < 3; c++) {
		uint32_t wide[34];
		for (int y = 0; y < 34; y++) {
			uint64_t r = rows[c][y];
			wide[y] = (uint32_t)((r | r << 1 | r >> 1) >> 1);
		}
		for (int y = 0; y < 32; y++)
			near[c][y] = wide[y] | wide[y + 1] | wide[y + 2];
	}
}

static void popcount_tile(const uint8_t *tile, uint64_t lit[3])
{
	for (int c = 0; c < 3; c++)
		for (int y = 0; y < 32; y++)
			lit[c] += (uint64_t)__builtin_popcount(tile_row(tile, c, y));
}

/* For every lit voxel of checked: counts it in lit, and in near when other
 * has a lit voxel within one voxel of it. */
static void count_near(const struct tile_index *checked, const struct tile_index *other, uint64_t lit[3],
		       uint64_t near_count[3])
{
	const struct volume *vol = checked->vol;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		for (uint32_t t = 0; t < checked->tiles; t++) {
			const uint8_t *tile = checked->tile[(size_t)k * checked->tiles + t];
			if (!tile)
				continue;
			popcount_tile(tile, lit);
			uint32_t near[3][32];
			near_mask(other, k, (int32_t)(t % vol->tiles_x), (int32_t)(t / vol->tiles_x), near);
			for (int c = 0; c < 3; c++)
				for (int y = 0; y < 32; y++)
					near_count[c] +=
						(uint64_t)__builtin_popcount(tile_row(tile, c, y) & near[c][y]);
		}
	}
}

static bool tile_equal(const uint8_t *a, const uint8_t *b)
{
	static const uint8_t zero[VOLUME_TILE_BYTES];
	return memcmp(a ? a : zero, b ? b : zero, VOLUME_TILE_BYTES) == 0;
}

static bool volumes_equal(const struct tile_index *a, const struct tile_index *b)
{
	size_t n = (size_t)a->vol->image_count * a->tiles;
	for (size_t i = 0; i < n; i++)
		if ((a->tile[i] || b->tile[i]) && !tile_equal(a->tile[i], b->tile[i]))
			return false;
	return true;
}

static bool same_geometry(const struct volume *a, const struct volume *b)
{
	return a->geom.width == b->geom.width && a->geom.height == b->geom.height &&
	       a->geom.images_per_rev == b->geom.images_per_rev && a->geom.mirrored == b->geom.mirrored &&
	       a->image_count == b->image_count;
}

int coverage_compare(const struct volume *ref, const struct volume *test, struct coverage *out)
{
	memset(out, 0, sizeof(*out));
	if (!same_geometry(ref, test))
		return -EINVAL;
	struct tile_index a, b;
	int r = index_build(&a, ref);
	if (r == 0 && (r = index_build(&b, test)) < 0)
		free(a.tile);
	if (r < 0)
		return r;
	out->identical = volumes_equal(&a, &b);
	uint64_t test_near[3] = { 0 };
	count_near(&a, &b, out->ref_lit, out->ref_covered);
	count_near(&b, &a, out->test_lit, test_near);
	for (int c = 0; c < 3; c++)
		out->test_stray[c] = out->test_lit[c] - test_near[c];
	free(a.tile);
	free(b.tile);
	return 0;
}

static uint64_t sum3(const uint64_t v[3])
{
	return v[0] + v[1] + v[2];
}

double coverage_score(const struct coverage *c)
{
	uint64_t lit = sum3(c->ref_lit);
	return lit ? (double)sum3(c->ref_covered) / (double)lit : 1.0;
}

double coverage_stray(const struct coverage *c)
{
	uint64_t lit = sum3(c->test_lit);
	return lit ? (double)sum3(c->test_stray) / (double)lit : 0.0;
}
