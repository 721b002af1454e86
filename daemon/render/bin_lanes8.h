/* The eight-lane point binning's steps (bin_points.c): each the scalar
 * rule's operations lane for lane on AVX-512 (docs/rendering.md,
 * "Points"), as always-inlined functions for bin_points.c's passes (and
 * slot_pick8() for bin_tris.c's), which include this file only where the
 * compiler targets x86. Each is the
 * four-lane step of the same name in bin_points.c (lanes4, transform4(),
 * ...) on eight lanes, where it has one. */
#ifndef SPINDLE_BIN_LANES8_H
#define SPINDLE_BIN_LANES8_H

#include <float.h>
#include <immintrin.h>
#include <stdbool.h>
#include <stdint.h>

#include "bin.h"

#define AVX512_TARGET __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2")))
#define AVX512_INLINE AVX512_TARGET static inline __attribute__((always_inline))

/* struct lanes4 for eight lanes, and whether the transform is diagonal
 * (transform8()). */
struct lanes8 {
	__m512d m[3][4];
	bool diagonal;
	__m512d fltmax, one, halfv, width, height, h, h2, zero;
	__m256i wmax, hmax, rowlen, vM, vN, half;
	__m256 fabsmask, nbuckets;
	const struct slot_table *slots;
	const double *dir;
	/* At most 64 volume images: their cos and sin, eight to a register
	 * (column8() picks them by permutes: gathers were the pass's
	 * bottleneck). */
	bool few;
	__m512d cos[8], sin[8];
};

/* The cos and sin of a volume of at most 64 images in c's registers. */
AVX512_INLINE void lanes8_few(struct lanes8 *c, const struct bin_set *b)
{
	c->few = b->images <= 64;
	if (!c->few)
		return;
	double cs[2][64] = { { 0 } };
	for (uint32_t k = 0; k < b->images; k++) {
		cs[0][k] = b->dir[2 * k];
		cs[1][k] = b->dir[2 * k + 1];
	}
	for (int i = 0; i < 8; i++) {
		c->cos[i] = _mm512_loadu_pd(&cs[0][8 * i]);
		c->sin[i] = _mm512_loadu_pd(&cs[1][8 * i]);
	}
}

AVX512_INLINE void lanes8_init(struct lanes8 *c, const struct bin_set *b, const struct scene_draw *d)
{
	const struct geometry *g = &b->geom;
	c->diagonal = bin_transform_diagonal(d->transform);
	for (int r = 0; r < 3; r++)
		for (int i = 0; i < 4; i++)
			c->m[r][i] = _mm512_set1_pd(d->transform[4 * i + r]);
	c->fltmax = _mm512_set1_pd(FLT_MAX);
	c->one = _mm512_set1_pd(1.0);
	c->halfv = _mm512_set1_pd(0.5);
	c->width = _mm512_set1_pd((double)g->width);
	c->height = _mm512_set1_pd((double)g->height);
	c->h = _mm512_set1_pd(g->half_height);
	c->h2 = _mm512_set1_pd(2.0 * g->half_height);
	c->zero = _mm512_setzero_pd();
	c->wmax = _mm256_set1_epi32((int)g->width - 1);
	c->hmax = _mm256_set1_epi32((int)g->height - 1);
	c->rowlen = _mm256_set1_epi32((int)b->slots.buckets + 1);
	c->vM = _mm256_set1_epi32((int)b->images);
	c->vN = _mm256_set1_epi32((int)g->images_per_rev);
	c->half = _mm256_set1_epi32((int)(g->images_per_rev / 2));
	c->fabsmask = _mm256_castsi256_ps(_mm256_set1_epi32(INT32_MAX));
	c->nbuckets = _mm256_set1_ps((float)b->slots.buckets);
	c->slots = &b->slots;
	c->dir = b->dir;
	lanes8_few(c, b);
}

/* x, y and z of the eight points at p (24 floats: lanes 0..15 of the
 * first load, 16..23 of the second), widened. */
AVX512_INLINE void load8(const float *p, __m512d *x, __m512d *y, __m512d *z)
{
	const __m512i ix = _mm512_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21, 0, 0, 0, 0, 0, 0, 0, 0);
	const __m512i one = _mm512_set1_epi32(1);
	__m512 a = _mm512_loadu_ps(p), c = _mm512_castps256_ps512(_mm256_loadu_ps(p + 16));
	__m512i iy = _mm512_add_epi32(ix, one), iz = _mm512_add_epi32(iy, one);
	*x = _mm512_cvtps_pd(_mm512_castps512_ps256(_mm512_permutex2var_ps(a, ix, c)));
	*y = _mm512_cvtps_pd(_mm512_castps512_ps256(_mm512_permutex2var_ps(a, iy, c)));
	*z = _mm512_cvtps_pd(_mm512_castps512_ps256(_mm512_permutex2var_ps(a, iz, c)));
}

/* transform4() on eight points; of a diagonal transform
 * (bin_transform_diagonal()), row r is m[r][r] times its own input, plus
 * m[r][3]. */
AVX512_INLINE __m512d transform8(const struct lanes8 *c, int r, __m512d x, __m512d y, __m512d z, __mmask8 *fin)
{
	const __m512d *m = c->m[r];
	__m512d v;
	if (c->diagonal) {
		v = _mm512_add_pd(_mm512_mul_pd(m[r], r == 0 ? x : r == 1 ? y : z), m[3]);
	} else {
		v = _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(m[0], x), _mm512_mul_pd(m[1], y)),
						_mm512_mul_pd(m[2], z)),
				  m[3]);
	}
	*fin &= _mm512_cmp_pd_mask(_mm512_abs_pd(v), c->fltmax, _CMP_LE_OQ);
	return v;
}

/* bucket4() on eight lanes: the bucket's index (not times 3), and in
 * *frac where the slope lies in it (0 .. 1: slope times the bucket count,
 * a power of two, is exact, and so is its fraction). */
AVX512_INLINE __m256i bucket8(const struct lanes8 *c, __m256 fx, __m256 fz, __m256 *s, __m256 *exact, __m256 *frac)
{
	const __m256 fzero = _mm256_setzero_ps();
	__m256 ax = _mm256_and_ps(fx, c->fabsmask), az = _mm256_and_ps(fz, c->fabsmask);
	__m256 xneg = _mm256_cmp_ps(fx, fzero, _CMP_LT_OS), zneg = _mm256_cmp_ps(fz, fzero, _CMP_LT_OS);
	__m256 odd = _mm256_xor_ps(xneg, zneg);
	__m256 perp = _mm256_blendv_ps(az, ax, odd), radial = _mm256_blendv_ps(ax, az, odd);
	__m256 gt = _mm256_cmp_ps(perp, radial, _CMP_GT_OS);
	__m256 mn = _mm256_min_ps(perp, radial), mx = _mm256_max_ps(perp, radial);
	__m256 ex = _mm256_or_ps(_mm256_cmp_ps(mx, fzero, _CMP_EQ_OQ),
				 _mm256_cmp_ps(mx, _mm256_set1_ps(INFINITY), _CMP_EQ_OQ));
	ex = _mm256_or_ps(ex, _mm256_cmp_ps(fx, fz, _CMP_UNORD_Q));
	__m256 slope = _mm256_div_ps(mn, mx);
	slope = _mm256_andnot_ps(_mm256_or_ps(ex, _mm256_cmp_ps(slope, slope, _CMP_UNORD_Q)), slope);
	__m256i q = _mm256_sub_epi32(
		_mm256_setzero_si256(),
		_mm256_add_epi32(_mm256_add_epi32(_mm256_castps_si256(zneg), _mm256_castps_si256(zneg)),
				 _mm256_castps_si256(odd)));
	__m256i octant = _mm256_sub_epi32(_mm256_add_epi32(q, q), _mm256_castps_si256(gt));
	__m256 sn = _mm256_mul_ps(slope, c->nbuckets);
	__m256i i = _mm256_cvttps_epi32(sn);
	*frac = _mm256_sub_ps(sn, _mm256_cvtepi32_ps(i));
	*s = slope;
	*exact = ex;
	return _mm256_add_epi32(_mm256_mullo_epi32(octant, c->rowlen), i);
}

/* The slots of slopes s in buckets idx of table t (slot.h), s lying at
 * frac in them: one 64-bit gather a lane. The lanes slot_of() calls near
 * are added to *near. bin_tris.c's triangles take their vertices' slots
 * this way too. */
AVX512_INLINE __m256i slot_pick8(const struct slot_table *t, __m256i idx, __m256 s, __m256 frac, __mmask8 *near)
{
	const __m256 width = _mm256_set1_ps(SLOT_NEAR), close = _mm256_set1_ps(SLOT_NEAR * (float)t->buckets);
	__m512i eb = _mm512_i32gather_epi64(idx, t->b, 8); /* edge | below << 32 | above << 48 */
	__m256 edge = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(eb));
	__m256i ba = _mm512_cvtepi64_epi32(_mm512_srli_epi64(eb, 32));
	__m256 d = _mm256_sub_ps(s, edge);
	*near |= _mm256_cmp_ps_mask(d, width, _CMP_LT_OS) &
		 _mm256_cmp_ps_mask(d, _mm256_sub_ps(_mm256_setzero_ps(), width), _CMP_GT_OS);
	*near |= _mm256_test_epi32_mask(ba, _mm256_set1_epi32(SLOT_NEAR_LOW << 16)) &
		 _mm256_cmp_ps_mask(frac, close, _CMP_LT_OS);
	*near |= _mm256_test_epi32_mask(ba, _mm256_set1_epi32((int)(SLOT_NEAR_HIGH << 16))) &
		 _mm256_cmp_ps_mask(_mm256_sub_ps(_mm256_set1_ps(1.0f), frac), close, _CMP_LT_OS);
	__m256i below = _mm256_and_si256(ba, _mm256_set1_epi32(0xFFFF));
	__m256i above = _mm256_and_si256(_mm256_srli_epi32(ba, 16), _mm256_set1_epi32(SLOT_ABOVE));
	return _mm256_mask_blend_epi32(_mm256_cmp_ps_mask(s, edge, _CMP_GE_OS), below, above);
}

/* slot4() on eight lanes (slot_pick8()). */
AVX512_INLINE __m256i slot8(const struct lanes8 *c, __m512d X, __m512d Z, __m256 *exact)
{
	__m256 s, frac;
	__m256i idx = bucket8(c, _mm512_cvtpd_ps(X), _mm512_cvtpd_ps(Z), &s, exact, &frac);
	__mmask8 near = 0;
	__m256i slot = slot_pick8(c->slots, idx, s, frac, &near);
	*exact = _mm256_or_ps(*exact, _mm256_castsi256_ps(_mm256_movm_epi32(near)));
	return slot;
}

/* lobes4() on eight lanes. */
AVX512_INLINE __m256i lobes8(const struct lanes8 *c, __m256i front, __m256i *back)
{
	__m256i k = _mm256_add_epi32(front, c->half);
	*back = _mm256_sub_epi32(k, _mm256_andnot_si256(_mm256_cmpgt_epi32(c->vN, k), c->vN));
	return _mm256_sub_epi32(front, _mm256_andnot_si256(_mm256_cmpgt_epi32(c->vM, front), c->vM));
}

/* index4() on eight lanes. */
AVX512_INLINE __m256i index8(const struct lanes8 *c, __m512d f, __m512d limit, __m256i max)
{
	__m256i i = _mm512_cvttpd_epi32(_mm512_maskz_mov_pd(_mm512_cmp_pd_mask(f, c->zero, _CMP_GE_OQ), f));
	return _mm256_mask_blend_epi32(_mm512_cmp_pd_mask(f, limit, _CMP_GE_OQ), i, max);
}

/* Entry k (below 64) of a table of eight registers, on eight lanes. */
AVX512_INLINE __m512d pick64(const __m512d *t, __m512i k, __mmask8 b4, __mmask8 b5)
{
	__m512d a = _mm512_permutex2var_pd(t[0], k, t[1]), b = _mm512_permutex2var_pd(t[2], k, t[3]);
	__m512d c = _mm512_permutex2var_pd(t[4], k, t[5]), d = _mm512_permutex2var_pd(t[6], k, t[7]);
	return _mm512_mask_blend_pd(b5, _mm512_mask_blend_pd(b4, a, b), _mm512_mask_blend_pd(b4, c, d));
}

/* column4() on eight lanes: image k's cos and sin gathered, or, for a
 * volume of at most 64 images, picked from registers (struct lanes8); the
 * same products either way. */
AVX512_INLINE __m256i column8(const struct lanes8 *c, __m512d X, __m512d Z, __m256i k)
{
	__m512d cs, sn;
	if (c->few) {
		__m512i k64 = _mm512_cvtepu32_epi64(k);
		__mmask8 b4 = _mm512_test_epi64_mask(k64, _mm512_set1_epi64(16));
		__mmask8 b5 = _mm512_test_epi64_mask(k64, _mm512_set1_epi64(32));
		cs = pick64(c->cos, k64, b4, b5);
		sn = pick64(c->sin, k64, b4, b5);
	} else {
		__m256i k2 = _mm256_add_epi32(k, k);
		cs = _mm512_i32gather_pd(k2, c->dir, 8);
		sn = _mm512_i32gather_pd(k2, c->dir + 1, 8);
	}
	__m512d S = _mm512_add_pd(_mm512_mul_pd(X, cs), _mm512_mul_pd(Z, sn));
	return index8(c, _mm512_mul_pd(_mm512_mul_pd(_mm512_add_pd(S, c->one), c->halfv), c->width), c->width, c->wmax);
}

/* row4() on eight lanes. */
AVX512_INLINE __m256i row8(const struct lanes8 *c, __m512d Y)
{
	__m512d fv = _mm512_mul_pd(_mm512_div_pd(_mm512_sub_pd(c->h, Y), c->h2), c->height);
	return index8(c, fv, c->height, c->hmax);
}

#endif
