#include "bin.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "pool.h"

#if defined(__x86_64__)
#include <immintrin.h>
#define BIN_TRIS_X86 1
#endif

#define KEY_NONE UINT32_MAX
/* A staged primitive's key holds its sort key (class * M + first) in the
 * low KEY_BITS bits and its turn (mod N) above them: sort keys are below
 * 15 * 16384 < 2^18 (M <= 16384, so at most 15 classes) and turns below
 * N <= 16384 = 2^14, so no key is KEY_NONE. Point keys are images. */
#define KEY_BITS 18
#define KEY_MASK ((1u << KEY_BITS) - 1)
_Static_assert(BIN_MAX_CLASSES * 16384u <= (1u << KEY_BITS) && 16384u <= (1u << (32 - KEY_BITS)),
	       "sort key and turn share a staged key");

/* The first primitive and first point item of a draw. */
struct draw_base {
	uint64_t prim, point;
};

/* A record and its sort key (KEY_NONE: unused). */
struct stage_prim {
	struct bin_prim rec;
	uint32_t key;
};

struct bin_work {
	const struct scene *scene;
	unsigned threads;
	uint64_t prim_items, point_items;
	struct draw_base *base; /* per draw */
	size_t base_cap;
	/* bin_slots() staging entries per item (unmirrored, a primitive
	 * may need two records); unused ones have key KEY_NONE. */
	struct stage_prim *stage_prims;
	size_t stage_prims_cap;
	/* bin_slots() records and keys per point (bin.h), as for the
	 * primitives above. */
	struct bin_point *point_recs;
	size_t point_recs_cap;
	uint16_t *point_keys;
	size_t point_keys_cap;
	uint32_t *hist; /* threads x (prim keys + point keys) */
	size_t hist_cap;
	size_t prim_cap, point_cap, turn_cap; /* of the sorted arrays */
	/* With bin_set.keep: the draws of the scene the set holds, while
	 * valid. */
	bool valid;
	struct scene_draw *kept;
	uint32_t kept_count;
	size_t kept_cap;
};

static uint32_t prim_keys(const struct bin_set *b)
{
	return b->classes * b->images;
}

static unsigned ceil_log2(uint32_t x)
{
	unsigned c = 0;
	while ((1u << c) < x)
		c++;
	return c;
}

int bin_init(struct bin_set *b, const struct geometry *g)
{
	memset(b, 0, sizeof(*b));
	b->geom = *g;
	b->images = geometry_images_per_volume(g);
	b->classes = ceil_log2(b->images) + 1;
	b->dir = malloc(2 * sizeof(double) * b->images);
	b->prim_start = calloc(prim_keys(b) + 1, sizeof(*b->prim_start));
	b->point_start = calloc(b->images + 1, sizeof(*b->point_start));
	b->work = calloc(1, sizeof(*b->work));
	if (!b->dir || !b->prim_start || !b->point_start || !b->work ||
	    slot_table_init(&b->slots, g->images_per_rev) < 0) {
		bin_finish(b);
		return -ENOMEM;
	}
	for (uint32_t k = 0; k < b->images; k++) {
		double theta = geometry_image_angle(g, k);
		b->dir[2 * k] = cos(theta);
		b->dir[2 * k + 1] = sin(theta);
	}
	return 0;
}

void bin_finish(struct bin_set *b)
{
	struct bin_work *w = b->work;
	if (w) {
		free(w->base);
		free(w->stage_prims);
		free(w->point_recs);
		free(w->point_keys);
		free(w->hist);
		free(w->kept);
		free(w);
	}
	slot_table_finish(&b->slots);
	free(b->dir);
	free(b->prims);
	free(b->prim_turn);
	free(b->prim_start);
	free(b->points);
	free(b->point_start);
	memset(b, 0, sizeof(*b));
}

/* ---- per item ---- */

static int draw_verts(const struct scene_draw *d)
{
	switch (d->prim) {
	case SCENE_POINTS:
		return 1;
	case SCENE_LINES:
		return 2;
	case SCENE_TRIANGLES:
		return 3;
	case SCENE_GRID: /* no vertices: sampled per image (grid.h) */
		return 0;
	}
	return 0;
}

/* The closed arc of slots [*first, *first + *len) (mod N) holding the
 * xz projection of the n vertices (negated when neg: the s < 0 lobe).
 * False when the projection may touch the axis: every slot. */
static bool prim_arc(const struct bin_set *b, const float (*v)[3], int n, bool neg, uint32_t *first, uint32_t *len)
{
	uint32_t s[3] = { 0 }, N = b->slots.n;
	bool near = false;
	float sign = neg ? -1.0f : 1.0f;
	for (int i = 0; i < n; i++) {
		s[i] = slot_of(&b->slots, sign * v[i][0], sign * v[i][2], &near);
		if (s[i] == SLOT_AXIS)
			return false;
		for (int j = i; j > 0 && s[j - 1] > s[j]; j--) {
			uint32_t t = s[j];
			s[j] = s[j - 1];
			s[j - 1] = t;
		}
	}
	/* The largest circular gap between the vertices' slots; vertex angles
	 * are within half a slot of their slot's centre, or one slot more
	 * when near a boundary. The hull misses the axis iff some angular gap
	 * exceeds pi. */
	uint32_t gap = s[0] + N - s[n - 1], start = s[0], end = s[n - 1];
	for (int i = 0; i + 1 < n; i++) {
		if (s[i + 1] - s[i] > gap) {
			gap = s[i + 1] - s[i];
			start = s[i + 1];
			end = s[i];
		}
	}
	uint32_t slack = near ? 3 : 1;
	if (gap <= slack || 2 * (gap - slack) <= N)
		return false;
	*len = end + N - start; /* mod N, without a division: below 2N */
	*len = (*len >= N ? *len - N : *len) + 1;
	*first = start;
	if (near) {
		*first = (start + N - 1) % N;
		*len += 2;
	}
	return *len < N;
}

static void prim_key(const struct bin_set *b, struct stage_prim *s, uint32_t first, uint32_t count)
{
	if (count >= b->images) {
		first = 0;
		count = b->images;
	}
	s->rec.first = (uint16_t)first;
	s->rec.count = (uint16_t)count;
	/* ceil_log2(count), count >= 1, without its loop */
	unsigned cls = count > 1 ? 32 - (unsigned)__builtin_clz(count - 1) : 0;
	s->key = cls * b->images + first;
}

/* Records (one or two: out has bin_slots() entries) of one segment or
 * triangle. */
static void bin_one_prim(const struct bin_set *b, const struct scene_draw *d, const float *xyz, int n,
			 const uint8_t rgb[3], struct stage_prim *out)
{
	double t[3][3];
	out[0].key = KEY_NONE;
	if (!b->geom.mirrored)
		out[1].key = KEY_NONE;
	for (int i = 0; i < n; i++)
		if (!bin_transform(d->transform, xyz + 3 * i, t[i]))
			return; /* NaN or infinite: nothing sensible to light */
	struct bin_prim *p = &out[0].rec;
	for (int i = 0; i < n; i++)
		for (int j = 0; j < 3; j++)
			p->v[i][j] = (float)t[i][j];
	p->nverts = (uint8_t)n;
	memcpy(p->rgb, rgb, 3);
	uint32_t M = b->images, first, len, bf, bl;
	if (!prim_arc(b, (const float(*)[3])p->v, n, false, &first, &len)) {
		prim_key(b, &out[0], 0, M);
	} else if (b->geom.mirrored) {
		/* both lobes fold onto M images: first < N = 2M */
		prim_key(b, &out[0], first >= M ? first - M : first, len);
	} else if (!prim_arc(b, (const float(*)[3])p->v, n, true, &bf, &bl) || len + bl >= M) {
		prim_key(b, &out[0], 0, M);
	} else {
		out[1].rec = *p;
		prim_key(b, &out[0], first, len);
		prim_key(b, &out[1], bf, bl);
	}
}

/* Turns the staged records of a segment or triangle by turn (1 .. N-1):
 * the range shifts by turn mod M (every image stays 0 .. M-1), and the turn
 * goes above the sort key for the scatter to keep (bin_set.prim_turn). */
static void turn_prims(const struct bin_set *b, uint32_t turn, struct stage_prim *s)
{
	uint32_t M = b->images;
	for (uint32_t i = 0; i < bin_slots(b); i++) {
		if (s[i].key == KEY_NONE)
			continue;
		uint32_t was = s[i].rec.first, first = was;
		if (s[i].rec.count < M) {
			first = (was + turn % M) % M;
			s[i].rec.first = (uint16_t)first;
		}
		s[i].key = (s[i].key - was + first) | turn << KEY_BITS; /* class * M + first */
	}
}

/* ---- the parallel build ---- */

struct chunk {
	uint64_t lo, hi;
};

static struct chunk chunk_of(uint64_t items, unsigned threads, unsigned w)
{
	return (struct chunk){ items * w / threads, items * (w + 1) / threads };
}

/* The segments or triangles of draw di in chunk c: [*lo, *hi), false
 * when none. */
static bool prim_run(const struct bin_work *w, uint32_t di, struct chunk c, uint64_t *lo, uint64_t *hi)
{
	const struct scene_draw *d = &w->scene->draws[di];
	int nv = draw_verts(d);
	if (nv < 2 || !d->xyz)
		return false;
	uint64_t base = w->base[di].prim, end = base + d->count / (uint32_t)nv;
	*lo = base > c.lo ? base : c.lo;
	*hi = end < c.hi ? end : c.hi;
	return *lo < *hi;
}

/* The points of draw di in chunk c: [*lo, *hi), false when none. */
static bool point_run(const struct bin_work *w, uint32_t di, struct chunk c, uint64_t *lo, uint64_t *hi)
{
	const struct scene_draw *d = &w->scene->draws[di];
	if (draw_verts(d) != 1 || !d->xyz)
		return false;
	uint64_t base = w->base[di].point, end = base + d->count;
	*lo = base > c.lo ? base : c.lo;
	*hi = end < c.hi ? end : c.hi;
	return *lo < *hi;
}

/* Adds the keys of an item's staged records (slots of them) to a
 * histogram; their turn is masked off. */
static inline void count_keys(uint32_t *hist, const struct stage_prim *s, uint32_t slots)
{
	for (uint32_t i = 0; i < slots; i++)
		if (s[i].key != KEY_NONE)
			hist[s[i].key & KEY_MASK]++;
}

/* A staged item's records turned by its draw's turn, and counted. */
static inline void finish_item(const struct bin_set *b, uint32_t turn, struct stage_prim *s, uint32_t *hist)
{
	if (turn)
		turn_prims(b, turn, s);
	count_keys(hist, s, bin_slots(b));
}

#ifdef BIN_TRIS_X86
/* The instruction sets of bin_points.c's AVX-512 path, which
 * bin_points_isa_supported(BIN_POINTS_AVX512) checks. */
#define TRIS_TARGET __attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2")))

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
	__m256i idx = _mm256_add_epi32(_mm256_mullo_epi32(octant, _mm256_set1_epi32((int)t->buckets + 1)),
				       _mm256_cvttps_epi32(_mm256_mul_ps(s, _mm256_set1_ps((float)t->buckets))));
	__m256i idx3 = _mm256_add_epi32(_mm256_add_epi32(idx, idx), idx);
	const float *table = (const float *)t->b;
	__m512i eb = _mm512_i32gather_epi64(idx3, table, 4); /* edge | below << 32 | above << 48 */
	__m256 nearv = _mm256_i32gather_ps(table + 2, idx3, 4);
	__m256 edge = _mm256_castsi256_ps(_mm512_cvtepi64_epi32(eb));
	__m256i ba = _mm512_cvtepi64_epi32(_mm512_srli_epi64(eb, 32));
	__m256 dd = _mm256_sub_ps(s, nearv);
	*near |= _mm256_cmp_ps_mask(dd, _mm256_set1_ps(1e-5f), _CMP_LT_OS) &
		 _mm256_cmp_ps_mask(dd, _mm256_set1_ps(-1e-5f), _CMP_GT_OS);
	return _mm256_mask_blend_epi32(_mm256_cmp_ps_mask(s, edge, _CMP_GE_OS),
				       _mm256_and_si256(ba, _mm256_set1_epi32(0xFFFF)), _mm256_srli_epi32(ba, 16));
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
 * bin_transform() groups it, in float (f, and v by coordinate and lane);
 * returns the lanes whose coordinates are all finite floats. */
TRIS_TARGET static inline __mmask8 vertex8(const float m[16], const __m512 r[5], int i, __m256 f[3], float v[3][8])
{
	__m512d x = _mm512_cvtps_pd(column9(r, 3 * i));
	__m512d y = _mm512_cvtps_pd(column9(r, 3 * i + 1));
	__m512d z = _mm512_cvtps_pd(column9(r, 3 * i + 2));
	__mmask8 fin = 0xFF;
	for (int c = 0; c < 3; c++) {
		__m512d t = _mm512_add_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(m[c]), x),
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
			finish_item(b, turn, &out[l], hist);
	}
}

/* bin_one_prim() of triangles j0 .. j1 - 1 of d, eight at a time, on a
 * mirrored geometry: the same operations lane for lane (the transform
 * grouped as bin_transform() groups it, the slots as slot_of() finds
 * them); a lane with a coordinate that is not a finite float goes to
 * bin_one_prim(). Returns the first triangle not staged. */
TRIS_TARGET static uint64_t stage_tris8(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
					struct stage_prim *out, uint32_t *hist)
{
	const float *m = d->transform;
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
			fin &= vertex8(m, r, i, f, v[i]);
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

/* The staged records of items j0 .. j1 - 1 of draw d (out: item j0's
 * bin_slots() entries), turned and counted in hist: triangles on a
 * mirrored geometry eight at a time where the CPU can (unless
 * b->prims_scalar), the rest one by one. */
static void stage_prims(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
			struct stage_prim *out, uint32_t *hist)
{
	const int nv = draw_verts(d);
	const uint32_t slots = bin_slots(b), turn = bin_draw_turn(b, d);
	uint64_t j = j0;
#ifdef BIN_TRIS_X86
	if (nv == 3 && b->geom.mirrored && !b->prims_scalar && bin_points_isa_supported(BIN_POINTS_AVX512))
		j = stage_tris8(b, d, j0, j1, out, hist);
#endif
	for (; j < j1; j++) {
		struct stage_prim *s = &out[slots * (j - j0)];
		bin_one_prim(b, d, d->xyz + j * (uint64_t)nv * 3, nv, d->prim_rgb ? d->prim_rgb + 3 * j : d->rgb, s);
		finish_item(b, turn, s, hist);
	}
}

static void count_job(void *arg, unsigned t)
{
	struct bin_set *b = arg;
	struct bin_work *w = b->work;
	uint32_t pk = prim_keys(b);
	uint32_t *hist = w->hist + (size_t)t * (pk + b->images);
	struct chunk c = chunk_of(w->prim_items, w->threads, t);
	const uint32_t slots = bin_slots(b);
	for (uint32_t di = 0; di < w->scene->draw_count; di++) {
		uint64_t lo, hi, base = w->base[di].prim;
		if (prim_run(w, di, c, &lo, &hi))
			stage_prims(b, &w->scene->draws[di], lo - base, hi - base, &w->stage_prims[slots * lo], hist);
	}
	c = chunk_of(w->point_items, w->threads, t);
	for (uint32_t di = 0; di < w->scene->draw_count; di++) {
		uint64_t lo, hi, base = w->base[di].point;
		if (point_run(w, di, c, &lo, &hi))
			bin_points_stage(b, &w->scene->draws[di], lo - base, hi - base, w->point_recs + slots * lo,
					 w->point_keys + slots * lo, hist + pk);
	}
}

/* Each thread's records go, in item order, to its own offsets: the result
 * is the same whatever the thread count. */
static void scatter_job(void *arg, unsigned t)
{
	struct bin_set *b = arg;
	struct bin_work *w = b->work;
	uint32_t pk = prim_keys(b);
	uint32_t *off = w->hist + (size_t)t * (pk + b->images);
	struct chunk c = chunk_of(w->prim_items, w->threads, t);
	/* Indexed, not pointer-stepped: a scene without lines or triangles
	 * (or points) has no staging array at all. */
	const uint32_t slots = bin_slots(b);
	if (!b->turned) {
		for (uint64_t i = slots * c.lo; i < slots * c.hi; i++)
			if (w->stage_prims[i].key != KEY_NONE)
				b->prims[off[w->stage_prims[i].key]++] = w->stage_prims[i].rec;
	} else {
		for (uint64_t i = slots * c.lo; i < slots * c.hi; i++) {
			uint32_t key = w->stage_prims[i].key;
			if (key == KEY_NONE)
				continue;
			uint32_t o = off[key & KEY_MASK]++;
			b->prims[o] = w->stage_prims[i].rec;
			b->prim_turn[o] = (uint16_t)(key >> KEY_BITS);
		}
	}
	c = chunk_of(w->point_items, w->threads, t);
	for (uint32_t di = 0; di < w->scene->draw_count; di++) {
		uint64_t lo, hi, base = w->base[di].point;
		if (point_run(w, di, c, &lo, &hi))
			bin_points_scatter(b, &w->scene->draws[di], lo - base, hi - base, w->point_recs + slots * lo,
					   w->point_keys + slots * lo, off + pk);
	}
}

static int grow(void **p, size_t *cap, size_t need, size_t size)
{
	if (need <= *cap)
		return 0;
	size_t n = *cap ? *cap : 256;
	while (n < need)
		n *= 2;
	void *q = realloc(*p, n * size);
	if (!q)
		return -ENOMEM;
	*p = q;
	*cap = n;
	return 0;
}

/* Counts items and sizes the work space. */
static int prepare(struct bin_set *b, const struct scene *scene, unsigned threads)
{
	struct bin_work *w = b->work;
	uint32_t draws = scene ? scene->draw_count : 0;
	b->turned = false;
	int r = grow((void **)&w->base, &w->base_cap, draws, sizeof(*w->base));
	if (r < 0)
		return r;
	w->scene = scene;
	w->threads = threads;
	w->prim_items = w->point_items = 0;
	for (uint32_t i = 0; i < draws; i++) {
		const struct scene_draw *d = &scene->draws[i];
		int nv = draw_verts(d);
		w->base[i] = (struct draw_base){ w->prim_items, w->point_items };
		if (nv == 0 || !d->xyz)
			continue;
		if (nv == 1) {
			w->point_items += d->count;
		} else {
			w->prim_items += d->count / (uint32_t)nv;
			b->turned |= bin_draw_turn(b, d) != 0;
		}
	}
	if (w->prim_items > INT32_MAX || w->point_items > INT32_MAX)
		return -E2BIG;
	size_t keys = prim_keys(b) + b->images;
	if ((r = grow((void **)&w->stage_prims, &w->stage_prims_cap, bin_slots(b) * w->prim_items,
		      sizeof(*w->stage_prims))) < 0 ||
	    (r = grow((void **)&w->point_recs, &w->point_recs_cap, bin_slots(b) * w->point_items,
		      sizeof(*w->point_recs))) < 0 ||
	    (r = grow((void **)&w->point_keys, &w->point_keys_cap, bin_slots(b) * w->point_items,
		      sizeof(*w->point_keys))) < 0 ||
	    (r = grow((void **)&w->hist, &w->hist_cap, threads * keys, sizeof(uint32_t))) < 0)
		return r;
	memset(w->hist, 0, threads * keys * sizeof(uint32_t));
	return 0;
}

/* Turns the per-thread counts into per-thread offsets, key-major, and the
 * per-key starts; returns the totals. */
/* Keys [from, to) of prefix(): each key's start in start[key - from],
 * each thread's histogram entry its own start; returns the total. */
static uint64_t prefix_keys(struct bin_work *w, uint32_t keys, uint32_t from, uint32_t to, uint32_t *start)
{
	uint64_t run = 0;
	if (w->threads == 1) { /* small scenes: a key is one histogram entry */
		for (uint32_t key = from; key < to; key++) {
			uint32_t n = w->hist[key];
			start[key - from] = w->hist[key] = (uint32_t)run;
			run += n;
		}
		return run;
	}
	for (uint32_t key = from; key < to; key++) {
		start[key - from] = (uint32_t)run;
		for (unsigned t = 0; t < w->threads; t++) {
			uint32_t *h = &w->hist[(size_t)t * keys + key];
			uint32_t n = *h;
			*h = (uint32_t)run;
			run += n;
		}
	}
	return run;
}

static void prefix(struct bin_set *b, uint64_t *prims, uint64_t *points)
{
	struct bin_work *w = b->work;
	uint32_t pk = prim_keys(b), keys = pk + b->images;
	*prims = prefix_keys(w, keys, 0, pk, b->prim_start);
	*points = prefix_keys(w, keys, pk, keys, b->point_start);
	b->prim_start[pk] = (uint32_t)*prims;
	b->point_start[b->images] = (uint32_t)*points;
}

/* Vertices in the scene: few are binned on the calling thread, as waking
 * the pool would cost more than the work. */
static bool small_scene(const struct scene *scene)
{
	uint64_t v = 0;
	for (uint32_t i = 0; i < scene->draw_count && v <= BIN_SERIAL_VERTICES; i++)
		v += scene->draws[i].count;
	return v <= BIN_SERIAL_VERTICES;
}

/* bin_build()'s build. */
static int bin_scene(struct bin_set *b, const struct scene *scene, struct pool *pool)
{
	struct bin_work *w = b->work;
	bool serial = small_scene(scene);
	int r = prepare(b, scene, serial ? 1 : pool_workers(pool));
	if (r < 0)
		return r;
	if (serial)
		count_job(b, 0);
	else
		pool_run(pool, count_job, b);
	uint64_t prims = 0, points = 0;
	prefix(b, &prims, &points);
	if ((r = grow((void **)&b->prims, &w->prim_cap, prims, sizeof(struct bin_prim))) < 0 ||
	    (r = grow((void **)&b->points, &w->point_cap, points, sizeof(struct bin_point))) < 0 ||
	    (b->turned && (r = grow((void **)&b->prim_turn, &w->turn_cap, prims, sizeof(uint16_t))) < 0))
		return r;
	b->prim_count = (uint32_t)prims;
	b->point_count = (uint32_t)points;
	if (serial)
		scatter_job(b, 0);
	else
		pool_run(pool, scatter_job, b);
	return 0;
}

/* Whether the set holds scene's binning: the draws it was built from, each
 * the same (scene.h) and numbered where it is binned (keep_scene()), which
 * makes the data the same too. */
static bool scene_kept(const struct bin_work *w, const struct scene *scene)
{
	if (!w->valid || !scene->draw_count || scene->draw_count != w->kept_count)
		return false;
	for (uint32_t i = 0; i < scene->draw_count; i++)
		if (!scene_draw_same(&scene->draws[i], &w->kept[i]))
			return false;
	return true;
}

/* After a build of scene: its draws noted, where every one that is binned
 * has a number. */
static void keep_scene(struct bin_work *w, const struct scene *scene)
{
	for (uint32_t i = 0; i < scene->draw_count; i++)
		if (scene->draws[i].prim != SCENE_GRID && !scene->draws[i].data_id)
			return;
	if (!scene->draw_count || grow((void **)&w->kept, &w->kept_cap, scene->draw_count, sizeof(*w->kept)) < 0)
		return;
	memcpy(w->kept, scene->draws, scene->draw_count * sizeof(*w->kept));
	w->kept_count = scene->draw_count;
	w->valid = true;
}

int bin_build(struct bin_set *b, const struct scene *scene, struct pool *pool)
{
	static const struct scene empty;
	struct bin_work *w = b->work;
	if (!scene)
		scene = &empty;
	b->kept = b->keep && scene_kept(w, scene);
	if (b->kept)
		return 0;
	w->valid = false;
	int r = bin_scene(b, scene, pool);
	if (r == 0 && b->keep)
		keep_scene(w, scene);
	return r;
}

unsigned bin_runs(const struct bin_set *b, uint32_t k, struct bin_run *out)
{
	uint32_t M = b->images;
	unsigned n = 0;
	for (unsigned c = 0; c < b->classes; c++) {
		const uint32_t *st = &b->prim_start[c * M];
		if (st[0] == st[M])
			continue;
		uint32_t window = 1u << c;
		if (window >= M) {
			out[n++] = (struct bin_run){ st[0], st[M] };
		} else if (k + 1 >= window) {
			out[n++] = (struct bin_run){ st[k + 1 - window], st[k + 1] };
		} else {
			out[n++] = (struct bin_run){ st[0], st[k + 1] };
			out[n++] = (struct bin_run){ st[M + k + 1 - window], st[M] };
		}
	}
	return n;
}
