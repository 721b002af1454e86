#include "bin.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "pool.h"

/* The first primitive and first point item of a draw. */
struct draw_base {
	uint64_t prim, point;
};

struct bin_work {
	const struct scene *scene;
	unsigned threads;
	uint64_t prim_items, point_items;
	struct draw_base *base; /* per draw */
	size_t base_cap;
	/* bin_slots() staging entries per item (unmirrored, a primitive
	 * may need two records); unused ones have key BIN_KEY_NONE. */
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
	/* threads x draws: the mask (bin_set.masks) a thread's points of a
	 * draw go to, or -1: records. */
	int32_t *mask_of;
	size_t mask_of_cap, masks_cap;
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
	size_t masks_cap = w ? w->masks_cap : 0;
	if (w) {
		free(w->base);
		free(w->stage_prims);
		free(w->point_recs);
		free(w->point_keys);
		free(w->hist);
		free(w->mask_of);
		free(w->kept);
		free(w);
	}
	for (uint32_t i = 0; b->masks && i < masks_cap; i++)
		free(b->masks[i].bits);
	free(b->masks);
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
static inline __attribute__((always_inline)) bool prim_arc(const struct bin_set *b, const float (*v)[3], int n,
							   bool neg, uint32_t *first, uint32_t *len)
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

void bin_one_prim(const struct bin_set *b, const struct scene_draw *d, const float *xyz, int n, const uint8_t rgb[3],
		  struct stage_prim *out)
{
	double t[3][3];
	out[0].key = BIN_KEY_NONE;
	if (!b->geom.mirrored)
		out[1].key = BIN_KEY_NONE;
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

void bin_turn_prims(const struct bin_set *b, uint32_t turn, struct stage_prim *s)
{
	uint32_t M = b->images;
	for (uint32_t i = 0; i < bin_slots(b); i++) {
		if (s[i].key == BIN_KEY_NONE)
			continue;
		uint32_t was = s[i].rec.first, first = was;
		if (s[i].rec.count < M) {
			first = (was + turn % M) % M;
			s[i].rec.first = (uint16_t)first;
		}
		s[i].key = (s[i].key - was + first) | turn << BIN_KEY_BITS; /* class * M + first */
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
	if (nv == 3 && b->geom.mirrored && !b->prims_scalar && bin_points_isa_supported(BIN_POINTS_AVX512))
		j = bin_stage_tris8(b, d, j0, j1, out, hist);
	for (; j < j1; j++) {
		struct stage_prim *s = &out[slots * (j - j0)];
		bin_one_prim(b, d, d->xyz + j * (uint64_t)nv * 3, nv, d->prim_rgb ? d->prim_rgb + 3 * j : d->rgb, s);
		bin_finish_item(b, turn, s, hist);
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
		if (!point_run(w, di, c, &lo, &hi))
			continue;
		int32_t m = w->mask_of[(size_t)t * w->scene->draw_count + di];
		if (m >= 0) {
			memset(b->masks[m].bits, 0, bin_mask_words(b) * sizeof(uint32_t));
			bin_points_mask(b, &w->scene->draws[di], lo - base, hi - base, b->masks[m].bits);
		} else {
			bin_points_stage(b, &w->scene->draws[di], lo - base, hi - base, w->point_recs + slots * lo,
					 w->point_keys + slots * lo, hist + pk);
		}
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
			if (w->stage_prims[i].key != BIN_KEY_NONE)
				b->prims[off[w->stage_prims[i].key]++] = w->stage_prims[i].rec;
	} else {
		for (uint64_t i = slots * c.lo; i < slots * c.hi; i++) {
			uint32_t key = w->stage_prims[i].key;
			if (key == BIN_KEY_NONE)
				continue;
			uint32_t o = off[key & BIN_KEY_MASK]++;
			b->prims[o] = w->stage_prims[i].rec;
			b->prim_turn[o] = (uint16_t)(key >> BIN_KEY_BITS);
		}
	}
	c = chunk_of(w->point_items, w->threads, t);
	for (uint32_t di = 0; di < w->scene->draw_count; di++) {
		uint64_t lo, hi, base = w->base[di].point;
		if (point_run(w, di, c, &lo, &hi) && w->mask_of[(size_t)t * w->scene->draw_count + di] < 0)
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

/* Mask i of b->masks there, with its bits. 0 or -ENOMEM. */
static int ensure_mask(struct bin_set *b, uint32_t i)
{
	struct bin_work *w = b->work;
	if (i >= w->masks_cap) {
		size_t cap = w->masks_cap ? 2 * w->masks_cap : 8;
		struct bin_point_mask *m = realloc(b->masks, cap * sizeof(*m));
		if (!m)
			return -ENOMEM;
		memset(m + w->masks_cap, 0, (cap - w->masks_cap) * sizeof(*m));
		b->masks = m;
		w->masks_cap = cap;
	}
	if (!b->masks[i].bits && !(b->masks[i].bits = malloc(bin_mask_words(b) * sizeof(uint32_t))))
		return -ENOMEM;
	return 0;
}

/* Which of each thread's runs of points go to a mask of their own
 * (bin_points_maskable()): w->mask_of. A mask has no more words than its
 * run has points. 0 or -ENOMEM. */
static int plan_masks(struct bin_set *b)
{
	struct bin_work *w = b->work;
	uint32_t draws = w->scene ? w->scene->draw_count : 0;
	int r = grow((void **)&w->mask_of, &w->mask_of_cap, (size_t)w->threads * draws, sizeof(*w->mask_of));
	if (r < 0)
		return r;
	for (unsigned t = 0; t < w->threads; t++) {
		struct chunk c = chunk_of(w->point_items, w->threads, t);
		for (uint32_t di = 0; di < draws; di++) {
			const struct scene_draw *d = &w->scene->draws[di];
			int32_t *m = &w->mask_of[(size_t)t * draws + di];
			uint64_t lo, hi;
			*m = -1;
			if (!point_run(w, di, c, &lo, &hi) || !bin_points_maskable(b, d, lo, hi))
				continue;
			if ((r = ensure_mask(b, b->mask_count)) < 0)
				return r;
			memcpy(b->masks[b->mask_count].rgb, d->rgb, 3);
			*m = (int32_t)b->mask_count++;
			b->mask_points += hi - lo;
		}
	}
	return 0;
}

/* Counts items, sizes the work space and plans the masks. */
static int prepare(struct bin_set *b, const struct scene *scene, unsigned threads)
{
	struct bin_work *w = b->work;
	uint32_t draws = scene ? scene->draw_count : 0;
	b->turned = false;
	b->mask_count = 0;
	b->mask_points = 0;
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
	return plan_masks(b);
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
