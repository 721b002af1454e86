/* The exact CPU sectioning renderer: the reference every other renderer is
 * measured against, and the fast path without a GPU (docs/design.md section 5).
 * Per volume, a persistent pool of workers transforms and bins the scene
 * (bin.h); then the workers take images one at a time, light the points
 * binned there, section the primitives of the image's runs into an 8-bit
 * canvas, and halftone and pack only the tiles something touched. A turned
 * draw's primitives are sectioned by the wedge of the image they show
 * unturned, and written mirrored where that image is shown mirrored
 * (scene.h, geometry_turn_source()). Lifted draws (scene.h,
 * scene_draw.lift) are rendered first, unlifted, into a canvas volume per
 * lift, which each image's pass merges shifted by rows before the
 * halftone (render_lifted()). */
#include "render_cpu.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bin.h"
#include "brightness.h"
#include "compose.h"
#include "grid.h"
#include "halftone.h"
#include "log.h"
#include "pool.h"
#include "section.h"

/* One per thread, each on cache lines of its own: a worker's counters
 * beside the next one's canvas fields would bounce a line between the
 * cores on every primitive. */
struct cpu_worker {
	struct section_canvas canvas;
	/* The canvas's plain colour under recent tables, for
	 * section_canvas_pack_plain(); emptied with the counters each pass. */
	struct halftone_patterns plain;
	struct halftone_patterns masks; /* the point masks' colours */
	uint8_t *mask;                  /* pack_image()'s image mask (volume mask_bytes) */
	int err;
	uint64_t raster_ns, pack_ns, prim_images, canvas_tiles, tiles;
} __attribute__((aligned(64)));

struct render_cpu {
	struct renderer base;
	struct pool *pool;
	struct cpu_worker *workers;
	struct bin_set bins;
	struct section_wedge *wedges; /* per volume image */
	struct brightness_map bright; /* geom.brightness's weights */
	struct brightness_tables thr; /* per volume image, made once */
	halftone_fn halftone;
	bool batch; /* unturned segments and triangles through section_lanes() (triangles binned eight at a time) */
	bool plain; /* the canvases keep a plain colour as bits, and points
		     * halftoned as lit bits (not in the scalar variant) */
	/* Per render: the scene's grid draws, prepared (grid.h). */
	struct grid_job *grids;
	uint32_t grid_count, grid_cap;
	struct volume *out;
	struct rle_volume *canvas_out; /* render_canvas(): canvases, not packed images */
	atomic_uint next_image;
	/* A render with lifted draws: the canvases of each lift (what its
	 * draws light unlifted), merged into every image shifted; and the
	 * scene's draws by lift, each with lift 0, lift 0 first. */
	struct lifted_part {
		int32_t lift;
		struct rle_volume *canvas;
	} * lifted;
	uint32_t lifted_count;
	struct scene_draw *by_lift;
	uint32_t by_lift_cap;
	/* A small scene's images reached (mark_used()), when marked. */
	uint8_t *used;
	bool marked;
	/* render_canvas()'s work space, one per worker (made at its first
	 * call): an image's touched tiles with their row masks, and its mask. */
	struct canvas_stage {
		uint8_t *tiles, *mask;
		struct rle_scratch rle;
	} * stage;
	unsigned stages;
};

/* Copies the touched tiles of image k's canvas, with their row masks, into
 * r->canvas_out (coded) and leaves the canvas all zero again. */
static int canvas_image(struct render_cpu *r, struct cpu_worker *w, struct canvas_stage *st, uint32_t k)
{
	struct section_canvas *c = &w->canvas;
	uint32_t tiles = c->tiles_x * c->tiles_y, n = 0;
	if (c->lit_tables) /* its points would be lost (section_canvas_lit()) */
		return -EINVAL;
	memset(st->mask, 0, r->canvas_out->mask_bytes);
	for (uint32_t t = section_canvas_next(c, 0); t < tiles; t = section_canvas_next(c, t + 1)) {
		uint8_t *dst = st->tiles + (size_t)n++ * CANVAS_TILE_BYTES;
		section_canvas_fold_tile(c, t);
		memcpy(dst, &c->rows[t], sizeof(uint32_t));
		memcpy(dst + sizeof(uint32_t), c->rgb + (size_t)t * HALFTONE_TILE_BYTES, HALFTONE_TILE_BYTES);
		st->mask[t / 8] |= (uint8_t)(1u << (t % 8));
		w->canvas_tiles++;
		section_canvas_clear_tile(c, t);
	}
	return rle_volume_set_image(r->canvas_out, k, st->mask, st->tiles, n, &st->rle);
}

/* Tile t of w's canvas (image k) packed into dst: its bytes halftoned,
 * its lit bits copied or ORed in, its plain bits through the plain
 * colour's pattern. Whether any bit is set. */
static bool pack_tile(struct render_cpu *r, struct cpu_worker *w, uint32_t k, uint32_t t, uint8_t *dst)
{
	struct section_canvas *c = &w->canvas;
	const struct halftone_table *thr = brightness_table(&r->thr, k, t % c->tiles_x);
	bool lit = false;
	if (c->rows[t])
		lit = r->halftone(c->rgb + (size_t)t * HALFTONE_TILE_BYTES, c->rows[t], thr, dst);
	if (c->lit_rows[t]) { /* flags only rows with a bit set */
		section_canvas_pack_lit(c, t, dst, !c->rows[t]);
		lit = true;
	} else if (!c->rows[t]) {
		volume_tile_zero(dst);
	}
	if (c->plain_rows[t])
		lit |= section_canvas_pack_plain(
			c, t, halftone_pattern(&w->plain, c->plain_rgb, thr, r->halftone)->bits, dst);
	return lit;
}

/* Halftones and packs the touched tiles of image k in increasing order
 * straight into the volume's storage (pack_tile()), and leaves the canvas
 * all zero again, whether or not packing succeeded. The image's storage
 * grows when full (it is kept from volume to volume, so seldom); its mask
 * is made in the worker's own (w->mask) and set once at the end
 * (volume_image_set()). */
static int pack_image(struct render_cpu *r, struct cpu_worker *w, uint32_t k)
{
	struct section_canvas *c = &w->canvas;
	const struct volume_image *img = &r->out->images[k];
	uint32_t tiles = c->tiles_x * c->tiles_y, count = 0;
	int err = 0;
	memset(w->mask, 0, r->out->mask_bytes);
	for (uint32_t t = section_canvas_next(c, 0); t < tiles; t = section_canvas_next(c, t + 1)) {
		w->canvas_tiles++;
		if (err == 0 && count == img->tile_cap)
			err = volume_image_reserve(r->out, k, count + 1);
		if (err == 0 && pack_tile(r, w, k, t, img->tiles + (size_t)count * VOLUME_TILE_BYTES)) {
			w->mask[t / 8] |= (uint8_t)(1u << (t % 8));
			count++;
		}
		section_canvas_clear_tile(c, t);
	}
	w->tiles += count;
	return err < 0 ? err : volume_image_set(r->out, k, w->mask, count);
}

/* Lights a binned point of image k's square (bin.h), clipped to the
 * image; a one-pixel point as lit bits under lit, the canvas's
 * lit_tables, where it has them (section_canvas_lit()). */
static void light_point(struct section_canvas *c, const struct bin_point *p, const struct brightness_tables *lit,
			uint32_t k)
{
	if (p->size == 1) { /* the common case */
		if (lit)
			section_lit_pixel(c, p->u, p->v, p->rgb, brightness_table(lit, k, p->u / VOLUME_TILE));
		else
			section_pixel(c, p->u, p->v, p->rgb);
		return;
	}
	uint32_t u0, u1, v0, v1;
	bin_point_columns(p, c->geom.width, &u0, &u1);
	bin_point_span(p->v, p->size & ~(uint32_t)BIN_POINT_MIRRORED, c->geom.height, &v0, &v1);
	for (uint32_t v = v0; v <= v1; v++)
		section_span(c, v, u0, u1, p->rgb);
}

/* The grid jobs of the last render. */
static void free_grid_jobs(struct render_cpu *r)
{
	for (uint32_t i = 0; i < r->grid_count; i++)
		grid_job_finish(&r->grids[i]);
	r->grid_count = 0;
}

/* An image's unturned segments and triangles for section_lanes(), queued
 * by vertex count and by whether their range is one image (most often
 * every vertex inside the wedge: section_lanes() skips the clip where a
 * batch is all such pieces); 2 * (triangle) + (one image) picks a queue. */
struct lane_queues {
	struct section_lane lanes[4][SECTION_BATCH];
	unsigned n[4];
};

static void queue_lane(struct lane_queues *q, struct section_canvas *c, const struct section_wedge *w,
		       const struct bin_prim *p)
{
	unsigned l = 2 * (p->nverts == 3) + (p->count == 1);
	q->lanes[l][q->n[l]++] = (struct section_lane){ &p->v[0][0], p->rgb };
	if (q->n[l] == SECTION_BATCH) {
		section_lanes(c, w, q->lanes[l], q->n[l], p->nverts);
		q->n[l] = 0;
	}
}

/* Sections image k's segments and triangles (its n runs, image_runs())
 * into the canvas; returns how many. Unturned ones go eight at a time
 * (section_lanes(), queued as struct lane_queues says). */
static uint64_t section_image(struct render_cpu *r, struct section_canvas *c, uint32_t k, const struct bin_run *runs,
			      unsigned n)
{
	const struct bin_set *b = &r->bins;
	uint64_t sectioned = 0;
	struct lane_queues q = { .n = { 0 } };
	for (unsigned j = 0; j < n; j++) {
		for (uint32_t i = runs[j].begin; i < runs[j].end; i++) {
			const struct bin_prim *p = &b->prims[i];
			if (!bin_prim_in_image(b, p, k))
				continue;
			sectioned++;
			bool turned = b->turned && b->prim_turn[i];
			if (r->batch && !turned) {
				queue_lane(&q, c, &r->wedges[k], p);
				continue;
			}
			double v[3][3];
			for (int a = 0; a < p->nverts; a++)
				for (int e = 0; e < 3; e++)
					v[a][e] = p->v[a][e];
			if (!turned) {
				section_prim(c, &r->wedges[k], (const double(*)[3])v, p->nverts, p->rgb);
			} else { /* what it lights unturned in its source image */
				bool mirror;
				uint32_t src = geometry_turn_source(&r->base.geom, k, b->prim_turn[i], &mirror);
				section_prim_mirror(c, &r->wedges[src], (const double(*)[3])v, p->nverts, p->rgb,
						    mirror);
			}
		}
	}
	for (unsigned l = 0; l < 4; l++)
		if (q.n[l])
			section_lanes(c, &r->wedges[k], q.lanes[l], q.n[l], l >= 2 ? 3 : 2);
	return sectioned;
}

/* Draws image k's points, primitives (its n runs, image_runs()) and grids
 * on the canvas; returns how many (0: the canvas is untouched). */
static uint64_t raster_image(struct render_cpu *r, struct cpu_worker *w, uint32_t k, const struct bin_run *runs,
			     unsigned n)
{
	const struct bin_set *b = &r->bins;
	struct section_canvas *c = &w->canvas;
	uint64_t drawn = b->point_start[k + 1] - b->point_start[k];
	const struct brightness_tables *lit = c->lit_tables; /* once: the stores may alias it */
	for (uint32_t i = b->point_start[k]; i < b->point_start[k + 1]; i++)
		light_point(c, &b->points[i], lit, k);
	for (uint32_t i = 0; i < b->mask_count; i++)
		section_canvas_mask(c, k, bin_mask_image(b, &b->masks[i], k), b->masks[i].rgb, &w->masks, r->halftone);
	drawn += b->mask_count;
	uint64_t sectioned = section_image(r, c, k, runs, n);
	w->prim_images += sectioned;
	drawn += sectioned;
	for (uint32_t i = 0; i < r->grid_count; i++) {
		const struct grid_job *job = &r->grids[i];
		bool mirror = false;
		uint32_t turn = job->draw->turn % r->base.geom.images_per_rev;
		uint32_t src = turn ? geometry_turn_source(&r->base.geom, k, turn, &mirror) : k;
		grid_draw_image(c, job, src, mirror);
		drawn++;
	}
	return drawn;
}

/* The scene's grid draws that can be drawn, prepared. 0 or -ENOMEM. */
static int prepare_grids(struct render_cpu *r, const struct scene *scene)
{
	free_grid_jobs(r);
	for (uint32_t i = 0; scene && i < scene->draw_count; i++) {
		const struct scene_draw *d = &scene->draws[i];
		if (d->prim != SCENE_GRID || !d->grid)
			continue;
		if (r->grid_count == r->grid_cap) {
			uint32_t cap = r->grid_cap ? 2 * r->grid_cap : 4;
			struct grid_job *g = realloc(r->grids, cap * sizeof(*g));
			if (!g)
				return -ENOMEM;
			r->grids = g;
			r->grid_cap = cap;
		}
		struct grid_job *job = &r->grids[r->grid_count];
		if (!grid_prepare(job, d))
			continue;
		r->grid_count++;
		if (!grid_prepare_rows(job, &r->base.geom))
			return -ENOMEM;
	}
	return 0;
}

struct merge {
	struct section_canvas *c;
	int32_t lift;
	uint64_t tiles;
};

static void merge_tile(void *arg, uint32_t t, const uint8_t *tile)
{
	struct merge *m = arg;
	uint8_t out[2][CANVAS_TILE_BYTES];
	uint32_t ty[2], tx = t % m->c->tiles_x;
	unsigned n = canvas_tile_lift(tile, t / m->c->tiles_x, m->lift, m->c->geom.height, out, ty);
	for (unsigned i = 0; i < n; i++)
		section_canvas_max_tile(m->c, ty[i] * m->c->tiles_x + tx, out[i]);
	m->tiles += n;
}

/* Image k of every lifted canvas merged into w's canvas, shifted by its
 * lift; returns the tiles merged (0: the canvas is as it was). */
static uint64_t merge_lifted(struct render_cpu *r, struct cpu_worker *w, uint32_t k)
{
	struct merge m = { .c = &w->canvas };
	for (uint32_t i = 0; i < r->lifted_count; i++) {
		m.lift = r->lifted[i].lift;
		if (rle_canvas_each(r->lifted[i].canvas, k, merge_tile, &m) < 0 && w->err == 0)
			w->err = -EINVAL;
	}
	return m.tiles;
}

/* Image k's runs of primitives (bin_runs()) into runs, their count in *n;
 * false when the image has nothing to draw: no point, no primitive, no
 * grid, no lifted canvas. A small object lies in a few images of the
 * volume; the rest cost a bit test (mark_used()) or this look at the runs,
 * and no clock reads. */
static bool image_runs(const struct render_cpu *r, uint32_t k, struct bin_run *runs, unsigned *n)
{
	const struct bin_set *b = &r->bins;
	*n = 0;
	if (r->marked && !(r->used[k / 8] >> (k % 8) & 1))
		return false;
	*n = bin_runs(b, k, runs);
	if (r->marked || r->grid_count || r->lifted_count || b->mask_count ||
	    b->point_start[k + 1] != b->point_start[k])
		return true;
	for (unsigned j = 0; j < *n; j++)
		if (runs[j].begin != runs[j].end)
			return true;
	return false;
}

/* A small scene (what the calling thread renders alone): the images its
 * points and primitives reach, a bit each in r->used, so that the others
 * (most of them, for a small object) cost a bit test (image_job()). Grids
 * and lifted canvases reach every image: then not marked. */
static void mark_used(struct render_cpu *r)
{
	const struct bin_set *b = &r->bins;
	uint32_t M = b->images;
	r->marked = !r->grid_count && !r->lifted_count;
	if (!r->marked)
		return;
	memset(r->used, 0, (M + 7) / 8);
	for (uint32_t i = 0; i < b->prim_count; i++) {
		const struct bin_prim *p = &b->prims[i];
		for (uint32_t j = 0, k = p->first; j < p->count && j < M; j++, k = k + 1 < M ? k + 1 : 0)
			r->used[k / 8] |= (uint8_t)(1u << (k % 8));
	}
	for (uint32_t k = 0; k < M; k++)
		if (b->point_start[k + 1] != b->point_start[k])
			r->used[k / 8] |= (uint8_t)(1u << (k % 8));
}

/* Claims the next images for a worker, [*k, *end): consecutive ones,
 * whose bins share the primitives that span several images (these then
 * stay in the worker's cache), fewer as fewer remain so that the workers
 * finish together, and at most CLAIM_MAX, so that a worker the system
 * stops for a while holds back little (7 in 8 neighbours already share a
 * worker). False when none is left. */
#define CLAIM_MAX 8
static bool claim_images(struct render_cpu *r, uint32_t *k, uint32_t *end)
{
	const uint32_t M = r->bins.images, share = 2 * pool_workers(r->pool);
	uint32_t next = atomic_load(&r->next_image), n;
	do {
		if (next >= M)
			return false;
		n = (M - next) / share;
		n = n < 1 ? 1 : n > CLAIM_MAX ? CLAIM_MAX : n;
	} while (!atomic_compare_exchange_weak(&r->next_image, &next, next + n));
	*k = next;
	*end = next + n;
	return true;
}

/* Each image's result depends on nothing but the scene, so any split
 * gives identical output. */
static void image_job(void *arg, unsigned index)
{
	struct render_cpu *r = arg;
	struct cpu_worker *w = &r->workers[index];
	uint32_t k = 0, end = 0;
	for (;; k++) {
		if (k == end && !claim_images(r, &k, &end))
			break;
		struct bin_run runs[2 * BIN_MAX_CLASSES];
		unsigned n;
		if (!image_runs(r, k, runs, &n)) {
			int err = r->canvas_out ? rle_volume_set_image(r->canvas_out, k, NULL, NULL, 0, NULL) : 0;
			if (err < 0 && w->err == 0)
				w->err = err;
			continue;
		}
		int64_t t0 = now_ns();
		uint64_t drawn = raster_image(r, w, k, runs, n);
		if (r->lifted_count)
			drawn += merge_lifted(r, w, k);
		int64_t t1 = now_ns();
		/* Nothing drawn: the canvas is all zero, the image empty. */
		int err;
		if (r->canvas_out)
			err = drawn ? canvas_image(r, w, &r->stage[index], k)
				    : rle_volume_set_image(r->canvas_out, k, NULL, NULL, 0, NULL);
		else
			err = drawn ? pack_image(r, w, k) : 0;
		w->raster_ns += (uint64_t)(t1 - t0);
		w->pack_ns += (uint64_t)(now_ns() - t1);
		if (err < 0 && w->err == 0)
			w->err = err;
	}
}

static int check_output(const struct render_cpu *r, const struct volume *out)
{
	const struct geometry *a = &r->base.geom, *b = &out->geom;
	if (a->width != b->width || a->height != b->height || a->images_per_rev != b->images_per_rev ||
	    a->mirrored != b->mirrored || a->half_height != b->half_height)
		return -EINVAL;
	return 0;
}

/* Sums the workers' counters into the stats; the first error wins. */
static int collect(struct render_cpu *r)
{
	struct render_stats *s = &r->base.stats;
	int err = 0;
	for (unsigned i = 0; i < pool_workers(r->pool); i++) {
		struct cpu_worker *w = &r->workers[i];
		s->raster_ns += w->raster_ns;
		s->pack_ns += w->pack_ns;
		s->prim_images += w->prim_images;
		s->canvas_tiles += w->canvas_tiles;
		s->tiles += w->tiles;
		if (err == 0)
			err = w->err;
	}
	return err;
}

/* The colour the canvases keep as bits (section_canvas_plain()): that of
 * the draw of segments or triangles with the most vertices, where it has
 * one colour; NULL where there is none. */
static const uint8_t *plain_colour(const struct scene *scene)
{
	const struct scene_draw *best = NULL;
	for (uint32_t i = 0; scene && i < scene->draw_count; i++) {
		const struct scene_draw *d = &scene->draws[i];
		if ((d->prim == SCENE_LINES || d->prim == SCENE_TRIANGLES) && !d->prim_rgb &&
		    (!best || d->count > best->count))
			best = d;
	}
	return best ? best->rgb : NULL;
}

/* One pass: scene (no lifts) binned and drawn, image by image, into out or
 * canvas, with r->lifted merged; the stats add up over passes. */
static int render_pass(struct render_cpu *r, const struct scene *scene, struct volume *out, struct rle_volume *canvas)
{
	struct renderer *base = &r->base;
	int64_t start = now_ns();
	int err = bin_build(&r->bins, scene, r->pool);
	base->stats.bins_kept += r->bins.kept;
	if (err == 0)
		err = prepare_grids(r, scene);
	int64_t binned = now_ns();
	base->stats.bin_ns += (uint64_t)(binned - start);
	if (err < 0)
		return err;
	base->stats.prims += r->bins.prim_count + r->bins.point_count + r->bins.mask_points;
	const uint8_t *plain = r->plain ? plain_colour(scene) : NULL;
	for (unsigned i = 0; i < pool_workers(r->pool); i++) {
		struct section_canvas c = r->workers[i].canvas; /* bright too */
		section_canvas_plain(&c, plain);
		/* Points straight to bits where images are packed now; kept
		 * as bytes (canvas), they stay bytes. */
		section_canvas_lit(&c, r->plain && !canvas ? &r->thr : NULL);
		r->workers[i] = (struct cpu_worker){ .canvas = c, .mask = r->workers[i].mask };
	}
	r->out = out;
	r->canvas_out = canvas;
	atomic_store(&r->next_image, 0);
	r->marked = false;
	if (!r->grid_count && !r->lifted_count && !r->bins.mask_count &&
	    r->bins.prim_count + r->bins.point_count <= BIN_SERIAL_VERTICES / 3) {
		mark_used(r);
		image_job(r, 0); /* a small scene: worker 0 (this thread) alone */
	} else {
		pool_run(r->pool, image_job, r);
	}
	r->out = NULL;
	r->canvas_out = NULL;
	return collect(r);
}

static void free_stage(struct render_cpu *r)
{
	for (unsigned i = 0; i < r->stages; i++) {
		free(r->stage[i].tiles);
		free(r->stage[i].mask);
		free(r->stage[i].rle.buf);
	}
	free(r->stage);
	r->stage = NULL;
	r->stages = 0;
}

/* render_canvas()'s work space, made at first need (freed with the
 * renderer). 0 or -ENOMEM. */
static int ensure_stage(struct render_cpu *r)
{
	if (r->stage)
		return 0;
	const struct geometry *g = &r->base.geom;
	uint32_t tiles = volume_geometry_tiles(g);
	unsigned n = pool_workers(r->pool);
	r->stage = calloc(n, sizeof(*r->stage));
	if (!r->stage)
		return -ENOMEM;
	r->stages = n;
	for (unsigned i = 0; i < n; i++) {
		r->stage[i].tiles = malloc((size_t)tiles * CANVAS_TILE_BYTES);
		r->stage[i].mask = malloc((tiles + 7) / 8);
		if (!r->stage[i].tiles || !r->stage[i].mask) {
			free_stage(r); /* tried again at the next need */
			return -ENOMEM;
		}
	}
	return 0;
}

/* The lifted canvases of the last render freed. */
static void drop_lifted(struct render_cpu *r)
{
	for (uint32_t i = 0; i < r->lifted_count; i++)
		rle_volume_free(r->lifted[i].canvas);
	r->lifted_count = 0;
}

/* Room for n draws in r->by_lift and n lifts in r->lifted. */
static int grow_lifted(struct render_cpu *r, uint32_t n)
{
	if (n <= r->by_lift_cap)
		return 0;
	struct scene_draw *d = realloc(r->by_lift, n * sizeof(*d));
	if (d)
		r->by_lift = d;
	struct lifted_part *l = realloc(r->lifted, n * sizeof(*l));
	if (l)
		r->lifted = l;
	if (!d || !l)
		return -ENOMEM;
	r->by_lift_cap = n;
	return 0;
}

/* The smallest lift of scene's draws above after; 0: none. */
static int32_t next_lift(const struct scene *scene, int32_t after)
{
	int32_t best = 0;
	for (uint32_t i = 0; i < scene->draw_count; i++) {
		int32_t l = scene->draws[i].lift;
		if (l && l > after && (!best || l < best))
			best = l;
	}
	return best;
}

/* Renders each lift's draws of scene, unlifted, into a canvas of its own
 * (r->lifted); *rest: the unlifted draws. 0 or negative errno. */
static int render_lifted(struct render_cpu *r, const struct scene *scene, struct scene *rest)
{
	const struct geometry *g = &r->base.geom;
	uint32_t tiles_x = volume_tiles_across(g->width);
	uint32_t tiles = tiles_x * volume_tiles_across(g->height);
	if (grow_lifted(r, scene->draw_count) < 0 || ensure_stage(r) < 0)
		return -ENOMEM;
	uint32_t m = 0;
	for (uint32_t i = 0; i < scene->draw_count; i++)
		if (!scene->draws[i].lift)
			r->by_lift[m++] = scene->draws[i];
	*rest = (struct scene){ .draw_count = m, .draws = r->by_lift };
	for (int32_t lift = next_lift(scene, INT32_MIN); lift; lift = next_lift(scene, lift)) {
		uint32_t first = m;
		for (uint32_t i = 0; i < scene->draw_count; i++) {
			if (scene->draws[i].lift != lift)
				continue;
			r->by_lift[m] = scene->draws[i];
			r->by_lift[m++].lift = 0;
		}
		struct rle_volume *cv = rle_volume_new(r->bins.images, (tiles + 7) / 8, tiles, CANVAS_TILE_BYTES);
		if (!cv)
			return -ENOMEM;
		r->lifted[r->lifted_count++] = (struct lifted_part){ lift, cv };
		struct scene part = { .draw_count = m - first, .draws = r->by_lift + first };
		uint32_t merged = r->lifted_count;
		r->lifted_count = 0; /* a part merges nothing */
		int err = render_pass(r, &part, NULL, cv);
		r->lifted_count = merged;
		rle_volume_sum(cv);
		if (err < 0)
			return err;
	}
	return 0;
}

/* Renders scene into out, or into canvas (render_canvas()). */
static int render_to(struct render_cpu *r, const struct scene *scene, struct volume *out, struct rle_volume *canvas)
{
	struct renderer *base = &r->base;
	int64_t start = now_ns();
	memset(&base->stats, 0, sizeof(base->stats));
	base->stats.engine = RENDER_ENGINE_CPU;
	base->stats.threads = pool_workers(r->pool);
	int err = 0;
	struct scene rest;
	if (scene && scene_has_lift(scene->draws, scene->draw_count)) {
		err = render_lifted(r, scene, &rest);
		scene = &rest;
	}
	if (err == 0)
		err = render_pass(r, scene, out, canvas);
	drop_lifted(r);
	base->stats.total_ns = (uint64_t)(now_ns() - start);
	return err;
}

static int cpu_render(struct renderer *base, const struct scene *scene, struct volume *out)
{
	struct render_cpu *r = (struct render_cpu *)base;
	int err = check_output(r, out);
	if (err < 0)
		return err;
	volume_clear(out);
	return render_to(r, scene, out, NULL);
}

static int cpu_render_canvas(struct renderer *base, const struct scene *scene, struct rle_volume *out)
{
	struct render_cpu *r = (struct render_cpu *)base;
	uint32_t tiles_x = volume_tiles_across(base->geom.width);
	uint32_t tiles = tiles_x * volume_tiles_across(base->geom.height);
	if (out->tile_bytes != CANVAS_TILE_BYTES || out->image_count != r->bins.images || out->tiles_per_image != tiles)
		return -EINVAL;
	if (ensure_stage(r) < 0)
		return -ENOMEM;
	int err = render_to(r, scene, NULL, out);
	rle_volume_sum(out);
	return err;
}

static void cpu_destroy(struct renderer *base)
{
	struct render_cpu *r = (struct render_cpu *)base;
	pool_destroy(r->pool);
	for (unsigned i = 0; r->workers && i < r->base.stats.threads; i++) {
		section_canvas_finish(&r->workers[i].canvas);
		free(r->workers[i].mask);
	}
	free(r->workers);
	free_stage(r);
	drop_lifted(r);
	free(r->lifted);
	free(r->by_lift);
	free(r->wedges);
	free(r->used);
	free_grid_jobs(r);
	free(r->grids);
	brightness_tables_finish(&r->thr);
	brightness_map_finish(&r->bright);
	bin_finish(&r->bins);
	free(r);
}

static struct renderer *cpu_serial(const struct renderer *base);

static const struct renderer_impl cpu_impl = {
	.name = "cpu",
	.render = cpu_render,
	.render_canvas = cpu_render_canvas,
	.serial = cpu_serial,
	.destroy = cpu_destroy,
};

static unsigned pick_threads(const struct geometry *geom, unsigned threads)
{
	if (threads == 0) {
		long n = sysconf(_SC_NPROCESSORS_ONLN);
		threads = n > 0 ? (unsigned)n : 1;
	}
	uint32_t images = geometry_images_per_volume(geom);
	return threads < images ? threads : images;
}

struct renderer *render_cpu_create(const struct geometry *geom, unsigned threads)
{
	struct render_cpu_options o = { .threads = threads, .keep = true };
	return render_cpu_create_opts(geom, &o);
}

static struct renderer *cpu_new(const struct geometry *geom, halftone_fn halftone, bool batch, bool keep,
				unsigned threads);

struct renderer *render_cpu_create_opts(const struct geometry *geom, const struct render_cpu_options *opts)
{
	halftone_fn halftone = halftone_pick(opts->simd);
	if (!halftone) {
		errno = ENOENT;
		return NULL;
	}
	/* The eight-lane sectioning goes with the best variant or AVX-512's:
	 * "scalar" (the reference of the benchmark's comparisons) and the
	 * narrower ones section one primitive at a time. */
	bool batch = !opts->simd || strcmp(opts->simd, "auto") == 0 || strcmp(opts->simd, "avx512") == 0;
	return cpu_new(geom, halftone, batch, opts->keep, opts->threads);
}

/* One thread, the same halftone variant (they all give the same bits). */
static struct renderer *cpu_serial(const struct renderer *base)
{
	const struct render_cpu *r = (const struct render_cpu *)base;
	return cpu_new(&base->geom, r->halftone, r->batch, r->bins.keep, 1);
}

/* A worker's canvas (weighted by bright) and pack mask; all or nothing.
 * 0 or -ENOMEM. */
static int worker_init(struct cpu_worker *w, const struct geometry *geom, const struct brightness_map *bright)
{
	if (section_canvas_init(&w->canvas, geom) < 0)
		return -ENOMEM;
	w->mask = calloc((w->canvas.tiles_x * w->canvas.tiles_y + 7) / 8, 1);
	if (!w->mask) {
		section_canvas_finish(&w->canvas);
		return -ENOMEM;
	}
	w->canvas.bright = bright;
	return 0;
}

/* r's storage and tables for geom, its n workers and their pool: 0 or
 * -ENOMEM (what was made is then freed by cpu_destroy()). */
static int cpu_init(struct render_cpu *r, const struct geometry *geom, unsigned n)
{
	r->workers = aligned_alloc(64, n * sizeof(*r->workers));
	if (r->workers)
		memset(r->workers, 0, n * sizeof(*r->workers));
	uint32_t images = geometry_images_per_volume(geom);
	r->wedges = calloc(images, sizeof(*r->wedges));
	r->used = calloc((images + 7) / 8, 1);
	if (!r->workers || !r->wedges || !r->used || bin_init(&r->bins, geom) < 0)
		return -ENOMEM;
	if (brightness_map_init(&r->bright, geom) < 0 || brightness_tables_init(&r->thr, &r->bright) < 0)
		return -ENOMEM;
	for (uint32_t k = 0; k < images; k++)
		section_wedge_init(&r->wedges[k], geom, k);
	for (unsigned i = 0; i < n; i++) {
		if (worker_init(&r->workers[i], geom, &r->bright) < 0)
			return -ENOMEM;
		r->base.stats.threads = i + 1; /* workers to free */
	}
	r->pool = pool_create(n);
	if (!r->pool)
		return -ENOMEM;
	r->base.pool = r->pool;
	r->base.stats.threads = n;
	return 0;
}

static struct renderer *cpu_new(const struct geometry *geom, halftone_fn halftone, bool batch, bool keep,
				unsigned threads)
{
	if (geometry_validate(geom) < 0) {
		errno = EINVAL;
		return NULL;
	}
	struct render_cpu *r = calloc(1, sizeof(*r));
	if (!r)
		return NULL;
	r->base.impl = &cpu_impl;
	r->base.geom = *geom;
	r->halftone = halftone;
	r->batch = batch && section_batch_supported();
	r->plain = batch; /* any CPU: section_span() and the pack take bits */
	if (cpu_init(r, geom, pick_threads(geom, threads)) < 0) {
		cpu_destroy(&r->base);
		errno = ENOMEM;
		return NULL;
	}
	r->bins.prims_scalar = !batch; /* the scalar variant bins one at a time too */
	r->bins.point_masks = batch;   /* and takes dense points as records */
	r->bins.keep = keep;
	return &r->base;
}
