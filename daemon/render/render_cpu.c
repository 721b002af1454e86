/* The exact CPU sectioning renderer: the reference every other renderer is
 * measured against (DESIGN.md section 5). Per volume, primitives are
 * transformed and binned once; then worker threads take images one at a
 * time, section their binned primitives into an 8-bit canvas, and halftone
 * and pack only the tiles something touched. */
#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bin.h"
#include "halftone.h"
#include "render.h"
#include "section.h"

struct cpu_worker {
	struct render_cpu *r;
	struct section_canvas canvas;
	pthread_t thread;
	int err;
};

struct render_cpu {
	struct renderer base;
	unsigned worker_count;
	struct cpu_worker *workers;
	struct bin_set bins;
	/* Per render: */
	struct volume *out;
	atomic_uint next_image;
};

/* Halftones one canvas tile of image k into the packed tile layout of
 * volume.h: planes R, G, B of 32 rows of 4 bytes, MSB leftmost. */
static void halftone_tile(const uint8_t *rgb, const uint8_t *thr, uint8_t *tile)
{
	for (int c = 0; c < 3; c++) {
		uint8_t *plane = tile + c * VOLUME_TILE_PLANE_BYTES;
		for (int y = 0; y < 32; y++) {
			const uint8_t *row = rgb + y * 32 * 3 + c;
			for (int xb = 0; xb < 4; xb++) {
				uint8_t byte = 0;
				for (int bit = 0; bit < 8; bit++) {
					int x = xb * 8 + bit;
					if (row[x * 3] > thr[(y & 15) * 16 + (x & 15)])
						byte |= (uint8_t)(0x80u >> bit);
				}
				plane[y * 4 + xb] = byte;
			}
		}
	}
}

/* Packs the touched tiles of image k in increasing order and leaves the
 * canvas all zero again, whether or not packing succeeded. */
static int pack_image(struct section_canvas *c, struct volume *out, uint32_t k)
{
	uint8_t thr[256], tile[VOLUME_TILE_BYTES];
	int err = 0;
	/* Tile origins are multiples of 32, so the phase table of the tile's
	 * local coordinates is the image's. */
	for (uint32_t y = 0; y < 16; y++)
		for (uint32_t x = 0; x < 16; x++)
			thr[y * 16 + x] = render_dither_threshold(k, x, y);
	uint32_t tiles = c->tiles_x * c->tiles_y;
	for (uint32_t t = 0; t < tiles; t++) {
		if (!c->touched[t])
			continue;
		if (err == 0) {
			halftone_tile(c->rgb + (size_t)t * SECTION_TILE_RGB_BYTES, thr, tile);
			err = volume_image_append(out, k, t, tile);
		}
		section_canvas_clear_tile(c, t);
	}
	return err;
}

static int render_image(struct render_cpu *r, struct section_canvas *c, uint32_t k)
{
	const struct bin_set *b = &r->bins;
	struct section_wedge w;
	section_wedge_init(&w, &r->base.geom, k);
	for (uint32_t i = b->start[k]; i < b->start[k + 1]; i++) {
		const struct bin_prim *p = &b->prims[b->index[i]];
		if (p->nverts == 1)
			section_point(c, &w, p->v[0], p->rgb);
		else
			section_prim(c, &w, (const double (*)[3])p->v, p->nverts, p->rgb);
	}
	return pack_image(c, r->out, k);
}

/* Images are handed out one at a time; each image's result depends on
 * nothing but the scene, so any split gives identical output. */
static void *worker_main(void *arg)
{
	struct cpu_worker *w = arg;
	struct render_cpu *r = w->r;
	w->err = 0;
	for (;;) {
		uint32_t k = atomic_fetch_add(&r->next_image, 1);
		if (k >= r->bins.image_count)
			break;
		int err = render_image(r, &w->canvas, k);
		if (err < 0 && w->err == 0)
			w->err = err;
	}
	return NULL;
}

static int check_output(const struct render_cpu *r, const struct volume *out)
{
	const struct geometry *a = &r->base.geom, *b = &out->geom;
	if (a->width != b->width || a->height != b->height ||
	    a->images_per_rev != b->images_per_rev || a->mirrored != b->mirrored ||
	    a->half_height != b->half_height)
		return -EINVAL;
	return 0;
}

/* Worker 0 runs on the caller's thread; if a thread can't be started its
 * share simply goes to the others. */
static int run_workers(struct render_cpu *r)
{
	unsigned started = 1;
	for (unsigned i = 1; i < r->worker_count; i++) {
		if (pthread_create(&r->workers[i].thread, NULL, worker_main, &r->workers[i]) != 0)
			break;
		started++;
	}
	worker_main(&r->workers[0]);
	int err = r->workers[0].err;
	for (unsigned i = 1; i < started; i++) {
		pthread_join(r->workers[i].thread, NULL);
		if (err == 0)
			err = r->workers[i].err;
	}
	return err;
}

static int cpu_render(struct renderer *base, const struct scene *scene, struct volume *out)
{
	struct render_cpu *r = (struct render_cpu *)base;
	int err = check_output(r, out);
	if (err < 0)
		return err;
	volume_clear(out);
	err = bin_build(&r->bins, &base->geom, scene);
	if (err < 0)
		return err;
	r->out = out;
	atomic_store(&r->next_image, 0);
	err = run_workers(r);
	r->out = NULL;
	return err;
}

static void cpu_destroy(struct renderer *base)
{
	struct render_cpu *r = (struct render_cpu *)base;
	for (unsigned i = 0; i < r->worker_count; i++)
		section_canvas_finish(&r->workers[i].canvas);
	free(r->workers);
	bin_finish(&r->bins);
	free(r);
}

static const struct renderer_impl cpu_impl = {
	.name = "cpu",
	.render = cpu_render,
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

struct renderer *render_cpu_create_opts(const struct geometry *geom,
					const struct render_cpu_options *opts)
{
	unsigned threads = opts->threads;
	if (!halftone_pick(opts->simd)) {
		errno = ENOENT;
		return NULL;
	}
	if (geometry_validate(geom) < 0) {
		errno = EINVAL;
		return NULL;
	}
	struct render_cpu *r = calloc(1, sizeof(*r));
	if (!r)
		return NULL;
	r->base.impl = &cpu_impl;
	r->base.geom = *geom;
	r->worker_count = pick_threads(geom, threads);
	r->workers = calloc(r->worker_count, sizeof(*r->workers));
	if (!r->workers || bin_init(&r->bins, geom) < 0)
		goto err_free;
	for (unsigned i = 0; i < r->worker_count; i++) {
		r->workers[i].r = r;
		if (section_canvas_init(&r->workers[i].canvas, geom) < 0)
			goto err_free;
	}
	return &r->base;

err_free:
	cpu_destroy(&r->base);
	errno = ENOMEM;
	return NULL;
}
