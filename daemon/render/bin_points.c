#include "bin.h"

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define BIN_POINTS_X86 1
#endif

/* A staged key: the volume image (below 16384, geometry_validate()), or
 * none; on a mirrored device PKEY_SECOND says the point has a second
 * record, which the scatter makes again. */
#define PKEY_NONE 0xFFFFu
#define PKEY_SECOND 0x8000u
#define PKEY_IMAGE 0x3FFFu
#define NO_IMAGE UINT32_MAX

/* scene.h: 0 counts as 1, and sizes are capped. */
static uint8_t point_size(const struct scene_draw *d)
{
	if (d->point_size == 0)
		return 1;
	return d->point_size < BIN_POINT_MAX_SIZE ? d->point_size : BIN_POINT_MAX_SIZE;
}

/* A record turned by turn (1 .. N-1): what image *k held goes to image
 * *k + turn (mod N), and where that is M or more (a mirrored device) to
 * image *k + turn - M mirrored: u -> W-1-u, and an even square flagged to
 * reach the other way (bin_point_columns()); an odd one is its own mirror. */
static inline void turn_record(const struct bin_set *b, uint32_t turn, struct bin_point *r, uint32_t *k)
{
	const struct geometry *g = &b->geom;
	uint32_t j = (*k + turn) % g->images_per_rev; /* k < M <= N, turn < N */
	if (j >= b->images) {
		j -= b->images;
		r->u = (uint16_t)(g->width - 1 - r->u);
		if (r->size % 2 == 0)
			r->size |= BIN_POINT_MIRRORED;
	}
	*k = j;
}

/* The record of a transformed point in volume image k. */
static inline void point_record(const struct bin_set *b, const double p[3], uint32_t k, struct bin_point *r)
{
	const struct geometry *g = &b->geom;
	r->u = (uint16_t)geometry_column(g, p[0] * b->dir[2 * k] + p[2] * b->dir[2 * k + 1]);
	r->v = (uint16_t)geometry_row(g, p[1]);
}

/* The rule itself (docs/design.md section 3): a point lights one voxel (a
 * square of them when larger) in each lobe's image. On a mirrored device
 * both lobes usually fold onto one volume image and then give one record:
 * the square is placed in the volume image's own columns, which the
 * mirrored half turn shows mirrored. Fills up to two records and their
 * volume images (NO_IMAGE: none), turned by turn (0 .. N-1). */
static void point_exact(const struct bin_set *b, const struct scene_draw *d, const float *xyz, const uint8_t rgb[3],
			uint32_t turn, struct bin_point r[2], uint32_t k[2])
{
	double p[3];
	k[0] = k[1] = NO_IMAGE;
	if (!bin_transform(d->transform, xyz, p))
		return;
	const struct geometry *g = &b->geom;
	uint32_t N = g->images_per_rev, M = b->images, front, back;
	bool near = false;
	front = slot_of(&b->slots, (float)p[0], (float)p[2], &near);
	if (near || front == SLOT_AXIS || N % 2 != 0) {
		/* Close to a boundary: the exact rule decides. */
		double phi = atan2(p[2], p[0]);
		front = geometry_image_of_azimuth(g, phi);
		back = geometry_image_of_azimuth_back(g, phi);
	} else {
		back = (front + N / 2) % N;
	}
	struct bin_point look = { .rgb = { rgb[0], rgb[1], rgb[2] }, .size = point_size(d) };
	r[0] = r[1] = look;
	k[0] = front % M;
	point_record(b, p, k[0], &r[0]);
	if (back % M != front % M) {
		k[1] = back % M;
		point_record(b, p, k[1], &r[1]);
	}
	for (int i = 0; turn && i < 2; i++)
		if (k[i] != NO_IMAGE)
			turn_record(b, turn, &r[i], &k[i]);
}

static inline const uint8_t *point_rgb(const struct scene_draw *d, uint64_t j)
{
	return d->prim_rgb ? d->prim_rgb + j * 3 : d->rgb;
}

/* Stages the records of point j (at entry i of recs and keys). */
static inline void stage_exact(const struct bin_set *b, const struct scene_draw *d, uint64_t j, uint32_t turn,
			       struct bin_point *recs, uint16_t *keys, uint64_t i, uint32_t *hist)
{
	struct bin_point r[2];
	uint32_t k[2];
	point_exact(b, d, d->xyz + 3 * j, point_rgb(d, j), turn, r, k);
	if (k[0] != NO_IMAGE)
		hist[k[0]]++;
	if (k[1] != NO_IMAGE)
		hist[k[1]]++;
	if (b->geom.mirrored) {
		recs[i] = r[0];
		keys[i] = (uint16_t)(k[0] == NO_IMAGE ? PKEY_NONE : k[0] | (k[1] != NO_IMAGE ? PKEY_SECOND : 0));
	} else {
		recs[2 * i] = r[0];
		recs[2 * i + 1] = r[1];
		keys[2 * i] = (uint16_t)(k[0] == NO_IMAGE ? PKEY_NONE : k[0]);
		keys[2 * i + 1] = (uint16_t)(k[1] == NO_IMAGE ? PKEY_NONE : k[1]);
	}
}

#ifdef BIN_POINTS_X86
/* stage_exact() for stage_avx2()'s fast path (mirrored, no turn): counts
 * only a second record, the first being counted with the others. */
static void stage_fast_exact(const struct bin_set *b, const struct scene_draw *d, uint64_t j, struct bin_point *recs,
			     uint16_t *keys, uint64_t i, uint32_t *hist)
{
	struct bin_point r[2];
	uint32_t k[2];
	point_exact(b, d, d->xyz + 3 * j, point_rgb(d, j), 0, r, k);
	recs[i] = r[0];
	keys[i] = (uint16_t)(k[0] == NO_IMAGE ? PKEY_NONE : k[0] | (k[1] != NO_IMAGE ? PKEY_SECOND : 0));
	if (k[1] != NO_IMAGE)
		hist[k[1]]++;
}

/* turn_record() on a record word (stage_avx2()). */
static inline void turn_word(const struct bin_set *b, uint32_t turn, uint64_t *w, uint32_t *k)
{
	const struct geometry *g = &b->geom;
	uint32_t j = (*k + turn) % g->images_per_rev;
	if (j >= b->images) {
		j -= b->images;
		uint64_t u = g->width - 1 - (*w & 0xFFFF);
		*w = (*w & ~(uint64_t)0xFFFF) | u;
		if ((*w >> 56) % 2 == 0)
			*w |= (uint64_t)BIN_POINT_MIRRORED << 56;
	}
	*k = j;
}

/* A record word's colour and size (x86: little-endian; u and v below). */
static inline uint64_t record_high(const uint8_t rgb[3], uint64_t size)
{
	return (uint64_t)rgb[0] << 32 | (uint64_t)rgb[1] << 40 | (uint64_t)rgb[2] << 48 | size << 56;
}

/* The vector paths' lanes past the fast path: the records of points j ..
 * j + n - 1 from their images ka (front), kb (back, unmirrored), columns
 * and row uva (u | v << 16) and back columns ub, the colour and size word
 * hi of a one-colour draw; a lane set in ex goes to the scalar rule. recs
 * and keys point at point j's entries. */
static inline void stage_lanes(const struct bin_set *b, const struct scene_draw *d, uint64_t j, int n, unsigned ex,
			       const uint32_t *ka, const uint32_t *kb, const uint32_t *uva, const uint32_t *ub,
			       uint64_t hi, uint32_t turn, struct bin_point *recs, uint16_t *keys, uint32_t *hist)
{
	const bool mirrored = b->geom.mirrored;
	const uint64_t size = point_size(d);
	for (int l = 0; l < n; l++) {
		uint64_t jj = j + (uint64_t)l, i = (uint64_t)l;
		if (ex & (1u << l)) {
			stage_exact(b, d, jj, turn, recs, keys, i, hist);
			continue;
		}
		uint64_t w = d->prim_rgb ? record_high(d->prim_rgb + 3 * jj, size) : hi;
		uint64_t w0 = w | uva[l];
		uint32_t k = ka[l];
		if (turn)
			turn_word(b, turn, &w0, &k);
		hist[k]++;
		if (mirrored) {
			memcpy(&recs[i], &w0, sizeof(w0));
			keys[i] = (uint16_t)k;
			continue;
		}
		memcpy(&recs[2 * i], &w0, sizeof(w0));
		keys[2 * i] = (uint16_t)k;
		uint64_t w1 = w | (uva[l] & 0xFFFF0000u) | ub[l];
		k = kb[l];
		if (turn)
			turn_word(b, turn, &w1, &k);
		hist[k]++;
		memcpy(&recs[2 * i + 1], &w1, sizeof(w1));
		keys[2 * i + 1] = (uint16_t)k;
	}
}

_Static_assert(sizeof(struct bin_point) == 8 && offsetof(struct bin_point, v) == 2 &&
		       offsetof(struct bin_point, rgb) == 4 && offsetof(struct bin_point, size) == 7,
	       "the vector paths write points as 64-bit words");
_Static_assert(sizeof(struct slot_bucket) == 8 && offsetof(struct slot_bucket, below) == 4 &&
		       offsetof(struct slot_bucket, above) == 6,
	       "the vector paths gather a slot bucket as a 64-bit word (edge, below, above)");

/* Mirrored, unturned, one colour: the vector paths stage a record and a
 * key a point with no scalar work in their loop, and the records are
 * counted by a pass over the keys afterwards (bin_points_stage()). */
static inline bool stage_fast(const struct bin_set *b, const struct scene_draw *d)
{
	return b->geom.mirrored && !bin_draw_turn(b, d) && !d->prim_rgb;
}

/* The fast path's lanes (ex) that the scalar rule decides, staged over
 * the vector's: recs and keys point at point j's entries. */
static inline void fast_exact_lanes(const struct bin_set *b, const struct scene_draw *d, uint64_t j, int n, unsigned ex,
				    struct bin_point *recs, uint16_t *keys, uint32_t *hist)
{
	for (int l = 0; ex && l < n; l++)
		if (ex & (1u << l))
			stage_fast_exact(b, d, j + (uint64_t)l, recs, keys, (uint64_t)l, hist);
}

/* ---- four points at a time (AVX2) ---- */

#define AVX2_INLINE __attribute__((target("avx2"))) static inline __attribute__((always_inline))

/* What stage_avx2()'s loop keeps in registers: the transform's rows (X =
 * ((m[0][0] x + m[0][1] y) + m[0][2] z) + m[0][3], as the scalar code
 * groups it), the image's size and the slope table's shape. */
struct lanes4 {
	__m256d m[3][4];
	__m256d absmask, fltmax, one, halfv, width, height, h, h2, zero;
	__m128i wmax, hmax, rowlen, lo16, vM, vN, half, near_low, near_high, above;
	__m128 fabsmask, nbuckets, near_width, near_nwidth, close, one_f;
	const struct slot_bucket *table;
	const double *dir;
};

AVX2_INLINE void lanes4_init(struct lanes4 *c, const struct bin_set *b, const struct scene_draw *d)
{
	const struct geometry *g = &b->geom;
	for (int r = 0; r < 3; r++)
		for (int i = 0; i < 4; i++)
			c->m[r][i] = _mm256_set1_pd(d->transform[4 * i + r]);
	c->absmask = _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX));
	c->fltmax = _mm256_set1_pd(FLT_MAX);
	c->one = _mm256_set1_pd(1.0);
	c->halfv = _mm256_set1_pd(0.5); /* (S + 1) / 2 == (S + 1) * 0.5 exactly: both round the same real */
	c->width = _mm256_set1_pd((double)g->width);
	c->height = _mm256_set1_pd((double)g->height);
	c->h = _mm256_set1_pd(g->half_height);
	c->h2 = _mm256_set1_pd(2.0 * g->half_height);
	c->zero = _mm256_setzero_pd();
	c->wmax = _mm_set1_epi32((int)g->width - 1);
	c->hmax = _mm_set1_epi32((int)g->height - 1);
	c->rowlen = _mm_set1_epi32((int)b->slots.buckets + 1);
	c->lo16 = _mm_set1_epi32(0xFFFF);
	c->vM = _mm_set1_epi32((int)b->images);
	c->vN = _mm_set1_epi32((int)g->images_per_rev);
	c->half = _mm_set1_epi32((int)(g->images_per_rev / 2));
	c->fabsmask = _mm_castsi128_ps(_mm_set1_epi32(INT32_MAX));
	c->nbuckets = _mm_set1_ps((float)b->slots.buckets);
	c->near_low = _mm_set1_epi32(SLOT_NEAR_LOW << 16);
	c->near_high = _mm_set1_epi32((int)(SLOT_NEAR_HIGH << 16));
	c->above = _mm_set1_epi32(SLOT_ABOVE);
	c->near_width = _mm_set1_ps(SLOT_NEAR);
	c->near_nwidth = _mm_set1_ps(-SLOT_NEAR);
	c->close = _mm_set1_ps(SLOT_NEAR * (float)b->slots.buckets);
	c->one_f = _mm_set1_ps(1.0f);
	c->table = b->slots.b;
	c->dir = b->dir;
}

/* x, y and z of the four points at p, widened. */
AVX2_INLINE void load4(const float *p, __m256d *x, __m256d *y, __m256d *z)
{
	*x = _mm256_cvtps_pd(_mm_setr_ps(p[0], p[3], p[6], p[9]));
	*y = _mm256_cvtps_pd(_mm_setr_ps(p[1], p[4], p[7], p[10]));
	*z = _mm256_cvtps_pd(_mm_setr_ps(p[2], p[5], p[8], p[11]));
}

/* Row r of the transform on four points; and whether it is finite there. */
AVX2_INLINE __m256d transform4(const struct lanes4 *c, int r, __m256d x, __m256d y, __m256d z, __m256d *fin)
{
	const __m256d *m = c->m[r];
	__m256d v = _mm256_add_pd(
		_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(m[0], x), _mm256_mul_pd(m[1], y)), _mm256_mul_pd(m[2], z)),
		m[3]);
	*fin = _mm256_and_pd(*fin, _mm256_cmp_pd(_mm256_and_pd(v, c->absmask), c->fltmax, _CMP_LE_OQ));
	return v;
}

/* slot_of()'s bucket of (fx, fz) on four lanes, the slope *s and where
 * it lies in the bucket, *frac (slot.h); *exact gets the lanes slot_of()
 * would not see (not finite) or that have no slot there (on the axis, or
 * a float overflow), whose slope is zeroed so that the gathers stay
 * inside the table. */
AVX2_INLINE __m128i bucket4(const struct lanes4 *c, __m128 fx, __m128 fz, __m128 *s, __m128 *exact, __m128 *frac)
{
	const __m128 fzero = _mm_setzero_ps();
	__m128 ax = _mm_and_ps(fx, c->fabsmask), az = _mm_and_ps(fz, c->fabsmask);
	__m128 xneg = _mm_cmplt_ps(fx, fzero), zneg = _mm_cmplt_ps(fz, fzero);
	__m128 odd = _mm_xor_ps(xneg, zneg); /* quadrants 1 and 3 */
	__m128 perp = _mm_blendv_ps(az, ax, odd), radial = _mm_blendv_ps(ax, az, odd);
	__m128 gt = _mm_cmpgt_ps(perp, radial);
	__m128 mn = _mm_min_ps(perp, radial), mx = _mm_max_ps(perp, radial);
	__m128 ex = _mm_or_ps(_mm_cmpeq_ps(mx, fzero), _mm_cmpeq_ps(mx, _mm_set1_ps(INFINITY)));
	ex = _mm_or_ps(ex, _mm_cmpunord_ps(fx, fz));
	__m128 slope = _mm_div_ps(mn, mx);
	slope = _mm_andnot_ps(_mm_or_ps(ex, _mm_cmpunord_ps(slope, slope)), slope);
	__m128i q = _mm_sub_epi32(_mm_setzero_si128(),
				  _mm_add_epi32(_mm_add_epi32(_mm_castps_si128(zneg), _mm_castps_si128(zneg)),
						_mm_castps_si128(odd))); /* 2 zneg + odd */
	__m128i octant = _mm_sub_epi32(_mm_add_epi32(q, q), _mm_castps_si128(gt));
	__m128 sn = _mm_mul_ps(slope, c->nbuckets);
	__m128i i = _mm_cvttps_epi32(sn);
	*frac = _mm_sub_ps(sn, _mm_cvtepi32_ps(i));
	*s = slope;
	*exact = ex;
	return _mm_add_epi32(_mm_mullo_epi32(octant, c->rowlen), i);
}

/* slot_of((float)X, (float)Z) on four lanes: the front image of each;
 * *exact gets the lanes point_exact() decides (bucket4(), and those near
 * a slot boundary). */
AVX2_INLINE __m128i slot4(const struct lanes4 *c, __m256d X, __m256d Z, __m128 *exact)
{
	__m128 s, frac;
	__m128i idx = bucket4(c, _mm256_cvtpd_ps(X), _mm256_cvtpd_ps(Z), &s, exact, &frac);
	/* edge | below << 32 | above << 48 */
	__m256i eb = _mm256_i32gather_epi64((const long long *)c->table, idx, 8);
	__m256i ebs = _mm256_permutevar8x32_epi32(eb, _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7));
	__m128 edge = _mm_castsi128_ps(_mm256_castsi256_si128(ebs));
	__m128i ba = _mm256_extracti128_si256(ebs, 1);
	__m128 d = _mm_sub_ps(s, edge);
	__m128 near = _mm_and_ps(_mm_cmplt_ps(d, c->near_width), _mm_cmpgt_ps(d, c->near_nwidth));
	__m128 low = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(ba, c->near_low), c->near_low));
	__m128 high = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(ba, c->near_high), c->near_high));
	near = _mm_or_ps(near, _mm_and_ps(low, _mm_cmplt_ps(frac, c->close)));
	near = _mm_or_ps(near, _mm_and_ps(high, _mm_cmplt_ps(_mm_sub_ps(c->one_f, frac), c->close)));
	*exact = _mm_or_ps(*exact, near);
	__m128i above = _mm_and_si128(_mm_srli_epi32(ba, 16), c->above);
	return _mm_castps_si128(_mm_blendv_ps(_mm_castsi128_ps(_mm_and_si128(ba, c->lo16)), _mm_castsi128_ps(above),
					      _mm_cmpge_ps(s, edge)));
}

/* The volume image of the front lobe of image front, front % M, and the
 * back lobe's image, (front + N/2) % N, in *back, on four lanes. */
AVX2_INLINE __m128i lobes4(const struct lanes4 *c, __m128i front, __m128i *back)
{
	__m128i k = _mm_add_epi32(front, c->half);
	*back = _mm_sub_epi32(k, _mm_andnot_si128(_mm_cmpgt_epi32(c->vN, k), c->vN));
	return _mm_sub_epi32(front, _mm_andnot_si128(_mm_cmpgt_epi32(c->vM, front), c->vM));
}

/* f truncated to an index below limit (max where f >= limit, 0 where f
 * is negative or NaN), on four lanes. */
AVX2_INLINE __m128i index4(const struct lanes4 *c, __m256d f, __m256d limit, __m128i max)
{
	__m128i i = _mm256_cvttpd_epi32(_mm256_and_pd(f, _mm256_cmp_pd(f, c->zero, _CMP_GE_OQ)));
	return _mm_blendv_epi8(i, max, _mm_castps_si128(_mm256_cvtpd_ps(_mm256_cmp_pd(f, limit, _CMP_GE_OQ))));
}

/* geometry_column() of X cos + Z sin of image k, on four lanes. */
AVX2_INLINE __m128i column4(const struct lanes4 *c, __m256d X, __m256d Z, __m128i k)
{
	__m128i k2 = _mm_add_epi32(k, k);
	__m256d S = _mm256_add_pd(_mm256_mul_pd(X, _mm256_i32gather_pd(c->dir, k2, 8)),
				  _mm256_mul_pd(Z, _mm256_i32gather_pd(c->dir + 1, k2, 8)));
	return index4(c, _mm256_mul_pd(_mm256_mul_pd(_mm256_add_pd(S, c->one), c->halfv), c->width), c->width, c->wmax);
}

/* geometry_row() of Y, on four lanes. */
AVX2_INLINE __m128i row4(const struct lanes4 *c, __m256d Y)
{
	__m256d fv = _mm256_mul_pd(_mm256_div_pd(_mm256_sub_pd(c->h, Y), c->h2), c->height);
	return index4(c, fv, c->height, c->hmax);
}

/* Points j0 .. j1 - 1 four at a time, with exactly point_exact()'s
 * operations (no fused multiply-adds: each product and sum rounded as the
 * scalar code rounds it); a point the slope table flags as near a slot
 * boundary, on the axis or not finite goes to point_exact(). Even N. */
__attribute__((target("avx2"))) static uint64_t stage_avx2(const struct bin_set *b, const struct scene_draw *d,
							   uint64_t j0, uint64_t j1, struct bin_point *recs,
							   uint16_t *keys, uint32_t *hist)
{
	struct lanes4 c;
	lanes4_init(&c, b, d);
	const bool mirrored = b->geom.mirrored, fast = stage_fast(b, d);
	const uint32_t turn = bin_draw_turn(b, d), slots = mirrored ? 1 : 2;
	const uint64_t hi = record_high(d->rgb, point_size(d));
	uint64_t j = j0;
	for (; j + 4 <= j1; j += 4) {
		__m256d x, y, z;
		load4(d->xyz + 3 * j, &x, &y, &z);
		__m256d fin = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
		__m256d X = transform4(&c, 0, x, y, z, &fin), Y = transform4(&c, 1, x, y, z, &fin);
		__m256d Z = transform4(&c, 2, x, y, z, &fin);
		__m128 exact;
		__m128i front = slot4(&c, X, Z, &exact);
		__m128i back, k0 = lobes4(&c, front, &back);
		/* records as 64-bit words (x86: little-endian): u, v, then the
		 * colour and size of hi */
		__m128i uv0 = _mm_or_si128(column4(&c, X, Z, k0), _mm_slli_epi32(row4(&c, Y), 16));
		unsigned ex = (unsigned)(_mm_movemask_ps(exact) | (~_mm256_movemask_pd(fin) & 0xF));
		if (fast) { /* 4 records, 4 keys at once; counted afterwards */
			_mm256_storeu_si256(
				(__m256i *)(recs + (j - j0)),
				_mm256_or_si256(_mm256_cvtepu32_epi64(uv0), _mm256_set1_epi64x((long long)hi)));
			_mm_storel_epi64((__m128i *)(keys + (j - j0)), _mm_packus_epi32(k0, k0));
			fast_exact_lanes(b, d, j, 4, ex, recs + (j - j0), keys + (j - j0), hist);
			continue;
		}
		uint32_t ka[4], kb[4], uva[4], ub[4];
		_mm_storeu_si128((__m128i *)ka, k0);
		_mm_storeu_si128((__m128i *)kb, back);
		_mm_storeu_si128((__m128i *)uva, uv0);
		_mm_storeu_si128((__m128i *)ub, mirrored ? _mm_setzero_si128() : column4(&c, X, Z, back));
		stage_lanes(b, d, j, 4, ex, ka, kb, uva, ub, hi, turn, recs + slots * (j - j0), keys + slots * (j - j0),
			    hist);
	}
	return j;
}

/* ---- eight points at a time (AVX-512: bin_lanes8.h) ---- */

#include "bin_lanes8.h"

/* stage_avx2() eight points at a time on AVX-512, with the same
 * operations lane for lane. */
AVX512_TARGET static uint64_t stage_avx512(const struct bin_set *b, const struct scene_draw *d, uint64_t j0,
					   uint64_t j1, struct bin_point *recs, uint16_t *keys, uint32_t *hist)
{
	struct lanes8 c;
	lanes8_init(&c, b, d);
	const bool mirrored = b->geom.mirrored, fast = stage_fast(b, d);
	const uint32_t turn = bin_draw_turn(b, d), slots = mirrored ? 1 : 2;
	const uint64_t hi = record_high(d->rgb, point_size(d));
	uint64_t j = j0;
	for (; j + 8 <= j1; j += 8) {
		__m512d x, y, z;
		load8(d->xyz + 3 * j, &x, &y, &z);
		__mmask8 fin = 0xFF;
		__m512d X = transform8(&c, 0, x, y, z, &fin), Y = transform8(&c, 1, x, y, z, &fin);
		__m512d Z = transform8(&c, 2, x, y, z, &fin);
		__m256 exact;
		__m256i front = slot8(&c, X, Z, &exact);
		__m256i back, k0 = lobes8(&c, front, &back);
		__m256i uv0 = _mm256_or_si256(column8(&c, X, Z, k0), _mm256_slli_epi32(row8(&c, Y), 16));
		unsigned ex = (unsigned)_mm256_movemask_ps(exact) | (~(unsigned)fin & 0xFF);
		if (fast) {
			_mm512_storeu_si512(
				(void *)(recs + (j - j0)),
				_mm512_or_si512(_mm512_cvtepu32_epi64(uv0), _mm512_set1_epi64((long long)hi)));
			_mm_storeu_si128((__m128i *)(keys + (j - j0)), _mm256_cvtepi32_epi16(k0));
			fast_exact_lanes(b, d, j, 8, ex, recs + (j - j0), keys + (j - j0), hist);
			continue;
		}
		uint32_t ka[8], kb[8], uva[8], ub[8];
		_mm256_storeu_si256((__m256i *)ka, k0);
		_mm256_storeu_si256((__m256i *)kb, back);
		_mm256_storeu_si256((__m256i *)uva, uv0);
		_mm256_storeu_si256((__m256i *)ub, mirrored ? _mm256_setzero_si256() : column8(&c, X, Z, back));
		stage_lanes(b, d, j, 8, ex, ka, kb, uva, ub, hi, turn, recs + slots * (j - j0), keys + slots * (j - j0),
			    hist);
	}
	return j;
}
/* A voxel (u, v) of volume image k set in a mask's bits (bin.h). */
static inline void mask_set(const struct bin_set *b, uint32_t *bits, uint32_t k, uint32_t u, uint32_t v)
{
	uint32_t tiles_x = volume_tiles_across(b->geom.width);
	size_t t = (size_t)k * volume_geometry_tiles(&b->geom) + (v / VOLUME_TILE) * tiles_x + u / VOLUME_TILE;
	bits[t * VOLUME_TILE + v % VOLUME_TILE] |= 1u << ((u % VOLUME_TILE) ^ 7);
}

/* Point j's records (the scalar rule) set in a mask. */
static void mask_exact(const struct bin_set *b, const struct scene_draw *d, uint64_t j, uint32_t *bits)
{
	struct bin_point r[2];
	uint32_t k[2];
	point_exact(b, d, d->xyz + 3 * j, d->rgb, 0, r, k);
	for (int i = 0; i < 2; i++)
		if (k[i] != NO_IMAGE)
			mask_set(b, bits, k[i], r[i].u, r[i].v);
}

/* mask_avx512()'s points at a time: in three passes over them (slot and
 * row, then column and bit, then the ORs), each a short chain whose
 * gathers and stores the next points' work overlaps. */
#define MASK_GROUPS 32
struct mask_block {
	__m512d X[MASK_GROUPS], Z[MASK_GROUPS];
	__m256i k[MASK_GROUPS], v[MASK_GROUPS];
	uint32_t word[8 * MASK_GROUPS], bit[8 * MASK_GROUPS];
	uint8_t ex[MASK_GROUPS];
};

/* The first pass on group g (points j .. j + 7): transform, front image,
 * row, and the lanes for the scalar rule. */
AVX512_INLINE void mask_slots(const struct lanes8 *c, const float *xyz, struct mask_block *m, unsigned g)
{
	__m512d x, y, z;
	load8(xyz, &x, &y, &z);
	__mmask8 fin = 0xFF;
	__m512d X = transform8(c, 0, x, y, z, &fin), Y = transform8(c, 1, x, y, z, &fin);
	__m512d Z = transform8(c, 2, x, y, z, &fin);
	__m256 exact;
	__m256i back;
	m->k[g] = lobes8(c, slot8(c, X, Z, &exact), &back);
	m->v[g] = row8(c, Y);
	m->X[g] = X;
	m->Z[g] = Z;
	m->ex[g] = (uint8_t)((unsigned)_mm256_movemask_ps(exact) | (~(unsigned)fin & 0xFF));
}

/* stage_avx512()'s fast path with each record's voxel set in a mask
 * instead: the same operations lane for lane, and the lanes it hands to
 * the scalar rule handed to it here. Returns the first point not done. */
AVX512_TARGET static uint64_t mask_avx512(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
					  uint32_t *bits)
{
	struct lanes8 c;
	struct mask_block m;
	lanes8_init(&c, b, d);
	const __m256i vtiles = _mm256_set1_epi32((int)volume_geometry_tiles(&b->geom));
	const __m256i vtx = _mm256_set1_epi32((int)volume_tiles_across(b->geom.width));
	const __m256i low = _mm256_set1_epi32(VOLUME_TILE - 1), seven = _mm256_set1_epi32(7);
	const __m256i one = _mm256_set1_epi32(1);
	uint64_t j = j0;
	while (j + 8 <= j1) {
		unsigned groups = (unsigned)((j1 - j) / 8 < MASK_GROUPS ? (j1 - j) / 8 : MASK_GROUPS);
		for (unsigned g = 0; g < groups; g++)
			mask_slots(&c, d->xyz + 3 * (j + 8 * g), &m, g);
		for (unsigned g = 0; g < groups; g++) {
			/* tile (k, v / 32, u / 32), its row v % 32, the bit of column u % 32 */
			__m256i k = m.k[g], u = column8(&c, m.X[g], m.Z[g], k), v = m.v[g];
			__m256i t = _mm256_add_epi32(_mm256_mullo_epi32(k, vtiles),
						     _mm256_add_epi32(_mm256_mullo_epi32(_mm256_srli_epi32(v, 5), vtx),
								      _mm256_srli_epi32(u, 5)));
			__mmask8 vec = (__mmask8)~m.ex[g]; /* the others: word 0, no bit */
			__m256i word = _mm256_maskz_add_epi32(vec, _mm256_slli_epi32(t, 5), _mm256_and_si256(v, low));
			__m256i bit =
				_mm256_maskz_sllv_epi32(vec, one, _mm256_xor_si256(_mm256_and_si256(u, low), seven));
			_mm256_storeu_si256((__m256i *)&m.word[8 * g], word);
			_mm256_storeu_si256((__m256i *)&m.bit[8 * g], bit);
		}
		for (unsigned i = 0; i < 8 * groups; i++)
			bits[m.word[i]] |= m.bit[i];
		for (unsigned g = 0; g < groups; g++)
			for (unsigned ex = m.ex[g]; ex; ex &= ex - 1)
				mask_exact(b, d, j + 8 * g + (uint64_t)__builtin_ctz(ex), bits);
		j += 8 * groups;
	}
	return j;
}
#endif

bool bin_points_isa_supported(enum bin_points_isa isa)
{
	switch (isa) {
	case BIN_POINTS_AUTO:
	case BIN_POINTS_SCALAR:
		return true;
#ifdef BIN_POINTS_X86
	case BIN_POINTS_AVX2:
		return __builtin_cpu_supports("avx2");
	case BIN_POINTS_AVX512:
		return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("avx512f") &&
		       __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
		       __builtin_cpu_supports("avx512bw");
#else
	default:
		return false;
#endif
	}
	return false;
}

/* The path that stages: the one asked for, the best there is for
 * BIN_POINTS_AUTO, or the scalar rule where the asked one is missing. */
static enum bin_points_isa isa_of(enum bin_points_isa want)
{
	if (want == BIN_POINTS_AUTO) {
		if (bin_points_isa_supported(BIN_POINTS_AVX512))
			return BIN_POINTS_AVX512;
		return bin_points_isa_supported(BIN_POINTS_AVX2) ? BIN_POINTS_AVX2 : BIN_POINTS_SCALAR;
	}
	return bin_points_isa_supported(want) ? want : BIN_POINTS_SCALAR;
}

void bin_points_stage(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
		      struct bin_point *recs, uint16_t *keys, uint32_t *hist)
{
	uint32_t turn = bin_draw_turn(b, d);
	uint64_t j = j0;
#ifdef BIN_POINTS_X86
	const uint32_t slots = bin_slots(b);
	enum bin_points_isa isa = b->geom.images_per_rev % 2 == 0 ? isa_of(b->points_isa) : BIN_POINTS_SCALAR;
	if (isa == BIN_POINTS_AVX512)
		j = stage_avx512(b, d, j0, j1, recs, keys, hist);
	if (isa != BIN_POINTS_SCALAR) /* what is left, or all */
		j = stage_avx2(b, d, j, j1, recs + slots * (j - j0), keys + slots * (j - j0), hist);
	if (isa != BIN_POINTS_SCALAR && stage_fast(b, d)) /* the vector paths' records, counted */
		for (uint64_t i = 0; i < j - j0; i++)
			if (keys[i] != PKEY_NONE)
				hist[keys[i] & PKEY_IMAGE]++;
#endif
	for (; j < j1; j++)
		stage_exact(b, d, j, turn, recs, keys, j - j0, hist);
}

void bin_points_scatter(struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
			const struct bin_point *recs, const uint16_t *keys, uint32_t *off)
{
	struct bin_point *out = b->points;
	if (!b->geom.mirrored) {
		for (uint64_t i = 0; i < 2 * (j1 - j0); i++)
			if (keys[i] != PKEY_NONE)
				out[off[keys[i]]++] = recs[i];
		return;
	}
	for (uint64_t i = 0; i < j1 - j0; i++) {
		uint32_t key = keys[i];
		if (key == PKEY_NONE)
			continue;
		out[off[key & PKEY_IMAGE]++] = recs[i];
		if (key & PKEY_SECOND) { /* a rounding tie: made again */
			struct bin_point r[2];
			uint32_t k[2];
			uint64_t jj = j0 + i;
			point_exact(b, d, d->xyz + 3 * jj, point_rgb(d, jj), bin_draw_turn(b, d), r, k);
			out[off[k[1]]++] = r[1];
		}
	}
}

bool bin_points_maskable(const struct bin_set *b, const struct scene_draw *d, uint64_t lo, uint64_t hi)
{
#ifdef BIN_POINTS_X86
	return b->point_masks && stage_fast(b, d) && point_size(d) == 1 && b->geom.images_per_rev % 2 == 0 &&
	       isa_of(b->points_isa) == BIN_POINTS_AVX512 && hi - lo >= bin_mask_words(b);
#else
	return false;
#endif
}

void bin_points_mask(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1, uint32_t *bits)
{
	uint64_t j = j0;
#ifdef BIN_POINTS_X86
	j = mask_avx512(b, d, j0, j1, bits);
#endif
	for (; j < j1; j++)
		mask_exact(b, d, j, bits);
}
