/* volume_shift(): a volume moved by whole pixels (calibration.h's axis
 * offset), tile by tile: each tile of the result takes its rows from at
 * most four tiles of the source, two across and two down, and only the
 * result tiles some stored source tile reaches are made, so that a shift
 * costs the source's tiles. */
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "volume.h"

/* Rows of the big-endian 32-bit words, as numbers. */
static inline uint32_t be32_load(const uint8_t *p)
{
	uint32_t v;
	memcpy(&v, p, sizeof(v));
	return __builtin_bswap32(v);
}

static inline void be32_store(uint8_t *p, uint32_t v)
{
	v = __builtin_bswap32(v);
	memcpy(p, &v, sizeof(v));
}

static const uint8_t dark_tile[VOLUME_TILE_BYTES];

/* Where one plane of a result tile comes from: its row i is row ry + i of
 * the top tiles (left a, right b), or past their end row ry + i - 32 of the
 * bottom ones, taken from pixel r on. */
struct plane_source {
	const uint8_t *ta, *tb, *ba, *bb;
	unsigned ry, r;
	uint32_t mask; /* columns inside the image */
};

static inline uint32_t shift_row(const struct plane_source *p, unsigned i)
{
	unsigned row = p->ry + i;
	const uint8_t *a = row < VOLUME_TILE ? p->ta : p->ba, *b = row < VOLUME_TILE ? p->tb : p->bb;
	row %= VOLUME_TILE;
	uint64_t pair = (uint64_t)be32_load(a + 4 * row) << 32 | be32_load(b + 4 * row);
	return (uint32_t)(pair << p->r >> 32) & p->mask;
}

/* The plane's 32 rows into out; returns their OR. */
static uint32_t shift_plane_scalar(uint8_t *out, const struct plane_source *p)
{
	uint32_t any = 0;
	for (unsigned i = 0; i < VOLUME_TILE; i++) {
		uint32_t w = shift_row(p, i);
		be32_store(out + 4 * i, w);
		any |= w;
	}
	return any;
}

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define SHIFT_AVX2 1

/* 8 rows from source row row on of tiles top and bottom (row + 8 past the
 * top's end: the block that crosses into the bottom tile), as numbers. */
__attribute__((target("avx2"))) static inline __m256i rows8(const uint8_t *top, const uint8_t *bottom, unsigned row,
							    __m256i swap)
{
	if (row + 8 <= VOLUME_TILE)
		return _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(top + 4 * row)), swap);
	if (row >= VOLUME_TILE)
		return _mm256_shuffle_epi8(_mm256_loadu_si256((const __m256i *)(bottom + 4 * (row - VOLUME_TILE))),
					   swap);
	/* Lane k: top row row + k while that is in the top tile, else bottom
	 * row row + k - 32; both are lane (t + k) & 7 of the last 8 rows of the
	 * top and the first 8 of the bottom, t = row - 24. */
	const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
	int t = (int)row - (VOLUME_TILE - 8);
	__m256i idx = _mm256_and_si256(_mm256_add_epi32(iota, _mm256_set1_epi32(t)), _mm256_set1_epi32(7));
	__m256i hi =
		_mm256_permutevar8x32_epi32(_mm256_loadu_si256((const __m256i *)(top + 4 * (VOLUME_TILE - 8))), idx);
	__m256i lo = _mm256_permutevar8x32_epi32(_mm256_loadu_si256((const __m256i *)bottom), idx);
	__m256i from_top = _mm256_cmpgt_epi32(_mm256_set1_epi32(8 - t), iota);
	return _mm256_shuffle_epi8(_mm256_blendv_epi8(lo, hi, from_top), swap);
}

/* The same, 8 rows at a time. */
__attribute__((target("avx2"))) static uint32_t shift_plane_avx2(uint8_t *out, const struct plane_source *p)
{
	const __m256i swap = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5,
					      4, 11, 10, 9, 8, 15, 14, 13, 12);
	const __m128i left = _mm_cvtsi32_si128((int)p->r), right = _mm_cvtsi32_si128((int)(VOLUME_TILE - p->r));
	const __m256i mask = _mm256_set1_epi32((int)p->mask);
	__m256i acc = _mm256_setzero_si256();
	for (unsigned i0 = 0; i0 < VOLUME_TILE; i0 += 8) {
		__m256i va = rows8(p->ta, p->ba, p->ry + i0, swap), vb = rows8(p->tb, p->bb, p->ry + i0, swap);
		__m256i w = _mm256_and_si256(_mm256_or_si256(_mm256_sll_epi32(va, left), _mm256_srl_epi32(vb, right)),
					     mask);
		acc = _mm256_or_si256(acc, w);
		_mm256_storeu_si256((__m256i *)(out + 4 * i0), _mm256_shuffle_epi8(w, swap));
	}
	return (uint32_t)!_mm256_testz_si256(acc, acc);
}
#endif

typedef uint32_t (*shift_plane_fn)(uint8_t *out, const struct plane_source *p);

/* floor(a / VOLUME_TILE) for negative a too. */
static inline int64_t tile_of(int64_t a)
{
	return a >= 0 ? a / VOLUME_TILE : -((-a + VOLUME_TILE - 1) / VOLUME_TILE);
}

struct shift_image {
	shift_plane_fn plane;
	const struct volume *src;
	const uint8_t **tile; /* per tile number: its bytes in the source, or NULL */
	uint64_t *reach;      /* the result tiles a stored source tile reaches (volume_mask_word()'s words) */
	uint16_t *col, *row;  /* per tile number: its tile column and row (geometry.h bounds the size) */
	/* A source tile at (x, y) reaches the result tiles x + ox[i], y + oy[j]
	 * (i < nx, j < ny) that lie in the image: two across where the shift
	 * is not whole tiles, else one; the same down. */
	int32_t ox[2], oy[2];
	unsigned nx, ny;
	int64_t du, dv;
};

/* The source tile at (tx, ty), or NULL: outside the image or not stored. */
static const uint8_t *source_tile(const struct shift_image *s, int64_t tx, int64_t ty)
{
	if (tx < 0 || ty < 0 || tx >= s->src->tiles_x || ty >= s->src->tiles_y)
		return NULL;
	return s->tile[ty * s->src->tiles_x + tx];
}

/* Fills out with tile (tx, ty) of the shifted image. Returns whether any
 * bit is set; false without writing when no source tile reaches it. */
static bool shift_tile(const struct shift_image *s, uint32_t tx, uint32_t ty, uint8_t *out)
{
	const struct geometry *g = &s->src->geom;
	int64_t sx = (int64_t)tx * VOLUME_TILE - s->du, sy = (int64_t)ty * VOLUME_TILE - s->dv;
	int64_t stx = tile_of(sx), sty = tile_of(sy);
	unsigned r = (unsigned)(sx - stx * VOLUME_TILE), ry = (unsigned)(sy - sty * VOLUME_TILE);
	/* The tiles the rows come from: top left and right, bottom left and
	 * right. */
	const uint8_t *tl = source_tile(s, stx, sty), *tr = r ? source_tile(s, stx + 1, sty) : NULL;
	const uint8_t *bl = ry ? source_tile(s, stx, sty + 1) : NULL,
		      *br = r && ry ? source_tile(s, stx + 1, sty + 1) : NULL;
	if (!tl && !tr && !bl && !br)
		return false;
	uint32_t x_end = g->width - tx * VOLUME_TILE, y_end = g->height - ty * VOLUME_TILE;
	struct plane_source p = {
		.ry = ry,
		.r = r,
		.mask = x_end >= VOLUME_TILE ? UINT32_MAX : ~(UINT32_MAX >> x_end),
	};
	uint32_t any = 0;
	for (unsigned c = 0; c < 3; c++) {
		size_t plane = (size_t)c * VOLUME_TILE_PLANE_BYTES;
		p.ta = (tl ? tl : dark_tile) + plane, p.tb = (tr ? tr : dark_tile) + plane;
		p.ba = (bl ? bl : dark_tile) + plane, p.bb = (br ? br : dark_tile) + plane;
		any |= s->plane(out + plane, &p);
	}
	if (y_end < VOLUME_TILE) { /* rows past H stay dark (volume.h) */
		any = 0;
		for (unsigned c = 0; c < 3; c++) {
			uint8_t *plane = out + (size_t)c * VOLUME_TILE_PLANE_BYTES;
			memset(plane + 4 * y_end, 0, 4 * (VOLUME_TILE - y_end));
			for (unsigned i = 0; i < 4 * y_end; i++)
				any |= plane[i];
		}
	}
	return any != 0;
}

/* The tiles (1 or 2) that a tile's pixels reach across a row (or down a
 * column) moved by d pixels, as offsets from its own: o[0 .. *n). */
static void reach_offsets(int64_t d, int32_t o[2], unsigned *n)
{
	o[0] = (int32_t)tile_of(d);
	o[1] = (int32_t)tile_of(d + VOLUME_TILE - 1);
	*n = o[1] == o[0] ? 1 : 2;
}

/* Marks in s->reach the result tiles that tile t of the source reaches. */
static void mark_reach(struct shift_image *s, uint32_t t)
{
	const struct volume *src = s->src;
	for (unsigned j = 0; j < s->ny; j++) {
		int64_t y = (int64_t)s->row[t] + s->oy[j];
		if (y < 0 || y >= src->tiles_y)
			continue;
		for (unsigned i = 0; i < s->nx; i++) {
			int64_t x = (int64_t)s->col[t] + s->ox[i];
			if (x < 0 || x >= src->tiles_x)
				continue;
			uint32_t r = (uint32_t)y * src->tiles_x + (uint32_t)x;
			s->reach[r / 64] |= 1ull << (r % 64);
		}
	}
}

/* Points s->tile at image k's stored tiles and marks in s->reach the
 * result tiles each reaches; with clear, undoes both instead. */
static void index_image(struct shift_image *s, const struct volume_image *img, bool clear)
{
	const struct volume *src = s->src;
	const uint8_t *next = img->tiles;
	for (uint32_t x = 0; x < volume_mask_words(src->mask_bytes); x++) {
		if (clear)
			s->reach[x] = 0;
		for (uint64_t m = volume_mask_word(img->mask, src->mask_bytes, x); m; m &= m - 1) {
			uint32_t t = 64 * x + (uint32_t)__builtin_ctzll(m);
			s->tile[t] = clear ? NULL : next;
			next += VOLUME_TILE_BYTES;
			if (!clear)
				mark_reach(s, t);
		}
	}
}

/* Image k of dst becomes image k of s->src shifted: only the result tiles
 * a stored source tile reaches are made, so that the cost is the
 * source's tiles, not the image's. */
static int shift_image(struct volume *dst, uint32_t k, struct shift_image *s)
{
	const struct volume *src = s->src;
	const struct volume_image *img = &src->images[k];
	volume_image_clear(dst, k);
	if (!img->tile_count)
		return 0;
	index_image(s, img, false);
	int r = 0;
	for (uint32_t x = 0; x < volume_mask_words(src->mask_bytes) && !r; x++)
		for (uint64_t m = s->reach[x]; m && !r; m &= m - 1) {
			uint32_t t = 64 * x + (uint32_t)__builtin_ctzll(m);
			uint8_t *out = volume_image_next(dst, k);
			if (!out)
				r = -ENOMEM;
			else if (shift_tile(s, s->col[t], s->row[t], out))
				r = volume_image_push(dst, k, t);
		}
	index_image(s, img, true);
	return r;
}

static bool same_tiling(const struct volume *dst, const struct volume *src)
{
	return dst != src && dst->image_count == src->image_count && dst->tiles_x == src->tiles_x &&
	       dst->tiles_y == src->tiles_y && dst->geom.width == src->geom.width &&
	       dst->geom.height == src->geom.height;
}

static void shift_end(struct shift_image *s)
{
	free(s->tile);
	free(s->reach);
	free(s->col);
	free(s->row);
}

static int shift_begin(struct shift_image *s, const struct volume *src, int32_t du, int32_t dv, shift_plane_fn plane)
{
	const uint32_t tiles = volume_tiles_per_image(src);
	*s = (struct shift_image){ .src = src, .du = du, .dv = dv, .plane = plane };
	s->tile = calloc(tiles, sizeof(*s->tile));
	s->reach = calloc(volume_mask_words(src->mask_bytes), sizeof(*s->reach));
	s->col = malloc(tiles * sizeof(*s->col));
	s->row = malloc(tiles * sizeof(*s->row));
	if (!s->tile || !s->reach || !s->col || !s->row) {
		shift_end(s);
		return -ENOMEM;
	}
	for (uint32_t t = 0; t < tiles; t++) {
		s->col[t] = (uint16_t)(t % src->tiles_x);
		s->row[t] = (uint16_t)(t / src->tiles_x);
	}
	reach_offsets(du, s->ox, &s->nx);
	reach_offsets(dv, s->oy, &s->ny);
	return 0;
}

static shift_plane_fn best_plane(void)
{
#ifdef SHIFT_AVX2
	__builtin_cpu_init();
	if (__builtin_cpu_supports("avx2"))
		return shift_plane_avx2;
#endif
	return shift_plane_scalar;
}

static int shift_with(struct volume *dst, const struct volume *src, int32_t du, int32_t dv, shift_plane_fn plane)
{
	if (!same_tiling(dst, src))
		return -EINVAL;
	struct shift_image s;
	int r = shift_begin(&s, src, du, dv, plane);
	if (r < 0)
		return r;
	for (uint32_t k = 0; k < src->image_count && !r; k++)
		r = shift_image(dst, k, &s);
	shift_end(&s);
	dst->seq = src->seq;
	dst->shown_ns = src->shown_ns;
	dst->origin = 0;
	return r;
}

int volume_shift(struct volume *dst, const struct volume *src, int32_t du, int32_t dv)
{
	return shift_with(dst, src, du, dv, best_plane());
}

int volume_shift_scalar(struct volume *dst, const struct volume *src, int32_t du, int32_t dv)
{
	return shift_with(dst, src, du, dv, shift_plane_scalar);
}
