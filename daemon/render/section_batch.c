/* Segments or triangles of one image sectioned eight at a time (section.h,
 * section_lanes()): the same operations as section_prim()'s, in the
 * same order, on eight lanes of doubles, for the cases that make up most
 * of a dense mesh; every other lane goes to section_prim() itself.
 *
 * A lane follows prim_body(), lobe_piece() and raster_rows() (section.c)
 * step for step:
 * - d1, d2 and their sum's range; a lane reaching both lobes leaves for
 *   section_prim(); one in the brightness band keeps its piece's s range,
 *   and its spans are lit by section_weighted_runs() as raster_convex()
 *   lights them;
 * - the lobe's in-counts; none inside a plane: nothing;
 * - Sutherland-Hodgman passes: by plane 1 where some vertex is outside it,
 *   then by plane 2 where that cuts what is left; else by plane 2 alone
 *   (every vertex inside both: the pass keeps them as they are). A pass's
 *   output is kept in slots, each vertex followed by the cut point of the
 *   edge it starts; a slot the pass does not emit repeats the one before it
 *   (cyclically), so the slots' consecutive pairs are the polygon's edges
 *   plus edges of no length, which raster_rows() skips (y0 == y1), and
 *   their vertices are the polygon's;
 * - rows from the extreme y; a piece in more than MAX_ROWS rows leaves;
 * - per row, the s range of the vertices in the row's slab and of the
 *   edges' crossings of its inner line, then the columns. Minimum and
 *   maximum give the same values in any order. */
#include "section.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

#if defined(__x86_64__)
#include <immintrin.h>
#define SECTION_BATCH_X86 1
#endif

/* A lane's vertices as doubles (as raster_image() converts them). */
static void lane_vertices(const struct section_lane *t, int verts, double v[3][3])
{
	for (int i = 0; i < verts; i++)
		for (int j = 0; j < 3; j++)
			v[i][j] = t->v[3 * i + j];
}

/* section_prim() of each of the n primitives, one by one. */
static void one_by_one(struct section_canvas *c, const struct section_wedge *w, const struct section_lane *t,
		       unsigned n, int verts)
{
	for (unsigned l = 0; l < n; l++) {
		double v[3][3] = { { 0 } };
		lane_vertices(&t[l], verts, v);
		section_prim(c, w, (const double(*)[3])v, verts, t[l].rgb);
	}
}

#ifdef SECTION_BATCH_X86

#define TARGET __attribute__((target("avx512f,avx512dq,avx512vl")))

/* Slots of a piece: 6 after one clip of a triangle, 12 after two. */
#define MAX_SLOTS 12

/* The most rows a piece may span here; taller ones go to section_prim(). */
#define MAX_ROWS 8

/* A piece in slots (lanes of x, y, z), each the polygon's vertex or a
 * repeat of the one before it. */
struct slots {
	int n;
	__m512d x[MAX_SLOTS], y[MAX_SLOTS], z[MAX_SLOTS];
};

/* What the eight lanes light: from row[l] on, rows of spans u0..u1,
 * lane l's row r where bit l of lit[r] is set. */
struct lanes_out {
	__mmask8 weighted;   /* lanes whose spans section_weighted_runs() lights */
	double lo[8], hi[8]; /* each piece's s range */
	uint32_t rows;
	uint32_t row[8];
	uint32_t u0[MAX_ROWS][8], u1[MAX_ROWS][8];
	__mmask8 lit[MAX_ROWS];
};

/* An edge of the slot polygon, its lower end first (edges_init()). */
struct edge {
	__m512d y0, y1, s0, dsdy;
	__mmask8 rising; /* y1 > y0: the others cross nothing */
};

/* geometry_clamp_index_() on eight lanes. */
TARGET static inline __m512i clamp_index(__m512d f, uint32_t n)
{
	__mmask8 ok = _mm512_cmp_pd_mask(f, _mm512_setzero_pd(), _CMP_GE_OQ);
	__mmask8 over = _mm512_cmp_pd_mask(f, _mm512_set1_pd((double)n), _CMP_GE_OQ);
	__m256i i = _mm512_maskz_cvttpd_epi32(ok & ~over, f);
	i = _mm256_mask_mov_epi32(i, over, _mm256_set1_epi32((int)(n - 1)));
	return _mm512_cvtepu32_epi64(i);
}

/* canvas_row() (section.c) on eight lanes. */
TARGET static inline __m512i lane_rows(const struct section_canvas *c, __m512d y)
{
	double h = c->geom.half_height;
	__m512d d = _mm512_sub_pd(_mm512_set1_pd(h), y), f;
	if (c->row_scale == 0.0)
		f = _mm512_mul_pd(_mm512_div_pd(d, _mm512_set1_pd(2.0 * h)), _mm512_set1_pd((double)c->geom.height));
	else
		f = _mm512_mul_pd(_mm512_mul_pd(d, _mm512_set1_pd(c->row_scale)),
				  _mm512_set1_pd((double)c->geom.height));
	return clamp_index(f, c->geom.height);
}

/* geometry_column() on eight lanes. */
TARGET static inline __m512i lane_columns(const struct section_canvas *c, __m512d s)
{
	/* (s + 1) / 2 == (s + 1) * 0.5 exactly: both round the same real */
	__m512d f = _mm512_mul_pd(_mm512_mul_pd(_mm512_add_pd(s, _mm512_set1_pd(1.0)), _mm512_set1_pd(0.5)),
				  _mm512_set1_pd((double)c->geom.width));
	return clamp_index(f, c->geom.width);
}

/* edges_init() of the slot polygon's edges (per lane). */
TARGET static inline void edges_of(int n, const __m512d *s, const __m512d *y, struct edge *e)
{
	for (int j = 0; j < n; j++) {
		int k = j + 1 < n ? j + 1 : 0;
		__mmask8 swap = _mm512_cmp_pd_mask(y[j], y[k], _CMP_GT_OQ);
		e[j].y0 = _mm512_mask_blend_pd(swap, y[j], y[k]);
		e[j].y1 = _mm512_mask_blend_pd(swap, y[k], y[j]);
		e[j].s0 = _mm512_mask_blend_pd(swap, s[j], s[k]);
		__m512d s1 = _mm512_mask_blend_pd(swap, s[k], s[j]);
		e[j].rising = _mm512_cmp_pd_mask(e[j].y1, e[j].y0, _CMP_GT_OQ);
		e[j].dsdy =
			_mm512_maskz_div_pd(e[j].rising, _mm512_sub_pd(s1, e[j].s0), _mm512_sub_pd(e[j].y1, e[j].y0));
	}
}

/* edges_cross() at line y (per lane). */
TARGET static inline void cross_edges(int n, const struct edge *e, __m512d line, __m512d *lo, __m512d *hi)
{
	for (int j = 0; j < n; j++) {
		__mmask8 on = _mm512_cmp_pd_mask(line, e[j].y0, _CMP_GE_OQ) &
			      _mm512_cmp_pd_mask(line, e[j].y1, _CMP_LE_OQ) & e[j].rising;
		__m512d at = _mm512_add_pd(e[j].s0, _mm512_mul_pd(_mm512_sub_pd(line, e[j].y0), e[j].dsdy));
		*lo = _mm512_mask_min_pd(*lo, on, *lo, at);
		*hi = _mm512_mask_max_pd(*hi, on, *hi, at);
	}
}

/* The s range of the slots whose y lies in [ylo, yhi]. */
TARGET static inline void slab_vertices(int n, const __m512d *s, const __m512d *y, __m512d ylo, __m512d yhi,
					__m512d *lo, __m512d *hi)
{
	for (int j = 0; j < n; j++) {
		__mmask8 in = _mm512_cmp_pd_mask(y[j], ylo, _CMP_GE_OQ) & _mm512_cmp_pd_mask(y[j], yhi, _CMP_LE_OQ);
		*lo = _mm512_mask_min_pd(*lo, in, *lo, s[j]);
		*hi = _mm512_mask_max_pd(*hi, in, *hi, s[j]);
	}
}

/* One pass keeping n.p >= 0 (clip_plane()) of the polygon in, into out
 * (twice the slots: each vertex, then the cut point of the edge it starts;
 * a slot not emitted repeats the emitted one before it). Lanes in keep
 * keep every vertex (no pass). Returns the lanes with a piece left. */
TARGET static inline __mmask8 clip_slots(const struct slots *in, __m512d nx, __m512d nz, __mmask8 keep_all,
					 struct slots *out)
{
	const int n = in->n;
	__m512d dp[MAX_SLOTS / 2];
	__mmask8 keep[MAX_SLOTS / 2], valid[MAX_SLOTS], any = 0;
	for (int i = 0; i < n; i++) {
		dp[i] = _mm512_add_pd(_mm512_mul_pd(nx, in->x[i]), _mm512_mul_pd(nz, in->z[i]));
		keep[i] = _mm512_cmp_pd_mask(dp[i], _mm512_setzero_pd(), _CMP_GE_OQ) | keep_all;
		any |= keep[i];
	}
	out->n = 2 * n;
	for (int i = 0; i < n; i++) {
		int k = i + 1 < n ? i + 1 : 0;
		__m512d t = _mm512_div_pd(dp[i], _mm512_sub_pd(dp[i], dp[k]));
		out->x[2 * i] = in->x[i];
		out->y[2 * i] = in->y[i];
		out->z[2 * i] = in->z[i];
		out->x[2 * i + 1] = _mm512_add_pd(in->x[i], _mm512_mul_pd(t, _mm512_sub_pd(in->x[k], in->x[i])));
		out->y[2 * i + 1] = _mm512_add_pd(in->y[i], _mm512_mul_pd(t, _mm512_sub_pd(in->y[k], in->y[i])));
		out->z[2 * i + 1] = _mm512_add_pd(in->z[i], _mm512_mul_pd(t, _mm512_sub_pd(in->z[k], in->z[i])));
		valid[2 * i] = keep[i];
		valid[2 * i + 1] = keep[i] ^ keep[k];
	}
	/* The last emitted slot, then each slot or the last before it. */
	__m512d lx = out->x[0], ly = out->y[0], lz = out->z[0];
	for (int pass = 0; pass < 2; pass++) {
		for (int j = 0; j < out->n; j++) {
			lx = _mm512_mask_blend_pd(valid[j], lx, out->x[j]);
			ly = _mm512_mask_blend_pd(valid[j], ly, out->y[j]);
			lz = _mm512_mask_blend_pd(valid[j], lz, out->z[j]);
			if (pass) {
				out->x[j] = lx;
				out->y[j] = ly;
				out->z[j] = lz;
			}
		}
	}
	return any;
}

/* Row r of the pieces (rows v0 .. v1 of each lane, live ones): its span,
 * as raster_rows() finds it from the slab's vertices and the edges'
 * crossings of the slab's inner lines (edges e when there is more than
 * one row). */
TARGET static inline void row_span(const struct section_canvas *c, int n, const __m512d *s, const __m512d *y,
				   const struct edge *e, bool edges, __m512i v0, __m512i v1, uint32_t r, __mmask8 live,
				   struct lanes_out *out)
{
	const __m512d inf = _mm512_set1_pd(INFINITY), ninf = _mm512_set1_pd(-INFINITY);
	double h = c->geom.half_height, row_h = 2.0 * h / c->geom.height, eps = 1e-9 * row_h;
	const __m512d hv = _mm512_set1_pd(h), rh = _mm512_set1_pd(row_h), ev = _mm512_set1_pd(eps);
	__m512i v = _mm512_add_epi64(v0, _mm512_set1_epi64(r));
	__mmask8 on = live & _mm512_cmple_epi64_mask(v, v1);
	__mmask8 top = _mm512_cmpeq_epi64_mask(v, v0), bottom = _mm512_cmpeq_epi64_mask(v, v1);
	__m512d vd = _mm512_cvtepu64_pd(v), next = _mm512_cvtepu64_pd(_mm512_add_epi64(v, _mm512_set1_epi64(1)));
	__m512d yhi = _mm512_mask_blend_pd(top, _mm512_add_pd(_mm512_sub_pd(hv, _mm512_mul_pd(vd, rh)), ev), inf);
	__m512d ylo = _mm512_mask_blend_pd(bottom, _mm512_sub_pd(_mm512_sub_pd(hv, _mm512_mul_pd(next, rh)), ev), ninf);
	__m512d slo = inf, shi = ninf;
	slab_vertices(n, s, y, ylo, yhi, &slo, &shi);
	if (edges) { /* an infinite line crosses nothing */
		cross_edges(n, e, yhi, &slo, &shi);
		cross_edges(n, e, ylo, &slo, &shi);
	}
	out->lit[r] = on & _mm512_cmp_pd_mask(slo, shi, _CMP_LE_OQ);
	_mm256_storeu_si256((__m256i *)out->u0[r], _mm512_cvtepi64_epi32(lane_columns(c, slo)));
	_mm256_storeu_si256((__m256i *)out->u1[r], _mm512_cvtepi64_epi32(lane_columns(c, shi)));
}

/* project_body() and raster_rows() of the pieces in p (live lanes): the
 * rows and spans into out; lanes taller than MAX_ROWS are added to *leave
 * and dropped from *live. */
TARGET static inline void raster_slots(const struct section_canvas *c, const struct section_wedge *w,
				       const struct slots *p, __mmask8 *live, __mmask8 *leave, struct lanes_out *out)
{
	const int n = p->n;
	__m512d s[MAX_SLOTS], ymin = _mm512_set1_pd(INFINITY), ymax = _mm512_set1_pd(-INFINITY);
	for (int j = 0; j < n; j++) {
		s[j] = _mm512_add_pd(_mm512_mul_pd(p->x[j], _mm512_set1_pd(w->dx)),
				     _mm512_mul_pd(p->z[j], _mm512_set1_pd(w->dz)));
		ymin = _mm512_min_pd(ymin, p->y[j]);
		ymax = _mm512_max_pd(ymax, p->y[j]);
	}
	if (out->weighted) { /* raster_convex()'s s range of the piece */
		__m512d lo = _mm512_set1_pd(INFINITY), hi = _mm512_set1_pd(-INFINITY);
		for (int j = 0; j < n; j++) {
			lo = _mm512_min_pd(lo, s[j]);
			hi = _mm512_max_pd(hi, s[j]);
		}
		_mm512_storeu_pd(out->lo, lo);
		_mm512_storeu_pd(out->hi, hi);
	}
	/* A row at a time, as many as the tallest piece has. */
	__m512i v0 = lane_rows(c, ymax), v1 = lane_rows(c, ymin);
	__mmask8 tall = *live & _mm512_cmpgt_epi64_mask(_mm512_sub_epi64(v1, v0), _mm512_set1_epi64(MAX_ROWS - 1));
	*leave |= tall;
	*live &= ~tall;
	uint32_t rows = *live ? (uint32_t)_mm512_mask_reduce_max_epi64(*live, _mm512_sub_epi64(v1, v0)) + 1 : 0;
	struct edge e[MAX_SLOTS];
	if (rows > 1) /* a piece in one row needs no edges */
		edges_of(n, s, p->y, e);
	_mm256_storeu_si256((__m256i *)out->row, _mm512_cvtepi64_epi32(v0));
	out->rows = rows;
	for (uint32_t r = 0; r < rows; r++)
		row_span(c, n, s, p->y, e, rows > 1, v0, v1, r, *live, out);
}

/* prim_body()'s and lobe_piece()'s tests of eight primitives (vertices in
 * tri): the lanes in the brightness band (out->weighted), those that
 * leave for section_prim() (both lobes), the live ones (some piece), the
 * lobe's sign and the lanes with every vertex inside plane 1. */
TARGET static inline __attribute__((always_inline)) __mmask8 lobe_lanes(
	const struct section_canvas *c, const struct section_wedge *w, const struct slots *tri, __mmask8 active,
	__mmask8 *leave, __m512d *sign, __mmask8 *all1, __mmask8 *all2, struct lanes_out *out)
{
	const __m512d zero = _mm512_setzero_pd();
	const __m512d *x = tri->x, *z = tri->z;
	const int nv = tri->n;
	__m512d d1[3], d2[3], lo = _mm512_set1_pd(INFINITY), hi = _mm512_set1_pd(-INFINITY), xz = zero;
	for (int i = 0; i < nv; i++) {
		d1[i] = _mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(w->n1x), x[i]),
				      _mm512_mul_pd(_mm512_set1_pd(w->n1z), z[i]));
		d2[i] = _mm512_add_pd(_mm512_mul_pd(_mm512_set1_pd(w->n2x), x[i]),
				      _mm512_mul_pd(_mm512_set1_pd(w->n2z), z[i]));
		__m512d e = _mm512_add_pd(d1[i], d2[i]);
		lo = _mm512_min_pd(lo, e);
		hi = _mm512_max_pd(hi, e);
		xz = _mm512_max_pd(xz, _mm512_max_pd(_mm512_abs_pd(x[i]), _mm512_abs_pd(z[i])));
	}
	out->weighted = 0;
	if (c->bright && brightness_active(c->bright)) { /* weight_start() */
		__m512d band = _mm512_set1_pd(c->bright->band_d);
		out->weighted = active & ~(_mm512_cmp_pd_mask(hi, _mm512_sub_pd(zero, band), _CMP_LT_OQ) |
					   _mm512_cmp_pd_mask(lo, band, _CMP_GT_OQ));
	}
	/* lobes_reached(): both lobes leave, none is nothing. */
	__m512d m = _mm512_mul_pd(_mm512_set1_pd(1e-12), xz);
	__mmask8 front = ~_mm512_cmp_pd_mask(hi, _mm512_sub_pd(zero, m), _CMP_LT_OQ);
	__mmask8 back = ~_mm512_cmp_pd_mask(lo, m, _CMP_GT_OQ);
	*leave = (_mm512_cmp_pd_mask(lo, zero, _CMP_LE_OQ) & _mm512_cmp_pd_mask(hi, zero, _CMP_GE_OQ)) | (front & back);
	*sign = _mm512_mask_blend_pd(front, _mm512_set1_pd(-1.0), _mm512_set1_pd(1.0));
	/* lobe_piece()'s in-counts. */
	__mmask8 any1 = 0, any2 = 0;
	*all1 = *all2 = 0xff;
	for (int i = 0; i < nv; i++) {
		__mmask8 in1 = _mm512_cmp_pd_mask(_mm512_mul_pd(*sign, d1[i]), zero, _CMP_GE_OQ);
		__mmask8 in2 = _mm512_cmp_pd_mask(_mm512_mul_pd(*sign, d2[i]), zero, _CMP_GE_OQ);
		any1 |= in1;
		any2 |= in2;
		*all1 &= in1;
		*all2 &= in2;
	}
	return active & ~*leave & (front | back) & any1 & any2;
}

/* Eight segments or triangles (tri->n vertices, lanes of x, y, z; active
 * lanes set) in image w. */
TARGET static inline __attribute__((always_inline)) void batch8(
	const struct section_canvas *c, const struct section_wedge *w, const struct slots *tri, __mmask8 active,
	struct lanes_out *out, __mmask8 *pending)
{
	__mmask8 leave, all1, all2;
	__m512d sign;
	__mmask8 live = lobe_lanes(c, w, tri, active, &leave, &sign, &all1, &all2, out);
	if (!(live & ~(all1 & all2))) {
		/* Every piece is its primitive whole (each vertex inside both
		 * planes): the clip would keep each vertex and repeat it, and
		 * the raster skips repeats, so the primitive's own slots give
		 * the same spans. Most of a dense mesh's pieces where the
		 * batch holds primitives of a one-image range (render_cpu.c
		 * queues those apart). */
		raster_slots(c, w, tri, &live, &leave, out);
		*pending = active & leave;
		return;
	}
	/* The clip: plane 1 where some vertex is outside it (then plane 2 on
	 * what is left), else plane 2 alone (every vertex inside both: the
	 * pass keeps them as they are). */
	__m512d n1x = _mm512_mul_pd(sign, _mm512_set1_pd(w->n1x)), n1z = _mm512_mul_pd(sign, _mm512_set1_pd(w->n1z));
	__m512d n2x = _mm512_mul_pd(sign, _mm512_set1_pd(w->n2x)), n2z = _mm512_mul_pd(sign, _mm512_set1_pd(w->n2z));
	struct slots one, two;
	clip_slots(tri, _mm512_mask_blend_pd(all1, n1x, n2x), _mm512_mask_blend_pd(all1, n1z, n2z), 0, &one);
	__mmask8 cut2 = 0; /* after plane 1, plane 2 cuts something */
	for (int j = 0; j < one.n; j++) {
		__m512d dp = _mm512_add_pd(_mm512_mul_pd(n2x, one.x[j]), _mm512_mul_pd(n2z, one.z[j]));
		cut2 |= _mm512_cmp_pd_mask(dp, _mm512_setzero_pd(), _CMP_LT_OQ);
	}
	cut2 &= live & ~all1;
	if (cut2) {
		live &= clip_slots(&one, n2x, n2z, (__mmask8)~cut2, &two) | ~cut2;
		raster_slots(c, w, &two, &live, &leave, out);
	} else {
		raster_slots(c, w, &one, &live, &leave, out);
	}
	*pending = active & leave;
}

bool section_batch_supported(void)
{
	return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
	       __builtin_cpu_supports("avx512vl");
}

/* What the lanes found for lane l, lit: its spans, weighted where its
 * piece is in the brightness band. */
static void light_lane(struct section_canvas *c, const struct section_wedge *w, const struct lanes_out *out, unsigned l,
		       const struct section_lane *t, int verts)
{
	const uint8_t *rgb = t->rgb;
	if (!(out->weighted >> l & 1)) {
		for (uint32_t r = 0; r < out->rows; r++)
			if (out->lit[r] >> l & 1)
				section_span(c, out->row[l] + r, out->u0[r][l], out->u1[r][l], rgb);
		return;
	}
	struct section_run runs[MAX_ROWS];
	unsigned count = 0;
	for (uint32_t r = 0; r < out->rows; r++)
		if (out->lit[r] >> l & 1)
			runs[count++] = (struct section_run){ out->row[l] + r, out->u0[r][l], out->u1[r][l] };
	if (count) { /* the weights come from the primitive's own vertices */
		double v[3][3];
		lane_vertices(t, verts, v);
		section_weighted_runs(c, w, (const double(*)[3])v, verts, rgb, out->lo[l], out->hi[l], runs, count);
	}
}

/* The spans of the plain lanes (of the plain colour, not weighted: a mask)
 * as plain bits (section_plain_span()), a row of all eight at a time: the
 * bits, the tile and the row worked out on the lanes, then ORed in one by
 * one (lanes may share a tile row); a span across a tile edge by
 * section_plain_span(). */
TARGET static void light_plain(struct section_canvas *c, const struct lanes_out *out, __mmask8 plain)
{
	/* Each 32-bit lane's bytes swapped (bits x ^ 7 for pixel x). */
	const __m256i swap = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5,
					      4, 11, 10, 9, 8, 15, 14, 13, 12);
	const __m256i c31 = _mm256_set1_epi32(31), one = _mm256_set1_epi32(1);
	const __m256i row0 = _mm256_loadu_si256((const __m256i *)out->row);
	const __m256i tiles_x = _mm256_set1_epi32((int)c->tiles_x);
	uint32_t *bits = c->plain_bits, *rows = c->plain_rows;
	for (uint32_t r = 0; r < out->rows; r++) {
		__mmask8 lit = out->lit[r] & plain;
		if (!lit)
			continue;
		__m256i u0 = _mm256_loadu_si256((const __m256i *)out->u0[r]);
		__m256i u1 = _mm256_loadu_si256((const __m256i *)out->u1[r]);
		__m256i v = _mm256_add_epi32(row0, _mm256_set1_epi32((int)r));
		__mmask8 cross = lit & _mm256_cmpneq_epi32_mask(_mm256_srli_epi32(u0, 5), _mm256_srli_epi32(u1, 5));
		/* Pixels a..b at bits 31 - b .. 31 - a: 2^(32 - a) - 2^(31 - b),
		 * modulo 2^32. */
		__m256i a = _mm256_and_si256(u0, c31), b = _mm256_and_si256(u1, c31);
		__m256i m = _mm256_sub_epi32(_mm256_sllv_epi32(_mm256_set1_epi32(2), _mm256_sub_epi32(c31, a)),
					     _mm256_sllv_epi32(one, _mm256_sub_epi32(c31, b)));
		m = _mm256_shuffle_epi8(m, swap);
		__m256i t = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_srli_epi32(v, 5), tiles_x),
					     _mm256_srli_epi32(u0, 5));
		__m256i y = _mm256_and_si256(v, c31);
		uint32_t mm[8], tt[8], yy[8];
		_mm256_storeu_si256((__m256i *)mm, m);
		_mm256_storeu_si256((__m256i *)tt, t);
		_mm256_storeu_si256((__m256i *)yy, y);
		for (unsigned l = lit & ~cross; l; l &= l - 1) {
			unsigned i = (unsigned)__builtin_ctz(l);
			bits[(size_t)tt[i] * VOLUME_TILE + yy[i]] |= mm[i];
			rows[tt[i]] |= 1u << yy[i];
		}
		for (unsigned l = cross; l; l &= l - 1) {
			unsigned i = (unsigned)__builtin_ctz(l);
			section_plain_span(c, out->row[i] + r, out->u0[r][i], out->u1[r][i]);
		}
	}
}

/* The n (1 .. 8) lanes' vertices as lanes of doubles, lanes past n the
 * first's: each lane's coordinates loaded as a row (the first eight; a
 * triangle's ninth apart) and the rows transposed, where scalar loads into
 * a buffer read back whole stalled on store forwarding. */
TARGET static inline void lane_coordinates(const struct section_lane *t, unsigned n, int verts, struct slots *p)
{
	__m256 r[8], u[8], col[9];
	for (unsigned l = 0; l < 8; l++) /* a segment has six */
		r[l] = _mm256_maskz_loadu_ps(verts == 3 ? 0xFF : 0x3F, t[l < n ? l : 0].v);
	for (int l = 0; l < 8; l += 2) {
		u[l] = _mm256_unpacklo_ps(r[l], r[l + 1]);
		u[l + 1] = _mm256_unpackhi_ps(r[l], r[l + 1]);
	}
	for (int l = 0; l < 8; l += 4) {
		r[l] = _mm256_shuffle_ps(u[l], u[l + 2], 0x44);
		r[l + 1] = _mm256_shuffle_ps(u[l], u[l + 2], 0xEE);
		r[l + 2] = _mm256_shuffle_ps(u[l + 1], u[l + 3], 0x44);
		r[l + 3] = _mm256_shuffle_ps(u[l + 1], u[l + 3], 0xEE);
	}
	for (int j = 0; j < 4; j++) {
		col[j] = _mm256_permute2f128_ps(r[j], r[4 + j], 0x20);
		col[4 + j] = _mm256_permute2f128_ps(r[j], r[4 + j], 0x31);
	}
	if (verts == 3) {
		const float *v[8];
		for (unsigned l = 0; l < 8; l++)
			v[l] = t[l < n ? l : 0].v;
		col[8] = _mm256_setr_ps(v[0][8], v[1][8], v[2][8], v[3][8], v[4][8], v[5][8], v[6][8], v[7][8]);
	}
	p->n = verts;
	for (int i = 0; i < verts; i++) {
		p->x[i] = _mm512_cvtps_pd(col[3 * i]);
		p->y[i] = _mm512_cvtps_pd(col[3 * i + 1]);
		p->z[i] = _mm512_cvtps_pd(col[3 * i + 2]);
	}
}

/* The eight lanes for verts 2 or 3, a constant in each caller (so the
 * vertex loops unroll). */
TARGET static inline __attribute__((always_inline)) void batch(struct section_canvas *c, const struct section_wedge *w,
							       const struct section_lane *t, unsigned n, int verts)
{
	struct slots prims; /* not zeroed: 2.3 KB a batch */
	lane_coordinates(t, n, verts, &prims);
	struct lanes_out out;
	__mmask8 pending;
	batch8(c, w, &prims, (__mmask8)((1u << n) - 1), &out, &pending);
	__mmask8 plain = 0;
	for (unsigned l = 0; c->plain && l < n; l++)
		if (!((pending | out.weighted) >> l & 1) && section_is_plain(c, t[l].rgb))
			plain |= (__mmask8)(1u << l);
	if (plain)
		light_plain(c, &out, plain);
	for (unsigned l = 0; l < n; l++) {
		if (plain >> l & 1)
			continue;
		if (!(pending >> l & 1)) {
			light_lane(c, w, &out, l, &t[l], verts);
			continue;
		}
		one_by_one(c, w, &t[l], 1, verts);
	}
}

TARGET static void batch_segments(struct section_canvas *c, const struct section_wedge *w, const struct section_lane *t,
				  unsigned n)
{
	batch(c, w, t, n, 2);
}

TARGET static void batch_triangles(struct section_canvas *c, const struct section_wedge *w,
				   const struct section_lane *t, unsigned n)
{
	batch(c, w, t, n, 3);
}

void section_lanes(struct section_canvas *c, const struct section_wedge *w, const struct section_lane *t, unsigned n,
		   int verts)
{
	if (!c->general && section_batch_supported()) {
		if (verts == 3)
			batch_triangles(c, w, t, n);
		else
			batch_segments(c, w, t, n);
		return;
	}
	one_by_one(c, w, t, n, verts);
}

#else

bool section_batch_supported(void)
{
	return false;
}

void section_lanes(struct section_canvas *c, const struct section_wedge *w, const struct section_lane *t, unsigned n,
		   int verts)
{
	one_by_one(c, w, t, n, verts);
}

#endif
