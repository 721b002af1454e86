/* Upright scalar grids a tile column at a time (grid_tiles.h,
 * grid_draw_tiles()): the 32 pixel columns of one canvas tile column are
 * set up one by one as the column path does (their lines mixed along x and
 * z once, into a scratch table of 32 floats per sample j, in the canvas's
 * byte order), and then every row of the image is 32 lanes of the same
 * arithmetic: mixed along y by the row's weight, the transfer, and MAX into
 * the canvas row, 32 bytes a plane. Lanes without a value hold NaN, which
 * lights nothing. The rows in AVX-512 and AVX2 intrinsics and, for the
 * rest, GCC's vector extensions, picked at run time; every variant does
 * the reference's operations in its order (no fused multiply-add:
 * -ffp-contract=off), so all light what it lights, byte for byte. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "grid_tiles.h"
#include "halftone.h"
#include "volume.h"

#if defined(__x86_64__) || defined(__i386__)
#define GRID_X86 1
#endif

/* The vector helpers below are always inlined into each variant: no
 * vector crosses a call, whatever the ABI would do with one. */
#pragma GCC diagnostic ignored "-Wpsabi"

#define LANES VOLUME_TILE /* pixel columns of a tile: the lanes of a row */
#define HALF 16           /* lanes of a vector */
#define LANE_AHEAD 2      /* lanes whose samples are asked for ahead */

typedef float f32v __attribute__((vector_size(4 * HALF)));
typedef int32_t i32v __attribute__((vector_size(4 * HALF)));
typedef uint8_t u8h __attribute__((vector_size(HALF)));
typedef uint8_t u8v __attribute__((vector_size(LANES)));

/* The draw's transfer as the rows take it (scene.h, grid.c's transfer()). */
struct tile_tf {
	float thr, lo, scale; /* scale: 1 / (hi - lo), as the reference computes it */
	float rgb[3];
	bool tri;
	const uint8_t *lut;
	uint32_t lut_count;
	/* NULL, or the brightness model's weight of each lane of the tile
	 * column (1 where it keeps the colour): grid.c's light() per lane. */
	const float *weight;
	/* NULL, or the same weights as 16-bit multipliers (brightness.h,
	 * BRIGHTNESS_KEEP): byte c of lane l becomes (c * mul[l]) >> 16, or
	 * stays c where bit l of keep is set (mul[l] 0); weight is then NULL. */
	const uint16_t *mul;
	uint32_t keep;
};

/* What brightness_apply() makes of colour bytes px under the lanes'
 * weights: c w + 1e-3 rounded down (w = 1 keeps c). */
static inline void weigh_lanes(uint8_t px[3][LANES], const float *weight)
{
	for (int c = 0; c < 3; c++)
		for (uint32_t l = 0; l < LANES; l++)
			px[c][l] = (uint8_t)((float)px[c][l] * weight[l] + 1e-3f);
}

/* weigh_lanes() by tf->mul: exactly the same bytes (brightness.h). */
static inline void mul_lanes(uint8_t px[3][LANES], const struct tile_tf *tf)
{
	for (int c = 0; c < 3; c++)
		for (uint32_t l = 0; l < LANES; l++)
			if (!(tf->keep >> l & 1))
				px[c][l] = (uint8_t)((px[c][l] * (uint32_t)tf->mul[l]) >> 16);
}

/* The image's rows and the samples they read. */
struct tile_span {
	const struct grid_rows *rows;
	uint32_t jlo, jhi;                   /* samples the rows read */
	uint32_t b0, b1;                     /* and their bricks */
	const struct brightness_map *bright; /* NULL, or an active one */
};

/* a where mask m is set, else b (a macro: GCC notes the ABI of any
 * function taking these vectors). */
#define FSEL(m, a, b) ((f32v)(((i32v)(a) & (m)) | ((i32v)(b) & ~(m))))

/* Lanes h * HALF .. of a row: the values from the mixed samples a and b,
 * their colours in px (0 where dark). Returns the lanes lit. */
static inline __attribute__((always_inline)) i32v row_half(const float *a, const float *b, float t,
							   const struct tile_tf *tf, uint8_t px[3][LANES], int h,
							   bool tri, bool lut)
{
	f32v va, vb, v;
	memcpy(&va, a + HALF * h, sizeof(va));
	memcpy(&vb, b + HALF * h, sizeof(vb));
	v = tri ? va * (1.0f - t) + vb * t : va;
	i32v lit = v >= tf->thr;
	f32v g = (v - tf->lo) * tf->scale, zero = { 0 }, one = zero + 1.0f;
	g = FSEL(g > 0.0f, FSEL(g < 1.0f, g, one), zero);
	i32v q[3];
	if (!lut) {
		for (int c = 0; c < 3; c++)
			q[c] = __builtin_convertvector(tf->rgb[c] * g + 0.5f, i32v);
	} else {
		i32v idx = __builtin_convertvector(g * (float)(tf->lut_count - 1) + 0.5f, i32v);
		for (int c = 0; c < 3; c++)
			q[c] = (i32v){ 0 };
		for (int l = 0; l < HALF; l++) /* only lit lanes have an index in range */
			if (lit[l])
				for (int c = 0; c < 3; c++)
					q[c][l] = tf->lut[3 * (uint32_t)idx[l] + c];
	}
	lit &= (q[0] | q[1] | q[2]) != 0;
	for (int c = 0; c < 3; c++) {
		u8h bytes = __builtin_convertvector(q[c] & lit, u8h);
		memcpy(px[c] + HALF * h, &bytes, sizeof(bytes));
	}
	return lit;
}

typedef void tile_row_fn(const float *a, const float *b, float t, const struct tile_tf *tf, uint8_t *dst,
			 uint32_t *rows, uint32_t bit, bool tri, bool lut);

/* Row v of the tile: MAX of its lit lanes into the canvas row at dst
 * (plane R; G and B a plane apart), its flag set in *rows. */
static inline __attribute__((always_inline)) void row_generic(const float *a, const float *b, float t,
							      const struct tile_tf *tf, uint8_t *dst, uint32_t *rows,
							      uint32_t bit, bool tri, bool lut)
{
	uint8_t px[3][LANES] __attribute__((aligned(LANES)));
	i32v lit = row_half(a, b, t, tf, px, 0, tri, lut) | row_half(a, b, t, tf, px, 1, tri, lut);
	i32v none = { 0 };
	if (!memcmp(&lit, &none, sizeof(lit)))
		return;
	if (tf->weight)
		weigh_lanes(px, tf->weight);
	else if (tf->mul)
		mul_lanes(px, tf);
	for (int c = 0; c < 3; c++) {
		u8v cur, add;
		memcpy(&cur, dst + c * HALFTONE_PLANE_BYTES, sizeof(cur));
		memcpy(&add, px[c], sizeof(add));
		u8v m = (u8v)(add > cur);
		cur = (add & m) | (cur & ~m);
		memcpy(dst + c * HALFTONE_PLANE_BYTES, &cur, sizeof(cur));
	}
	*rows |= bit;
}

#ifdef GRID_X86
#include <immintrin.h>

/* The lanes lit of a lookup table's draw, their colours from g: scalar,
 * as the table is read a lane at a time anyway. */
static inline __attribute__((always_inline)) uint32_t lut_lanes(const float g[LANES], uint32_t lit,
								const struct tile_tf *tf, uint8_t px[3][LANES])
{
	memset(px, 0, 3 * LANES);
	for (uint32_t l = 0; l < LANES; l++) {
		if (!(lit >> l & 1))
			continue;
		const uint8_t *e = tf->lut + 3 * (uint32_t)(g[l] * (float)(tf->lut_count - 1) + 0.5f);
		if (!(e[0] | e[1] | e[2])) {
			lit &= ~(1u << l);
			continue;
		}
		for (int c = 0; c < 3; c++)
			px[c][l] = e[c];
	}
	return lit;
}

/* weigh_lanes() of one plane's 32 bytes in AVX2. */
__attribute__((target("avx2"))) static inline __attribute__((always_inline)) __m256i weigh_avx2(__m256i px,
												const float *weight)
{
	uint8_t b[LANES];
	__m256i q[4];
	_mm256_storeu_si256((__m256i *)(void *)b, px);
	for (int h = 0; h < 4; h++) {
		__m256 x = _mm256_cvtepi32_ps(
			_mm256_cvtepu8_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(b + 8 * h))));
		x = _mm256_add_ps(_mm256_mul_ps(x, _mm256_loadu_ps(weight + 8 * h)), _mm256_set1_ps(1e-3f));
		q[h] = _mm256_cvttps_epi32(x);
	}
	__m256i w = _mm256_packus_epi16(_mm256_packus_epi32(q[0], q[1]), _mm256_packus_epi32(q[2], q[3]));
	return _mm256_permutevar8x32_epi32(w, _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7));
}

/* mul_lanes() of one plane's 32 bytes in AVX2: 16-bit lanes, one
 * multiply per 16 bytes, the KEEP lanes blended back. */
__attribute__((target("avx2"))) static inline __attribute__((always_inline)) __m256i mul_avx2(__m256i px,
											      const struct tile_tf *tf)
{
	__m256i w[2];
	for (int h = 0; h < 2; h++) {
		__m256i q = _mm256_cvtepu8_epi16(h ? _mm256_extracti128_si256(px, 1) : _mm256_castsi256_si128(px));
		__m256i m = _mm256_loadu_si256((const __m256i *)(const void *)(tf->mul + 16 * h));
		__m256i bits = _mm256_setr_epi16(1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096, 8192, 16384,
						 (short)32768);
		__m256i keep = _mm256_set1_epi16((short)(uint16_t)(tf->keep >> (16 * h)));
		keep = _mm256_cmpeq_epi16(_mm256_and_si256(keep, bits), bits);
		w[h] = _mm256_blendv_epi8(_mm256_mulhi_epu16(q, m), q, keep);
	}
	return _mm256_permute4x64_epi64(_mm256_packus_epi16(w[0], w[1]), 0xd8);
}

#define AVX2_INLINE __attribute__((target("avx2"))) static inline __attribute__((always_inline))

/* The colours of lanes 8h .. 8h + 7 of window position g (rgb g + 0.5,
 * truncated; weighed where tf->weight) into q[c][h], zero where not
 * lit: on, less the lanes whose colours are all zero, which it returns. */
AVX2_INLINE __m256 colours_avx2(__m256 g, __m256 on, const struct tile_tf *tf, int h, __m256i q[3][4])
{
	__m256i nz = _mm256_setzero_si256();
	for (int c = 0; c < 3; c++) {
		__m256 k = _mm256_set1_ps(tf->rgb[c]);
		q[c][h] = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(k, g), _mm256_set1_ps(0.5f)));
		nz = _mm256_or_si256(nz, q[c][h]);
	}
	on = _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(nz, _mm256_setzero_si256())), on);
	if (tf->weight) { /* weigh_lanes() on the colours before they are bytes */
		const __m256 w = _mm256_loadu_ps(tf->weight + 8 * h), e = _mm256_set1_ps(1e-3f);
		for (int c = 0; c < 3; c++)
			q[c][h] = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(q[c][h]), w), e));
	}
	for (int c = 0; c < 3; c++)
		q[c][h] = _mm256_and_si256(q[c][h], _mm256_castps_si256(on));
	return on;
}

/* Lanes 8h .. 8h + 7 of row_avx2(): their clamped window position in g[h]
 * and, without a lut, their colours in q (colours_avx2()). Returns the
 * lit lanes' bits. */
AVX2_INLINE uint32_t lanes_avx2(const float *a, const float *b, __m256 wa, __m256 wb, const struct tile_tf *tf,
				bool tri, bool lut, int h, __m256 g[4], __m256i q[3][4])
{
	const __m256 one = _mm256_set1_ps(1.0f);
	__m256 v = _mm256_loadu_ps(a + 8 * h);
	if (tri)
		v = _mm256_add_ps(_mm256_mul_ps(v, wa), _mm256_mul_ps(_mm256_loadu_ps(b + 8 * h), wb));
	__m256 on = _mm256_cmp_ps(v, _mm256_set1_ps(tf->thr), _CMP_GE_OQ);
	__m256 x = _mm256_mul_ps(_mm256_sub_ps(v, _mm256_set1_ps(tf->lo)), _mm256_set1_ps(tf->scale));
	x = _mm256_blendv_ps(one, x, _mm256_cmp_ps(x, one, _CMP_LT_OQ));
	g[h] = _mm256_and_ps(x, _mm256_cmp_ps(x, _mm256_setzero_ps(), _CMP_GT_OQ));
	if (!lut)
		on = colours_avx2(g[h], on, tf, h, q);
	return (uint32_t)_mm256_movemask_ps(on) << (8 * h);
}

/* The row's 32 bytes a plane into px: the lit lanes through the lut
 * (which may leave them all dark: false), or the colours q packed. */
AVX2_INLINE bool bytes_avx2(const __m256 g[4], __m256i q[3][4], const struct tile_tf *tf, bool lut, uint32_t lit,
			    __m256i px[3])
{
	if (lut) {
		float gl[LANES];
		uint8_t bytes[3][LANES];
		for (int h = 0; h < 4; h++)
			_mm256_storeu_ps(gl + 8 * h, g[h]);
		if (!lut_lanes(gl, lit, tf, bytes))
			return false;
		for (int c = 0; c < 3; c++)
			px[c] = _mm256_loadu_si256((const __m256i *)(const void *)bytes[c]);
		return true;
	}
	const __m256i order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
	for (int c = 0; c < 3; c++) {
		__m256i w = _mm256_packus_epi16(_mm256_packus_epi32(q[c][0], q[c][1]),
						_mm256_packus_epi32(q[c][2], q[c][3]));
		px[c] = _mm256_permutevar8x32_epi32(w, order);
	}
	return true;
}

/* The row's bytes px weighed (a lut's) or scaled as tf says, and MAXed
 * into the row at dst. */
AVX2_INLINE void store_avx2(__m256i px[3], const struct tile_tf *tf, bool lut, uint8_t *dst)
{
	if (tf->weight && lut)
		for (int c = 0; c < 3; c++)
			px[c] = weigh_avx2(px[c], tf->weight);
	else if (tf->mul)
		for (int c = 0; c < 3; c++)
			px[c] = mul_avx2(px[c], tf);
	for (int c = 0; c < 3; c++) {
		__m256i *p = (__m256i *)(void *)(dst + c * HALFTONE_PLANE_BYTES);
		_mm256_storeu_si256(p, _mm256_max_epu8(_mm256_loadu_si256(p), px[c]));
	}
}

/* row_generic() in AVX2: 4 vectors of 8 lanes, packed to bytes. */
AVX2_INLINE void row_avx2(const float *a, const float *b, float t, const struct tile_tf *tf, uint8_t *dst,
			  uint32_t *rows, uint32_t bit, bool tri, bool lut)
{
	const __m256 wa = _mm256_set1_ps(1.0f - t), wb = _mm256_set1_ps(t);
	__m256 g[4];
	__m256i q[3][4], px[3];
	uint32_t lit = 0;
	for (int h = 0; h < 4; h++)
		lit |= lanes_avx2(a, b, wa, wb, tf, tri, lut, h, g, q);
	if (!lit || !bytes_avx2(g, q, tf, lut, lit, px))
		return;
	store_avx2(px, tf, lut, dst);
	*rows |= bit;
}

/* The values of 16 lanes of a row in AVX-512, clamped window position g
 * of each, and (in *on) those at or above the threshold. */
__attribute__((target("avx512f,avx512bw,avx2"))) static inline __attribute__((always_inline)) __m512 g512(
	const float *a, const float *b, __m512 wa, __m512 wb, const struct tile_tf *tf, bool tri, __mmask16 *on)
{
	__m512 v = _mm512_loadu_ps(a);
	if (tri)
		v = _mm512_add_ps(_mm512_mul_ps(v, wa), _mm512_mul_ps(_mm512_loadu_ps(b), wb));
	*on = _mm512_cmp_ps_mask(v, _mm512_set1_ps(tf->thr), _CMP_GE_OQ);
	__m512 x = _mm512_mul_ps(_mm512_sub_ps(v, _mm512_set1_ps(tf->lo)), _mm512_set1_ps(tf->scale));
	x = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(x, _mm512_set1_ps(1.0f), _CMP_LT_OQ), _mm512_set1_ps(1.0f), x);
	return _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(x, _mm512_setzero_ps(), _CMP_GT_OQ), x);
}

/* Colour channel c of g: rgb[c] g + 0.5, truncated. */
__attribute__((target("avx512f,avx512bw,avx2"))) static inline __attribute__((always_inline)) __m512i c512(
	__m512 g, const struct tile_tf *tf, int c)
{
	return _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(tf->rgb[c]), g), _mm512_set1_ps(0.5f)));
}

/* weigh_lanes() of one plane's 32 bytes in AVX-512. */
__attribute__((target("avx512f,avx512bw,avx2"))) static inline __attribute__((always_inline)) __m256i weigh_avx512(
	__m256i px, const float *weight)
{
	__m128i half[2] = { _mm256_castsi256_si128(px), _mm256_extracti128_si256(px, 1) }, out[2];
	for (int h = 0; h < 2; h++) {
		__m512 x = _mm512_cvtepi32_ps(_mm512_cvtepu8_epi32(half[h]));
		x = _mm512_add_ps(_mm512_mul_ps(x, _mm512_loadu_ps(weight + 16 * h)), _mm512_set1_ps(1e-3f));
		out[h] = _mm512_cvtusepi32_epi8(_mm512_cvttps_epi32(x));
	}
	return _mm256_inserti128_si256(_mm256_castsi128_si256(out[0]), out[1], 1);
}

/* mul_lanes() of one plane's 32 bytes in AVX-512: 32 16-bit lanes, one
 * multiply, the KEEP lanes moved back. */
__attribute__((target("avx512f,avx512bw,avx2"))) static inline __attribute__((always_inline)) __m256i mul_avx512(
	__m256i px, const struct tile_tf *tf)
{
	__m512i q = _mm512_cvtepu8_epi16(px);
	__m512i w = _mm512_mulhi_epu16(q, _mm512_loadu_si512(tf->mul));
	return _mm512_cvtepi16_epi8(_mm512_mask_mov_epi16(w, tf->keep, q));
}

#define AVX512_INLINE __attribute__((target("avx512f,avx512bw,avx2"))) static inline __attribute__((always_inline))

/* Colours x weighed: x w + 1e-3, truncated (weigh_lanes()). */
AVX512_INLINE __m512i weigh512(__m512i x, __m512 w)
{
	return _mm512_cvttps_epi32(_mm512_add_ps(_mm512_mul_ps(_mm512_cvtepi32_ps(x), w), _mm512_set1_ps(1e-3f)));
}

/* Channel c of the row's colours (window positions g0, g1 of its two
 * halves of 16 lanes) as 32 bytes, weighed where tf->weight, zero where
 * not lit (on0, on1). */
AVX512_INLINE __m256i channel512(__m512 g0, __m512 g1, __mmask16 on0, __mmask16 on1, const struct tile_tf *tf, int c)
{
	__m512i x0 = c512(g0, tf, c), x1 = c512(g1, tf, c);
	if (tf->weight) { /* weigh_lanes() on the colours before they are bytes */
		x0 = weigh512(x0, _mm512_loadu_ps(tf->weight));
		x1 = weigh512(x1, _mm512_loadu_ps(tf->weight + 16));
	}
	return _mm256_inserti128_si256(_mm256_castsi128_si256(_mm512_maskz_cvtusepi32_epi8(on0, x0)),
				       _mm512_maskz_cvtusepi32_epi8(on1, x1), 1);
}

/* The colours of the row's lit lanes (on0, on1) as 32 bytes a plane in
 * px (channel512()), less the lanes whose three colours are zero; false:
 * none is left. */
AVX512_INLINE bool colours_avx512(__m512 g0, __m512 g1, __mmask16 on0, __mmask16 on1, const struct tile_tf *tf,
				  __m256i px[3])
{
	__m512i n0 = _mm512_or_si512(_mm512_or_si512(c512(g0, tf, 0), c512(g0, tf, 1)), c512(g0, tf, 2));
	__m512i n1 = _mm512_or_si512(_mm512_or_si512(c512(g1, tf, 0), c512(g1, tf, 1)), c512(g1, tf, 2));
	on0 = _mm512_mask_test_epi32_mask(on0, n0, n0);
	on1 = _mm512_mask_test_epi32_mask(on1, n1, n1);
	if (!(on0 | on1))
		return false;
	px[0] = channel512(g0, g1, on0, on1, tf, 0);
	px[1] = channel512(g0, g1, on0, on1, tf, 1);
	px[2] = channel512(g0, g1, on0, on1, tf, 2);
	return true;
}

/* The row's lit lanes (lit) of window positions g0, g1 through the lut,
 * as 32 bytes a plane in px; false: all dark. */
AVX512_INLINE bool lut_avx512(__m512 g0, __m512 g1, uint32_t lit, const struct tile_tf *tf, __m256i px[3])
{
	float gl[LANES];
	uint8_t bytes[3][LANES];
	_mm512_storeu_ps(gl, g0);
	_mm512_storeu_ps(gl + 16, g1);
	if (!lut_lanes(gl, lit, tf, bytes))
		return false;
	for (int c = 0; c < 3; c++)
		px[c] = _mm256_loadu_si256((const __m256i *)(const void *)bytes[c]);
	return true;
}

/* store_avx2() in AVX-512. */
AVX512_INLINE void store_avx512(__m256i px[3], const struct tile_tf *tf, bool lut, uint8_t *dst)
{
	if (tf->weight && lut)
		for (int c = 0; c < 3; c++)
			px[c] = weigh_avx512(px[c], tf->weight);
	else if (tf->mul)
		for (int c = 0; c < 3; c++)
			px[c] = mul_avx512(px[c], tf);
	for (int c = 0; c < 3; c++) {
		__m256i *p = (__m256i *)(void *)(dst + c * HALFTONE_PLANE_BYTES);
		_mm256_storeu_si256(p, _mm256_max_epu8(_mm256_loadu_si256(p), px[c]));
	}
}

/* row_generic() in AVX-512: 2 vectors of 16 lanes, narrowed to bytes. */
AVX512_INLINE void row_avx512(const float *a, const float *b, float t, const struct tile_tf *tf, uint8_t *dst,
			      uint32_t *rows, uint32_t bit, bool tri, bool lut)
{
	const __m512 wa = _mm512_set1_ps(1.0f - t), wb = _mm512_set1_ps(t);
	__mmask16 on0, on1;
	__m512 g0 = g512(a, b, wa, wb, tf, tri, &on0), g1 = g512(a + 16, b + 16, wa, wb, tf, tri, &on1);
	if (!(on0 | on1))
		return;
	__m256i px[3];
	bool any = lut ? lut_avx512(g0, g1, on0 | (uint32_t)on1 << 16, tf, px)
		       : colours_avx512(g0, g1, on0, on1, tf, px);
	if (!any)
		return;
	store_avx512(px, tf, lut, dst);
	*rows |= bit;
}
#endif

typedef float f32x8 __attribute__((vector_size(32)));

/* grid_column_mix() for one lane, 8 samples at a time (the same
 * operations, lane by lane), into out[(j - j0) LANES]. */
#define LANE_MIX(T)                                                                            \
	do {                                                                                   \
		typedef T t8 __attribute__((vector_size(8 * sizeof(T))));                      \
		const T *l[4];                                                                 \
		for (int i = 0; i < col->lines; i++)                                           \
			l[i] = (const T *)gr->data + col->line[i];                             \
		uint32_t j = j0;                                                               \
		for (; j1 - j >= 7 && j1 >= j; j += 8, out += 8 * LANES) {                     \
			t8 x[4];                                                               \
			f32x8 m;                                                               \
			for (int i = 0; i < col->lines; i++)                                   \
				memcpy(&x[i], l[i] + j, sizeof(x[i]));                         \
			if (col->lines == 1) {                                                 \
				m = __builtin_convertvector(x[0], f32x8);                      \
			} else {                                                               \
				f32x8 a = __builtin_convertvector(x[0], f32x8) * (1.0f - tx) + \
					  __builtin_convertvector(x[1], f32x8) * tx;           \
				f32x8 b = __builtin_convertvector(x[2], f32x8) * (1.0f - tx) + \
					  __builtin_convertvector(x[3], f32x8) * tx;           \
				m = a * (1.0f - tz) + b * tz;                                  \
			}                                                                      \
			for (int e = 0; e < 8; e++)                                            \
				out[e * LANES] = m[e];                                         \
		}                                                                              \
		if (j <= j1)                                                                   \
			grid_column_mix(col, gr, j, j1, out, LANES);                           \
	} while (0)

static inline __attribute__((always_inline)) void lane_mix(const struct column *col, const struct scene_grid *gr,
							   uint32_t j0, uint32_t j1, float *out)
{
	float tx = col->t[0], tz = col->t[2];
	switch (gr->type) {
	case SCENE_GRID_U8:
		LANE_MIX(uint8_t);
		break;
	case SCENE_GRID_U16:
		LANE_MIX(uint16_t);
		break;
	case SCENE_GRID_I16:
		LANE_MIX(int16_t);
		break;
	default:
		LANE_MIX(float);
		break;
	}
}
#undef LANE_MIX

/* Lane p of a tile column: its column of the grid, and which of the
 * bricks the rows read hold something that may light. */
struct lane {
	struct column col;
	bool dark[4096 / SCENE_GRID_BRICK + 1];
};

/* The samples lane l's rows read, as runs j0 .. j1 (ascending, apart),
 * into r[2 n]; returns n. A row reads samples j and j + 1 (nearest: j
 * alone) and is dark unless one lies in a lit brick: every sample of a lit
 * brick, and the one on each side of it. */
static inline uint32_t lane_runs(const struct lane *l, const struct tile_span *sp, uint32_t *r)
{
	uint32_t n = 0;
	for (uint32_t b = sp->b0; b <= sp->b1; b++) {
		if (l->dark[b])
			continue;
		uint32_t j0 = b * SCENE_GRID_BRICK, j1 = j0 + SCENE_GRID_BRICK - 1;
		j0 = j0 > sp->jlo ? j0 - 1 : sp->jlo; /* and the sample below */
		j0 = j0 > sp->jlo ? j0 : sp->jlo;
		j1 = j1 < sp->jhi ? j1 + 1 : sp->jhi; /* and the one above */
		if (n && r[2 * n - 1] + 1 >= j0) {    /* joins the run below */
			r[2 * n - 1] = j1;
			continue;
		}
		r[2 * n] = j0;
		r[2 * n + 1] = j1;
		n++;
	}
	return n;
}

/* Asks the memory for what lane l will read (runs r[2 n]): a big grid's
 * lines lie far apart, and each lane starts four new ones. */
static inline void lane_prefetch(const struct lane *l, const struct scene_grid *gr, const uint32_t *r, uint32_t n,
				 size_t size)
{
	for (uint32_t k = 0; k < n; k++)
		for (int i = 0; i < l->col.lines; i++) {
			const char *p = (const char *)gr->data + (l->col.line[i] + r[2 * k]) * size;
			const char *end = (const char *)gr->data + (l->col.line[i] + r[2 * k + 1]) * size;
			for (; p < end; p += 64)
				__builtin_prefetch(p);
			__builtin_prefetch(end);
		}
}

/* The lanes of tile column tu whose pixel column crosses the grid's box
 * (their columns set up in lanes, their bricks' darkness found), and of
 * them those with a lit brick, into on; returns how many. */
static inline __attribute__((always_inline)) uint32_t lanes_on(
	struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror, uint32_t tu,
	const struct tile_span *sp, const struct tile_tf *tf, struct lane lanes[LANES], uint32_t on[LANES])
{
	const struct geometry *g = &c->geom;
	const struct scene_grid *gr = job->draw->grid;
	uint32_t inside[LANES], count = 0, nb = scene_grid_bricks(gr->n[1]);
	for (uint32_t p = 0; p < LANES; p++) {
		uint32_t out = tu * VOLUME_TILE + (p ^ 7); /* lane p: canvas byte p, column halftone_pos(p) */
		if (out >= g->width)
			continue;
		uint32_t u = mirror ? g->width - 1 - out : out;
		double s = (u + 0.5) * 2.0 / g->width - 1.0, fx = job->off[0] + s * dir[0],
		       fz = job->off[2] + s * dir[2];
		if (!(fx >= -0.5 && fx < gr->n[0] - 0.5 && fz >= -0.5 && fz < gr->n[2] - 0.5))
			continue;
		struct lane *l = &lanes[p];
		grid_column_setup(&l->col, gr, fx, fz, tf->tri);
		for (int i = 0; gr->brick_max && i < l->col.lines; i++) /* for grid_column_dark() below */
			__builtin_prefetch(gr->brick_max + l->col.line[i] / gr->n[1] * nb + sp->b0);
		inside[count++] = p;
	}
	uint32_t n_in = count;
	count = 0;
	for (uint32_t i = 0; i < n_in; i++) {
		struct lane *l = &lanes[inside[i]];
		if (!grid_column_dark(&l->col, gr, &job->draw->transfer, sp->b0, sp->b1, l->dark))
			on[count++] = inside[i];
	}
	return count;
}

/* Tile column tu's lanes set up: their samples mixed into buf ((jhi -
 * jlo + 1) LANES floats), and lit[b] the lanes whose brick b may light.
 * false: none may. */
static inline __attribute__((always_inline)) bool tile_lanes(
	struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror, uint32_t tu,
	const struct tile_span *sp, const struct tile_tf *tf, float *buf, uint32_t *lit)
{
	const struct scene_grid *gr = job->draw->grid;
	struct lane lanes[LANES];
	uint32_t on[LANES], count = lanes_on(c, job, dir, mirror, tu, sp, tf, lanes, on);
	if (!count)
		return false;
	memset(lit + sp->b0, 0, (sp->b1 - sp->b0 + 1) * sizeof(lit[0]));
	/* NaN everywhere: what no lane sets lights nothing. */
	memset(buf, 0xff, (size_t)(sp->jhi - sp->jlo + 1) * LANES * sizeof(*buf));
	size_t size = gr->type == SCENE_GRID_U8 ? 1 : gr->type == SCENE_GRID_F32 ? 4 : 2;
	uint32_t runs[LANES][2 * (4096 / SCENE_GRID_BRICK + 1)], nruns[LANES];
	for (uint32_t i = 0; i < count; i++) {
		const struct lane *l = &lanes[on[i]];
		nruns[i] = lane_runs(l, sp, runs[i]);
		for (uint32_t b = sp->b0; b <= sp->b1; b++)
			lit[b] |= (uint32_t)!l->dark[b] << on[i];
		if (i < LANE_AHEAD)
			lane_prefetch(l, gr, runs[i], nruns[i], size);
	}
	for (uint32_t i = 0; i < count; i++) {
		if (i + LANE_AHEAD < count)
			lane_prefetch(&lanes[on[i + LANE_AHEAD]], gr, runs[i + LANE_AHEAD], nruns[i + LANE_AHEAD],
				      size);
		for (uint32_t k = 0; k < nruns[i]; k++) {
			uint32_t j0 = runs[i][2 * k], j1 = runs[i][2 * k + 1];
			lane_mix(&lanes[on[i]].col, gr, j0, j1, buf + (size_t)(j0 - sp->jlo) * LANES + on[i]);
		}
	}
	return true;
}

/* Tile column tu's rows, from its lanes (tile_lanes()): row is
 * row_generic() or a twin, tri and lut constants in each copy. */
static inline __attribute__((always_inline)) void tile_rows(
	struct section_canvas *c, uint32_t tu, const struct tile_span *sp, const struct tile_tf *tf, const float *buf,
	const uint32_t *lit, tile_row_fn *row, bool tri, bool lut)
{
	const struct grid_rows *rows = sp->rows;
	for (uint32_t v = rows->v0; v < rows->v1; v++) {
		const struct grid_row *r = &rows->row[v];
		if (!(lit[r->j0 / SCENE_GRID_BRICK] | lit[r->j1 / SCENE_GRID_BRICK]))
			continue;
		size_t t = (size_t)(v / VOLUME_TILE) * c->tiles_x + tu;
		uint8_t *dst = c->rgb + t * HALFTONE_TILE_BYTES + (v % VOLUME_TILE) * HALFTONE_ROW_BYTES;
		row(buf + (size_t)(r->j0 - sp->jlo) * LANES, buf + (size_t)(r->j1 - sp->jlo) * LANES, r->t, tf, dst,
		    &c->rows[t], 1u << (v % VOLUME_TILE), tri, lut);
	}
}

typedef void tiles_fn(struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror,
		      const struct tile_span *sp, const struct tile_tf *tf, float *buf);

/* The lanes' weights of tile column tu under map m (NULL: none) into
 * tf (brightness_map.lanes): NULL both when every lane keeps its colour,
 * else the multipliers where every lane has one, else the floats. */
static inline void tile_weights(const struct brightness_map *m, uint32_t tu, struct tile_tf *tf)
{
	const struct brightness_lanes *l = m ? &m->lanes[tu] : NULL;
	bool weighed = l && l->weighed;
	tf->keep = weighed ? l->keep : 0;
	tf->weight = weighed && !l->by_mul ? l->weight : NULL;
	tf->mul = weighed && l->by_mul ? l->mul : NULL;
}

#define TILES_VARIANT(name, attr, rowfn)                                                                              \
	attr static void name(struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror, \
			      const struct tile_span *sp, const struct tile_tf *draw_tf, float *buf)                  \
	{                                                                                                             \
		for (uint32_t tu = 0; tu < c->tiles_x; tu++) {                                                        \
			uint32_t lit[4096 / SCENE_GRID_BRICK + 1];                                                    \
			struct tile_tf tw = *draw_tf;                                                                 \
			const struct tile_tf *tf = &tw;                                                               \
			if (!tile_lanes(c, job, dir, mirror, tu, sp, draw_tf, buf, lit))                              \
				continue;                                                                             \
			tile_weights(sp->bright, tu, &tw);                                                            \
			if (tf->lut && tf->tri)                                                                       \
				tile_rows(c, tu, sp, tf, buf, lit, rowfn, true, true);                                \
			else if (tf->lut)                                                                             \
				tile_rows(c, tu, sp, tf, buf, lit, rowfn, false, true);                               \
			else if (tf->tri)                                                                             \
				tile_rows(c, tu, sp, tf, buf, lit, rowfn, true, false);                               \
			else                                                                                          \
				tile_rows(c, tu, sp, tf, buf, lit, rowfn, false, false);                              \
		}                                                                                                     \
	}

TILES_VARIANT(tiles_generic, , row_generic)
#ifdef GRID_X86
TILES_VARIANT(tiles_avx2, __attribute__((target("avx2"))), row_avx2)
TILES_VARIANT(tiles_avx512, __attribute__((target("avx512f,avx512bw,avx2"))), row_avx512)
#endif

static const struct {
	const char *name;
	tiles_fn *fn;
} all_variants[] = {
#ifdef GRID_X86
	{ "avx512", tiles_avx512 },
	{ "avx2", tiles_avx2 },
#endif
	{ "generic", tiles_generic },
};

static tiles_fn *picked;
static pthread_once_t pick_once = PTHREAD_ONCE_INIT;

static bool supported(const char *name)
{
#ifdef GRID_X86
	__builtin_cpu_init();
	if (!strcmp(name, "avx512"))
		return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw");
	if (!strcmp(name, "avx2"))
		return __builtin_cpu_supports("avx2");
#endif
	return !strcmp(name, "generic");
}

static void pick_best(void)
{
	for (size_t i = 0; i < sizeof(all_variants) / sizeof(all_variants[0]); i++)
		if (supported(all_variants[i].name)) {
			picked = all_variants[i].fn;
			return;
		}
}

const char *grid_tiles_variant(unsigned i)
{
	for (size_t k = 0; k < sizeof(all_variants) / sizeof(all_variants[0]); k++)
		if (supported(all_variants[k].name) && i-- == 0)
			return all_variants[k].name;
	return NULL;
}

bool grid_tiles_use(const char *name)
{
	pthread_once(&pick_once, pick_best);
	for (size_t i = 0; i < sizeof(all_variants) / sizeof(all_variants[0]); i++)
		if (!strcmp(all_variants[i].name, name) && supported(name)) {
			picked = all_variants[i].fn;
			return true;
		}
	return false;
}

bool grid_draw_tiles(struct section_canvas *c, const struct grid_job *job, const double dir[3], bool mirror,
		     const struct brightness_map *m)
{
	const struct scene_draw *d = job->draw;
	const struct grid_rows *rows = job->rows;
	if (d->grid->type == SCENE_GRID_RGBA8 || job->columns)
		return false;
	if (rows->v0 >= rows->v1)
		return true;
	struct tile_span sp = { rows, 0, 0, 0, 0, m };
	uint32_t ja = rows->row[rows->v0].j0, jb = rows->row[rows->v1 - 1].j0;
	uint32_t ka = rows->row[rows->v0].j1, kb = rows->row[rows->v1 - 1].j1;
	sp.jlo = ja < jb ? ja : jb;
	sp.jhi = ka > kb ? ka : kb;
	sp.b0 = sp.jlo / SCENE_GRID_BRICK;
	sp.b1 = sp.jhi / SCENE_GRID_BRICK;
	size_t need = (size_t)(sp.jhi - sp.jlo + 1) * LANES;
	if (c->scratch_floats < need) {
		float *f = malloc(need * sizeof(*f));
		if (!f)
			return false;
		free(c->scratch);
		c->scratch = f;
		c->scratch_floats = need;
	}
	const struct scene_transfer *x = &d->transfer;
	struct tile_tf tf = {
		x->threshold,
		x->lo,
		1.0f / (x->hi - x->lo),
		{ d->rgb[0], d->rgb[1], d->rgb[2] },
		x->sampling == SCENE_TRILINEAR,
		x->lut,
		x->lut_count,
		NULL,
		NULL,
		0,
	};
	pthread_once(&pick_once, pick_best);
	picked(c, job, dir, mirror, &sp, &tf, c->scratch);
	return true;
}
