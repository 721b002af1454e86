/* Triangles staged eight at a time (bin.h): the transform, the
 * slots (slot.h), the arcs and keys of bin_one_prim() on eight lanes, with
 * the same operations lane for lane, and the records written at once. */
#include "bin.h"

#include <float.h>
#include <stdbool.h>
#include <stddef.h>
#include <string.h>

#if defined(__x86_64__)
#include <immintrin.h>
#define BIN_TRIS_X86 1
#endif

#ifdef BIN_TRIS_X86
#include "bin_lanes8.h"

/* The instruction sets of bin_points.c's AVX-512 path, which
 * bin_points_isa_supported(BIN_POINTS_AVX512) checks. */
#define TRIS_TARGET AVX512_TARGET

/* slot_of() of eight (x, z), with the same operations: the slots; the
 * lanes it flags near a boundary are added to *near, those on the axis
 * to *axis. */
TRIS_TARGET static inline __m256i slots8(const struct slot_table *t, __m256 fx, __m256 fz, __mmask8 *near,
					 __mmask8 *axis)
{
	const __m256 fzero = _mm256_setzero_ps(), fabsmask = _mm256_castsi256_ps(_mm256_set1_epi32(INT32_MAX));
	__m256 ax = _mm256_and_ps(fx, fabsmask), az = _mm256_and_ps(fz, fabsmask);
	__m256 xneg = _mm256_cmp_ps(fx, fzero, _CMP_LT_OS), zneg = _mm256_cmp_ps(fz, fzero, _CMP_LT_OS);
	__m256 odd = _mm256_xor_ps(xneg, zneg); /* quadrants 1 and 3 */
	__m256 perp = _mm256_blendv_ps(az, ax, odd), radial = _mm256_blendv_ps(ax, az, odd);
	__m256 gt = _mm256_cmp_ps(perp, radial, _CMP_GT_OS);
	__m256 mn = _mm256_min_ps(perp, radial), mx = _mm256_max_ps(perp, radial);
	__mmask8 zero = _mm256_cmp_ps_mask(mx, fzero, _CMP_EQ_OQ);
	*axis |= zero;
	/* The slope, zeroed on the axis so that the gathers stay in the table. */
	__m256 s = _mm256_maskz_div_ps((__mmask8)~zero, mn, mx);
	__m256i q = _mm256_sub_epi32(
		_mm256_setzero_si256(),
		_mm256_add_epi32(_mm256_add_epi32(_mm256_castps_si256(zneg), _mm256_castps_si256(zneg)),
				 _mm256_castps_si256(odd))); /* 2 zneg + odd */
	__m256i octant = _mm256_sub_epi32(_mm256_add_epi32(q, q), _mm256_castps_si256(gt));
	__m256 sn = _mm256_mul_ps(s, _mm256_set1_ps((float)t->buckets));
	__m256i i = _mm256_cvttps_epi32(sn);
	__m256i idx = _mm256_add_epi32(_mm256_mullo_epi32(octant, _mm256_set1_epi32((int)t->buckets + 1)), i);
	return slot_pick8(t, idx, s, _mm256_sub_ps(sn, _mm256_cvtepi32_ps(i)), near);
}

/* prim_arc()'s largest circular gap between the sorted slots of three
 * vertices (the first of equals), and the slots after and before it. */
TRIS_TARGET static inline __m256i largest_gap(const __m256i sl[3], __m256i vN, __m256i *start, __m256i *end)
{
	__m256i lo = _mm256_min_epu32(_mm256_min_epu32(sl[0], sl[1]), sl[2]);
	__m256i hi = _mm256_max_epu32(_mm256_max_epu32(sl[0], sl[1]), sl[2]);
	__m256i mid =
		_mm256_sub_epi32(_mm256_add_epi32(_mm256_add_epi32(sl[0], sl[1]), sl[2]), _mm256_add_epi32(lo, hi));
	__m256i gap = _mm256_sub_epi32(_mm256_add_epi32(lo, vN), hi);
	__m256i g1 = _mm256_sub_epi32(mid, lo), g2 = _mm256_sub_epi32(hi, mid);
	*start = lo;
	*end = hi;
	__mmask8 c1 = _mm256_cmpgt_epi32_mask(g1, gap);
	gap = _mm256_mask_blend_epi32(c1, gap, g1);
	*start = _mm256_mask_blend_epi32(c1, *start, mid);
	*end = _mm256_mask_blend_epi32(c1, *end, lo);
	__mmask8 c2 = _mm256_cmpgt_epi32_mask(g2, gap);
	*start = _mm256_mask_blend_epi32(c2, *start, hi);
	*end = _mm256_mask_blend_epi32(c2, *end, mid);
	return _mm256_mask_blend_epi32(c2, gap, g2);
}

/* prim_arc() and prim_key() of eight triangles on a mirrored geometry,
 * from their vertices' slots and near flags: each record's first image
 * and count, and its key. Lanes on the axis are made "every image". */
TRIS_TARGET static inline void arcs8(const struct bin_set *b, const __m256i sl[3], __mmask8 near, __mmask8 every,
				     uint32_t first[8], uint32_t count[8], uint32_t key[8])
{
	const uint32_t N = b->slots.n, M = b->images;
	const __m256i vN = _mm256_set1_epi32((int)N), vM = _mm256_set1_epi32((int)M), one = _mm256_set1_epi32(1);
	__m256i start, end, gap = largest_gap(sl, vN, &start, &end);
	__m256i slack = _mm256_mask_blend_epi32(near, one, _mm256_set1_epi32(3));
	every |= _mm256_cmple_epi32_mask(gap, slack) |
		 _mm256_cmple_epi32_mask(_mm256_slli_epi32(_mm256_sub_epi32(gap, slack), 1), vN);
	__m256i len = _mm256_sub_epi32(_mm256_add_epi32(end, vN), start);
	len = _mm256_mask_sub_epi32(len, _mm256_cmpge_epi32_mask(len, vN), len, vN);
	len = _mm256_add_epi32(len, one);
	__m256i back = _mm256_sub_epi32(start, one); /* (start + N - 1) % N */
	back = _mm256_mask_blend_epi32(_mm256_cmpeq_epi32_mask(start, _mm256_setzero_si256()), back,
				       _mm256_sub_epi32(vN, one));
	start = _mm256_mask_blend_epi32(near, start, back);
	len = _mm256_mask_add_epi32(len, near, len, _mm256_set1_epi32(2));
	every |= _mm256_cmpge_epi32_mask(len, vN);
	/* Both lobes fold onto M images; a range of M or more is every one. */
	start = _mm256_mask_sub_epi32(start, _mm256_cmpge_epi32_mask(start, vM), start, vM);
	every |= _mm256_cmpge_epi32_mask(len, vM);
	start = _mm256_maskz_mov_epi32((__mmask8)~every, start);
	len = _mm256_mask_blend_epi32(every, len, vM);
	/* ceil_log2(count), 0 for 1: floor(log2(count - 1)) + 1, the exponent
	 * of count - 1 in float (exact below 2^24) */
	__m256i e = _mm256_srli_epi32(_mm256_castps_si256(_mm256_cvtepi32_ps(_mm256_sub_epi32(len, one))), 23);
	__m256i cls = _mm256_sub_epi32(e, _mm256_set1_epi32(126));
	cls = _mm256_maskz_mov_epi32(_mm256_cmpgt_epi32_mask(len, one), cls);
	_mm256_storeu_si256((__m256i *)first, start);
	_mm256_storeu_si256((__m256i *)count, len);
	_mm256_storeu_si256((__m256i *)key, _mm256_add_epi32(_mm256_mullo_epi32(cls, vM), start));
}

/* Float k (0 .. 8) of each of eight triangles (9 floats each) held in r:
 * element 9 l + k of the 72, for lane l. */
TRIS_TARGET static inline __m256 column9(const __m512 r[5], int k)
{
	__m512i e = _mm512_add_epi32(_mm512_setr_epi32(0, 9, 18, 27, 36, 45, 54, 63, 0, 0, 0, 0, 0, 0, 0, 0),
				     _mm512_set1_epi32(k));
	__m512 lo = _mm512_permutex2var_ps(r[0], e, r[1]); /* elements 0 .. 31 */
	__m512 mid = _mm512_permutex2var_ps(r[2], _mm512_sub_epi32(e, _mm512_set1_epi32(32)), r[3]);
	__m512 hi = _mm512_permutexvar_ps(_mm512_sub_epi32(e, _mm512_set1_epi32(64)), r[4]);
	lo = _mm512_mask_blend_ps(_mm512_cmpge_epi32_mask(e, _mm512_set1_epi32(32)), lo, mid);
	lo = _mm512_mask_blend_ps(_mm512_cmpge_epi32_mask(e, _mm512_set1_epi32(64)), lo, hi);
	return _mm512_castps512_ps256(lo);
}

/* Vertex i of eight triangles (r, column9()) through the transform m as
 * bin_transform() groups it (diagonal: bin_transform_diagonal()), in
 * float (f, and v by coordinate and lane); returns the lanes whose
 * coordinates are all finite floats. */
TRIS_TARGET static inline __mmask8 vertex8(const float m[16], bool diagonal, const __m512 r[5], int i, __m256 f[3],
					   float v[3][8])
{
	__m512d in[3] = { _mm512_cvtps_pd(column9(r, 3 * i)), _mm512_cvtps_pd(column9(r, 3 * i + 1)),
			  _mm512_cvtps_pd(column9(r, 3 * i + 2)) };
	__m512d x = in[0], y = in[1], z = in[2];
	__mmask8 fin = 0xFF;
	for (int c = 0; c < 3; c++) {
		__m512d t =
			diagonal
				? _mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(m[5 * c]), in[c]),
						_mm512_set1_pd(m[12 + c]))
				: _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(m[c]), x),
									    _mm512_mul_pd(_mm512_set1_pd(m[4 + c]), y)),
							      _mm512_mul_pd(_mm512_set1_pd(m[8 + c]), z)),
						_mm512_set1_pd(m[12 + c]));
		fin &= _mm512_cmp_pd_mask(_mm512_abs_pd(t), _mm512_set1_pd(FLT_MAX), _CMP_LE_OQ);
		f[c] = _mm512_cvtpd_ps(t);
		_mm256_storeu_ps(v[c], f[c]);
	}
	return fin;
}

/* Lane l's staged record: its vertices from v (vertex, coordinate,
 * lane), colour, images and key. */
static inline void lane_record(float v[3][3][8], unsigned l, const uint8_t rgb[3], uint32_t first, uint32_t count,
			       uint32_t key, struct stage_prim *s)
{
	for (int i = 0; i < 3; i++)
		for (int c = 0; c < 3; c++)
			s->rec.v[i][c] = v[i][c][l];
	s->rec.nverts = 3;
	memcpy(s->rec.rgb, rgb, 3);
	s->rec.first = (uint16_t)first;
	s->rec.count = (uint16_t)count;
	s->key = key;
}

/* The staged records of eight triangles (struct stage_prim: 12 words,
 * the nine coordinates, nverts and colour, first and count, key) from
 * their words by column (v: vertex, coordinate, lane; word9 the same for
 * all; first, count and key by lane), a transpose: eight rows of the
 * first eight columns, eight of the last four. */
_Static_assert(sizeof(struct stage_prim) == 48 && offsetof(struct stage_prim, key) == 44 &&
		       offsetof(struct bin_prim, nverts) == 36 && offsetof(struct bin_prim, first) == 40 &&
		       offsetof(struct bin_prim, count) == 42,
	       "store_records8() writes a staged triangle as 12 little-endian words");
TRIS_TARGET static inline void store_records8(float v[3][3][8], uint32_t word9, const uint32_t first[8],
					      const uint32_t count[8], const uint32_t key[8], struct stage_prim *out)
{
	__m256i c[8];
	for (int k = 0; k < 8; k++)
		c[k] = _mm256_loadu_si256((const __m256i *)v[k / 3][k % 3]);
	/* 8 x 8: pairs of columns interleaved, then pairs of pairs, then
	 * halves swapped */
	__m256i a[8], bq[8];
	for (int k = 0; k < 8; k += 2) {
		a[k] = _mm256_unpacklo_epi32(c[k], c[k + 1]);
		a[k + 1] = _mm256_unpackhi_epi32(c[k], c[k + 1]);
	}
	for (int k = 0; k < 8; k += 4)
		for (int h = 0; h < 2; h++) {
			bq[k + h] = _mm256_unpacklo_epi64(a[k + h], a[k + 2 + h]);
			bq[k + 2 + h] = _mm256_unpackhi_epi64(a[k + h], a[k + 2 + h]);
		}
	/* bq[0..3]: columns 0..3 of lanes (0, 4), (2, 6)... by 128-bit half */
	__m256i w8 = _mm256_loadu_si256((const __m256i *)v[2][2]);
	__m256i w9 = _mm256_set1_epi32((int)word9);
	__m256i w10 = _mm256_or_si256(_mm256_loadu_si256((const __m256i *)first),
				      _mm256_slli_epi32(_mm256_loadu_si256((const __m256i *)count), 16));
	__m256i w11 = _mm256_loadu_si256((const __m256i *)key);
	__m256i t0 = _mm256_unpacklo_epi32(w8, w9), t1 = _mm256_unpackhi_epi32(w8, w9);
	__m256i t2 = _mm256_unpacklo_epi32(w10, w11), t3 = _mm256_unpackhi_epi32(w10, w11);
	__m256i tail[4] = { _mm256_unpacklo_epi64(t0, t2), _mm256_unpackhi_epi64(t0, t2), _mm256_unpacklo_epi64(t1, t3),
			    _mm256_unpackhi_epi64(t1, t3) };
	/* lane l: row l % 4 of each group, half l / 4; the unpacks' order is
	 * lanes 0, 1, 4, 5 in a[k], a[k + 1]: see the index below */
	static const int row[4] = { 0, 2, 1, 3 };
	for (int l = 0; l < 8; l++) {
		int r = row[l % 4], half = l / 4;
		__m256i lo = half ? _mm256_permute2x128_si256(bq[r], bq[4 + r], 0x31)
				  : _mm256_permute2x128_si256(bq[r], bq[4 + r], 0x20);
		__m128i hi = half ? _mm256_extracti128_si256(tail[l % 4], 1) : _mm256_castsi256_si128(tail[l % 4]);
		uint8_t *dst = (uint8_t *)&out[l];
		_mm256_storeu_si256((__m256i *)dst, lo);
		_mm_storeu_si128((__m128i *)(dst + 32), hi);
	}
}

/* The staged records of triangles j .. j + 7 of d into out, turned and
 * counted in hist, from the lanes' vertices v, images and keys; a lane not
 * in fin (a coordinate that is not a finite float) by bin_one_prim(). A
 * draw of one colour and no turn has its records written at once. */
TRIS_TARGET static inline void records8(
	const struct bin_set *b, const struct scene_draw *d, uint64_t j, float v[3][3][8], __mmask8 fin,
	const uint32_t first[8], const uint32_t count[8], const uint32_t key[8], struct stage_prim *out, uint32_t *hist)
{
	const uint32_t turn = bin_draw_turn(b, d);
	const bool whole = !turn && !d->prim_rgb;
	if (whole)
		store_records8(v, 3u | (uint32_t)d->rgb[0] << 8 | (uint32_t)d->rgb[1] << 16 | (uint32_t)d->rgb[2] << 24,
			       first, count, key, out);
	for (unsigned l = 0; l < 8; l++) {
		const uint8_t *rgb = d->prim_rgb ? d->prim_rgb + 3 * (j + l) : d->rgb;
		if (!(fin >> l & 1))
			bin_one_prim(b, d, d->xyz + 9 * (j + l), 3, rgb, &out[l]);
		else if (whole)
			hist[key[l]]++; /* written, unturned */
		else
			lane_record(v, l, rgb, first[l], count[l], key[l], &out[l]);
		if (!whole || !(fin >> l & 1))
			bin_finish_item(b, turn, &out[l], hist);
	}
}

/* bin_one_prim() of triangles j0 .. j1 - 1 of d, eight at a time, on a
 * mirrored geometry: the same operations lane for lane (the transform
 * grouped as bin_transform() groups it, the slots as slot_of() finds
 * them); a lane with a coordinate that is not a finite float goes to
 * bin_one_prim(). Returns the first triangle not staged. */
TRIS_TARGET static uint64_t tris8(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
				  struct stage_prim *out, uint32_t *hist)
{
	const float *m = d->transform;
	const bool diagonal = bin_transform_diagonal(m);
	uint64_t j = j0;
	for (; j + 8 <= j1; j += 8) {
		const float *p = d->xyz + 9 * j;
		/* the 72 floats of eight triangles, loaded whole */
		const __m512 r[5] = { _mm512_loadu_ps(p), _mm512_loadu_ps(p + 16), _mm512_loadu_ps(p + 32),
				      _mm512_loadu_ps(p + 48), _mm512_castps256_ps512(_mm256_loadu_ps(p + 64)) };
		float v[3][3][8]; /* vertex, coordinate, lane */
		__m256i sl[3];
		__mmask8 fin = 0xFF, near = 0, axis = 0;
		for (int i = 0; i < 3; i++) {
			__m256 f[3];
			fin &= vertex8(m, diagonal, r, i, f, v[i]);
			/* Not finite: left to bin_one_prim(), its slope kept in the table */
			sl[i] = slots8(&b->slots, _mm256_maskz_mov_ps(fin, f[0]), _mm256_maskz_mov_ps(fin, f[2]), &near,
				       &axis);
		}
		uint32_t first[8], count[8], key[8];
		arcs8(b, sl, near, axis, first, count, key);
		records8(b, d, j, v, fin, first, count, key, &out[j - j0], hist);
	}
	return j;
}
#endif

uint64_t bin_stage_tris8(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
			 struct stage_prim *out, uint32_t *hist)
{
#ifdef BIN_TRIS_X86
	return tris8(b, d, j0, j1, out, hist);
#else
	(void)b, (void)d, (void)j1, (void)out, (void)hist;
	return j0;
#endif
}
