#include "halftone.h"

#include <pthread.h>
#include <stddef.h>
#include <string.h>

#include "volume.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define HALFTONE_X86 1
#endif

/* Entry (x, y) of the 16x16 Bayer index matrix, 0..255: bit-reverse of the
 * interleaved bits of x ^ y and y (recursive Bayer construction). */
static unsigned bayer16(unsigned x, unsigned y)
{
	unsigned a = (x ^ y) & 15, b = y & 15, v = 0;
	for (int i = 0; i < 4; i++) {
		v |= ((a >> i) & 1u) << (7 - 2 * i);
		v |= ((b >> i) & 1u) << (6 - 2 * i);
	}
	return v;
}

uint8_t halftone_threshold(uint32_t k, uint32_t u, uint32_t v)
{
	/* Phase: image k shifts the matrix by p = 97 k mod 256 (x by p % 16, y
	 * by p / 16). 97 is odd, so any 256 consecutive images all differ, and
	 * neighbouring images are offset by (1, 6): no two adjacent slices light
	 * the same pixels of a mid-grey area. */
	uint32_t p = (k * 97u) & 255u;
	unsigned idx = bayer16((u + (p & 15u)) & 15u, (v + (p >> 4)) & 15u);
	/* 0..255 -> 0..254, so 0 is never lit and 255 always. */
	return (uint8_t)((idx * 255u) >> 8);
}

void halftone_table_init(struct halftone_table *t, uint32_t k)
{
	/* Tile origins are multiples of 32, so a tile's local coordinates
	 * have the image's phase. */
	for (uint32_t y = 0; y < 16; y++)
		for (uint32_t x = 0; x < HALFTONE_ROW_BYTES; x++)
			t->thr[y][halftone_pos(x)] = halftone_threshold(k, x, y);
}

/* The packed row is the little-endian 32-bit word whose bit j says whether
 * canvas byte j beats its threshold: byte j holds pixel x = j ^ 7, which
 * packs into byte x / 8 = j / 8 at bit 7 - x % 8 = j % 8. */
static inline void put_row(uint8_t *out, uint32_t word)
{
	out[0] = (uint8_t)word;
	out[1] = (uint8_t)(word >> 8);
	out[2] = (uint8_t)(word >> 16);
	out[3] = (uint8_t)(word >> 24);
}

/* One variant: every row set in rows, in all three planes, through
 * row_word (the packed word of a 32-byte canvas row against its 32
 * thresholds); everything else comes out zero. */
#define HALFTONE_BY_ROWS(name, attrs, row_word)                                                                      \
	attrs static int name(const uint8_t *canvas, uint32_t rows, const struct halftone_table *t, uint8_t *out)    \
	{                                                                                                            \
		uint32_t any = 0;                                                                                    \
		volume_tile_zero(out);                                                                               \
		for (; rows; rows &= rows - 1) {                                                                     \
			uint32_t y = (uint32_t)__builtin_ctz(rows);                                                  \
			for (int c = 0; c < 3; c++) {                                                                \
				uint32_t word = row_word(canvas + c * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES, \
							 t->thr[y & 15]);                                            \
				put_row(out + c * VOLUME_TILE_PLANE_BYTES + y * 4, word);                            \
				any |= word;                                                                         \
			}                                                                                            \
		}                                                                                                    \
		return any != 0;                                                                                     \
	}

static inline uint32_t row_scalar(const uint8_t *row, const uint8_t *thr)
{
	uint32_t word = 0;
	for (uint32_t j = 0; j < 32; j++)
		word |= (uint32_t)(row[j] > thr[j]) << j;
	return word;
}

HALFTONE_BY_ROWS(halftone_scalar, , row_scalar)

#ifdef HALFTONE_X86
/* c > t for unsigned bytes is "c - t saturated is not zero". */
__attribute__((target("sse2"))) static inline uint32_t row_sse2(const uint8_t *row, const uint8_t *thr)
{
	const __m128i zero = _mm_setzero_si128();
	__m128i a = _mm_loadu_si128((const __m128i *)row);
	__m128i b = _mm_loadu_si128((const __m128i *)(row + 16));
	__m128i ta = _mm_loadu_si128((const __m128i *)thr);
	__m128i tb = _mm_loadu_si128((const __m128i *)(thr + 16));
	uint32_t lo = (uint32_t)_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(a, ta), zero));
	uint32_t hi = (uint32_t)_mm_movemask_epi8(_mm_cmpeq_epi8(_mm_subs_epu8(b, tb), zero));
	return ~(lo | hi << 16);
}

HALFTONE_BY_ROWS(halftone_sse2, __attribute__((target("sse2"))), row_sse2)

__attribute__((target("avx2"))) static inline uint32_t row_avx2(const uint8_t *row, const uint8_t *thr)
{
	__m256i a = _mm256_loadu_si256((const __m256i *)row);
	__m256i th = _mm256_loadu_si256((const __m256i *)thr);
	return ~(uint32_t)_mm256_movemask_epi8(_mm256_cmpeq_epi8(_mm256_subs_epu8(a, th), _mm256_setzero_si256()));
}

HALFTONE_BY_ROWS(halftone_avx2, __attribute__((target("avx2"))), row_avx2)

/* Two rows at a time: rows y and y + 1 (y even) are 64 contiguous bytes in
 * the canvas and in the table. */
__attribute__((target("avx512f,avx512bw"))) static int halftone_avx512(const uint8_t *canvas, uint32_t rows,
								       const struct halftone_table *t, uint8_t *out)
{
	uint64_t any = 0;
	/* Pairs of rows with something set: bit p for rows 2p, 2p + 1. */
	uint32_t pairs = 0;
	for (uint32_t p = 0; p < 16; p++)
		pairs |= ((rows >> (2 * p)) & 3u ? 1u : 0u) << p;
	volume_tile_zero(out);
	for (; pairs; pairs &= pairs - 1) {
		uint32_t y = 2 * (uint32_t)__builtin_ctz(pairs);
		__m512i th = _mm512_loadu_si512((const void *)t->thr[y & 15]);
		for (int c = 0; c < 3; c++) {
			const uint8_t *row = canvas + c * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES;
			uint64_t m = _mm512_cmpgt_epu8_mask(_mm512_loadu_si512((const void *)row), th);
			put_row(out + c * VOLUME_TILE_PLANE_BYTES + y * 4, (uint32_t)m);
			put_row(out + c * VOLUME_TILE_PLANE_BYTES + y * 4 + 4, (uint32_t)(m >> 32));
			any |= m;
		}
	}
	return any != 0;
}
#endif

static struct halftone_variant variants[5];

static void init_variants(void)
{
	int n = 0;
#ifdef HALFTONE_X86
	__builtin_cpu_init();
	if (__builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512f"))
		variants[n++] = (struct halftone_variant){ "avx512", halftone_avx512 };
	if (__builtin_cpu_supports("avx2"))
		variants[n++] = (struct halftone_variant){ "avx2", halftone_avx2 };
	if (__builtin_cpu_supports("sse2"))
		variants[n++] = (struct halftone_variant){ "sse2", halftone_sse2 };
#endif
	variants[n++] = (struct halftone_variant){ "scalar", halftone_scalar };
	variants[n] = (struct halftone_variant){ NULL, NULL };
}

const struct halftone_variant *halftone_variants(void)
{
	static pthread_once_t once = PTHREAD_ONCE_INIT;
	pthread_once(&once, init_variants);
	return variants;
}

halftone_fn halftone_pick(const char *name)
{
	const struct halftone_variant *v = halftone_variants();
	if (!name || strcmp(name, "auto") == 0)
		return v[0].fn;
	for (; v->name; v++)
		if (strcmp(v->name, name) == 0)
			return v->fn;
	return NULL;
}

int halftone_rgba_with(struct volume *vol, uint32_t k, const uint8_t *rgba, halftone_threshold_fn threshold,
		       const void *ctx)
{
	const struct geometry *g = &vol->geom;
	uint8_t tile[VOLUME_TILE_BYTES];
	for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
		uint32_t u0 = t % vol->tiles_x * VOLUME_TILE, v0 = t / vol->tiles_x * VOLUME_TILE;
		memset(tile, 0, sizeof(tile));
		for (uint32_t y = 0; y < VOLUME_TILE && v0 + y < g->height; y++) {
			for (uint32_t x = 0; x < VOLUME_TILE && u0 + x < g->width; x++) {
				const uint8_t *px = rgba + ((size_t)(v0 + y) * g->width + u0 + x) * 4;
				uint8_t thr = threshold(ctx, k, u0 + x, v0 + y);
				for (int c = 0; c < 3; c++)
					if (px[c] > thr)
						tile[c * VOLUME_TILE_PLANE_BYTES + y * 4 + x / 8] |=
							(uint8_t)(0x80u >> (x % 8));
			}
		}
		int e = volume_image_append(vol, k, t, tile);
		if (e < 0)
			return e;
	}
	return 0;
}

static uint8_t ordered_threshold(const void *ctx, uint32_t k, uint32_t u, uint32_t v)
{
	(void)ctx;
	return halftone_threshold(k, u, v);
}

int halftone_rgba_image(struct volume *vol, uint32_t k, const uint8_t *rgba)
{
	return halftone_rgba_with(vol, k, rgba, ordered_threshold, NULL);
}

const struct halftone_pattern *halftone_pattern(struct halftone_patterns *p, const uint8_t rgb[3],
						const struct halftone_table *thr, halftone_fn fn)
{
	for (unsigned i = 0; i < HALFTONE_PATTERNS; i++)
		if (p->pattern[i].thr == thr && !memcmp(p->pattern[i].rgb, rgb, 3))
			return &p->pattern[i];
	uint8_t tile[HALFTONE_TILE_BYTES], out[VOLUME_TILE_BYTES];
	for (int i = 0; i < 3; i++) /* rows 0..15 of the colour */
		memset(tile + i * HALFTONE_PLANE_BYTES, rgb[i], 16 * HALFTONE_ROW_BYTES);
	fn(tile, 0xffff, thr, out);
	struct halftone_pattern *pt = &p->pattern[p->next];
	p->next = (p->next + 1) % HALFTONE_PATTERNS;
	for (int i = 0; i < 3; i++)
		memcpy(pt->bits[i], out + i * VOLUME_TILE_PLANE_BYTES, sizeof(pt->bits[i]));
	pt->thr = thr;
	memcpy(pt->rgb, rgb, 3);
	return pt;
}
