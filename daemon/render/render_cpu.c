/* The exact CPU sectioning renderer: the reference every other renderer is
 * measured against, and the fast path without a GPU (docs/design.md section 5).
 * Per volume, a persistent pool of workers transforms and bins the scene
 * (bin.h); then the workers take images one at a time, light the points
 * binned there, section the primitives of the image's runs into an 8-bit
 * canvas, and halftone and pack only the tiles something touched. A turned
 * draw's primitives are sectioned by the wedge of the image they show
 * unturned, and written mirrored where that image is shown mirrored
 * (scene.h, geometry_turn_source()). */
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

struct cpu_worker {
	struct section_canvas canvas;
	int err;
	uint64_t raster_ns, pack_ns, prim_images, canvas_tiles, tiles;
};

struct render_cpu {
	struct renderer base;
	struct pool *pool;
	struct cpu_worker *workers;
	struct bin_set bins;
	struct section_wedge *wedges; /* per volume image */
	struct brightness_map bright; /* geom.brightness's weights */
	struct brightness_tables thr; /* per volume image, made once */
	halftone_fn halftone;
	/* Per render: the scene's grid draws, prepared (grid.h). */
	struct grid_job *grids;
	uint32_t grid_count, grid_cap;
	struct volume *out;
	struct rle_volume *canvas_out; /* render_canvas(): canvases, not packed images */
	atomic_uint next_image;
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
	memset(st->mask, 0, r->canvas_out->mask_bytes);
	for (uint32_t t = 0; t < tiles; t++) {
		if (!c->rows[t])
			continue;
		uint8_t *dst = st->tiles + (size_t)n++ * CANVAS_TILE_BYTES;
		memcpy(dst, &c->rows[t], sizeof(uint32_t));
		memcpy(dst + sizeof(uint32_t), c->rgb + (size_t)t * HALFTONE_TILE_BYTES, HALFTONE_TILE_BYTES);
		st->mask[t / 8] |= (uint8_t)(1u << (t % 8));
		w->canvas_tiles++;
		section_canvas_clear_tile(c, t);
	}
	return rle_volume_set_image(r->canvas_out, k, st->mask, st->tiles, n, &st->rle);
}

/* Halftones and packs the touched tiles of image k in increasing order and
 * leaves the canvas all zero again, whether or not packing succeeded. */
static int pack_image(struct render_cpu *r, struct cpu_worker *w, uint32_t k)
{
	struct section_canvas *c = &w->canvas;
	int err = 0;
	uint32_t tiles = c->tiles_x * c->tiles_y;
	for (uint32_t t = 0; t < tiles; t++) {
		if (!c->rows[t])
			continue;
		w->canvas_tiles++;
		/* Halftoned straight into the volume's storage. */
		uint8_t *dst = err == 0 ? volume_image_next(r->out, k) : NULL;
		if (!dst && err == 0)
			err = -ENOMEM;
		const struct halftone_table *thr = brightness_table(&r->thr, k, t % c->tiles_x);
		if (dst && r->halftone(c->rgb + (size_t)t * HALFTONE_TILE_BYTES, c->rows[t], thr, dst)) {
			err = volume_image_push(r->out, k, t);
			w->tiles++;
		}
		section_canvas_clear_tile(c, t);
	}
	return err;
}

/* Lights a binned point's square (bin.h), clipped to the image. */
static void light_point(struct section_canvas *c, const struct bin_point *p)
{
	if (p->size == 1) { /* the common case: section_pixel() without branches */
		uint32_t u = p->u, v = p->v, t = (v / VOLUME_TILE) * c->tiles_x + u / VOLUME_TILE;
		uint8_t *px = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + (v % VOLUME_TILE) * HALFTONE_ROW_BYTES +
			      halftone_pos(u % VOLUME_TILE);
		for (int i = 0; i < 3; i++) {
			uint8_t was = px[i * HALFTONE_PLANE_BYTES], rgb = p->rgb[i];
			px[i * HALFTONE_PLANE_BYTES] = was > rgb ? was : rgb;
		}
		c->rows[t] |= 1u << (v % VOLUME_TILE);
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

/* Draws image k's points, primitives and grids on the canvas; returns how
 * many (0: the canvas is untouched). */
static uint64_t raster_image(struct render_cpu *r, struct cpu_worker *w, uint32_t k)
{
	const struct bin_set *b = &r->bins;
	struct section_canvas *c = &w->canvas;
	uint64_t drawn = b->point_start[k + 1] - b->point_start[k];
	for (uint32_t i = b->point_start[k]; i < b->point_start[k + 1]; i++)
		light_point(c, &b->points[i]);
	struct bin_run runs[2 * BIN_MAX_CLASSES];
	unsigned n = bin_runs(b, k, runs);
	for (unsigned j = 0; j < n; j++) {
		for (uint32_t i = runs[j].begin; i < runs[j].end; i++) {
			const struct bin_prim *p = &b->prims[i];
			if (!bin_prim_in_image(b, p, k))
				continue;
			double v[3][3];
			for (int a = 0; a < p->nverts; a++)
				for (int e = 0; e < 3; e++)
					v[a][e] = p->v[a][e];
			if (!b->turned || !b->prim_turn[i]) {
				section_prim(c, &r->wedges[k], (const double(*)[3])v, p->nverts, p->rgb);
			} else { /* what it lights unturned in its source image */
				bool mirror;
				uint32_t src = geometry_turn_source(&r->base.geom, k, b->prim_turn[i], &mirror);
				section_prim_mirror(c, &r->wedges[src], (const double(*)[3])v, p->nverts, p->rgb,
						    mirror);
			}
			w->prim_images++;
			drawn++;
		}
	}
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

/* Images are handed out one at a time; each image's result depends on
 * nothing but the scene, so any split gives identical output. */
static void image_job(void *arg, unsigned index)
{
	struct render_cpu *r = arg;
	struct cpu_worker *w = &r->workers[index];
	for (;;) {
		uint32_t k = atomic_fetch_add(&r->next_image, 1);
		if (k >= r->bins.images)
			break;
		int64_t t0 = now_ns();
		uint64_t drawn = raster_image(r, w, k);
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

/* Renders scene into out, or into canvas (render_canvas()). */
static int render_to(struct render_cpu *r, const struct scene *scene, struct volume *out, struct rle_volume *canvas)
{
	struct renderer *base = &r->base;
	int64_t start = now_ns();
	int err = 0;
	memset(&base->stats, 0, sizeof(base->stats));
	base->stats.engine = RENDER_ENGINE_CPU;
	base->stats.threads = pool_workers(r->pool);
	err = bin_build(&r->bins, scene, r->pool);
	if (err == 0)
		err = prepare_grids(r, scene);
	int64_t binned = now_ns();
	base->stats.bin_ns = (uint64_t)(binned - start);
	if (err < 0)
		return err;
	base->stats.prims = r->bins.prim_count + r->bins.point_count;
	for (unsigned i = 0; i < pool_workers(r->pool); i++) {
		struct section_canvas c = r->workers[i].canvas; /* bright too */
		r->workers[i] = (struct cpu_worker){ .canvas = c };
	}
	r->out = out;
	r->canvas_out = canvas;
	atomic_store(&r->next_image, 0);
	if (!r->grid_count && r->bins.prim_count + r->bins.point_count <= BIN_SERIAL_VERTICES / 3)
		image_job(r, 0); /* a small scene: worker 0 (this thread) alone */
	else
		pool_run(r->pool, image_job, r);
	r->out = NULL;
	r->canvas_out = NULL;
	err = collect(r);
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
	uint32_t tiles_x = (base->geom.width + VOLUME_TILE - 1) / VOLUME_TILE;
	uint32_t tiles = tiles_x * ((base->geom.height + VOLUME_TILE - 1) / VOLUME_TILE);
	if (out->tile_bytes != CANVAS_TILE_BYTES || out->image_count != r->bins.images || out->tiles_per_image != tiles)
		return -EINVAL;
	if (!r->stage) {
		unsigned n = pool_workers(r->pool);
		r->stage = calloc(n, sizeof(*r->stage));
		r->stages = r->stage ? n : 0;
		for (unsigned i = 0; r->stage && i < n; i++) {
			r->stage[i].tiles = malloc((size_t)tiles * CANVAS_TILE_BYTES);
			r->stage[i].mask = malloc(out->mask_bytes);
			if (!r->stage[i].tiles || !r->stage[i].mask)
				return -ENOMEM; /* freed with the renderer */
		}
		if (!r->stage)
			return -ENOMEM;
	}
	int err = render_to(r, scene, NULL, out);
	rle_volume_sum(out);
	return err;
}

static void cpu_destroy(struct renderer *base)
{
	struct render_cpu *r = (struct render_cpu *)base;
	pool_destroy(r->pool);
	for (unsigned i = 0; r->workers && i < r->base.stats.threads; i++)
		section_canvas_finish(&r->workers[i].canvas);
	free(r->workers);
	for (unsigned i = 0; i < r->stages; i++) {
		free(r->stage[i].tiles);
		free(r->stage[i].mask);
		free(r->stage[i].rle.buf);
	}
	free(r->stage);
	free(r->wedges);
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
	struct render_cpu_options o = { .threads = threads };
	return render_cpu_create_opts(geom, &o);
}

static struct renderer *cpu_new(const struct geometry *geom, halftone_fn halftone, unsigned threads);

struct renderer *render_cpu_create_opts(const struct geometry *geom, const struct render_cpu_options *opts)
{
	halftone_fn halftone = halftone_pick(opts->simd);
	if (!halftone) {
		errno = ENOENT;
		return NULL;
	}
	return cpu_new(geom, halftone, opts->threads);
}

/* One thread, the same halftone variant (they all give the same bits). */
static struct renderer *cpu_serial(const struct renderer *base)
{
	const struct render_cpu *r = (const struct render_cpu *)base;
	return cpu_new(&base->geom, r->halftone, 1);
}

static struct renderer *cpu_new(const struct geometry *geom, halftone_fn halftone, unsigned threads)
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
	unsigned n = pick_threads(geom, threads);
	r->workers = calloc(n, sizeof(*r->workers));
	uint32_t images = geometry_images_per_volume(geom);
	r->wedges = calloc(images, sizeof(*r->wedges));
	if (!r->workers || !r->wedges || bin_init(&r->bins, geom) < 0)
		goto err_free;
	if (brightness_map_init(&r->bright, geom) < 0 || brightness_tables_init(&r->thr, &r->bright) < 0)
		goto err_free;
	for (uint32_t k = 0; k < images; k++)
		section_wedge_init(&r->wedges[k], geom, k);
	for (unsigned i = 0; i < n; i++) {
		if (section_canvas_init(&r->workers[i].canvas, geom) < 0)
			goto err_free;
		r->workers[i].canvas.bright = &r->bright;
		r->base.stats.threads = i + 1; /* canvases to free */
	}
	r->pool = pool_create(n);
	if (!r->pool)
		goto err_free;
	r->base.stats.threads = n;
	return &r->base;

err_free:
	cpu_destroy(&r->base);
	errno = ENOMEM;
	return NULL;
}
