/* Dense draws of one-pixel points of one colour binned as masks (bin.h,
 * struct bin_point_mask): a mask's bits are exactly the voxels of the
 * records the scalar rule gives the same points, and the CPU renderer
 * that lights the masks gives the volume, and the canvases (the object
 * cache's form), of the scalar variant, which lights records, bit for
 * bit. Random points and points on slot boundaries, on the axis, past the
 * float range, NaN and infinite, under the identity, a scale and shift
 * (the diagonal shortcut), a tilt and a huge scale; beside draws that stay
 * records (per-point colours, a turn, squares); on geometries of at most
 * 64 volume images (cos and sin from registers) and of more, with partial
 * tiles; on 1 to 3 threads; in each brightness model. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bin.h"
#include "check.h"
#include "pool.h"
#include "renderer.h"
#include "rle.h"
#include "rtest.h"

#define MASKED 4 /* draws that qualify */
#define DRAWS 7

struct cloud {
	struct rtest_mesh mesh;
	uint8_t *rgb; /* per point, for the draw of per-point colours */
	struct scene_draw draws[DRAWS];
};

static const uint8_t colour[MASKED][3] = { { 255, 0, 0 }, { 0, 255, 0 }, { 0, 0, 255 }, { 200, 130, 60 } };

/* per points of each draw: random in and past the volume, and for each
 * draw its share of the stress points */
static void add_points(const struct geometry *g, struct rtest_mesh *m, uint64_t *seed, uint32_t per)
{
	static const double special[][3] = {
		{ 0, 0, 0 },    { -0.0, 0, -0.0 }, { 0.5, 0, 0 },      { -0.5, 0, -0.0 },
		{ 1e30, 0, 1 }, { 1, 1e30, 1 },    { 3e38, 0, 3e38 },  { 1e-40, 0, 0 },
		{ NAN, 0, 0 },  { 0, NAN, 0 },     { 0, 0, INFINITY }, { -INFINITY, 0, 0 },
	};
	const uint32_t n_special = sizeof(special) / sizeof(special[0]);
	double d = 2.0 * M_PI / g->images_per_rev;
	for (uint32_t i = 0; i < per; i++) {
		double x, y = rtest_range(seed, -1.1, 1.1) * g->half_height, z, r;
		if (i < n_special) {
			x = special[i][0];
			y = special[i][1];
			z = special[i][2];
		} else if (i % 5 == 0) { /* on and about a slot boundary */
			double a = 0.5 * (double)(i / 5 % (2 * g->images_per_rev)) * d;
			r = rtest_range(seed, 1e-6, 1.0);
			x = r * cos(a) * (1 + 1e-7 * (i % 3));
			z = r * sin(a);
		} else {
			r = 1.15 * sqrt(rtest_rnd(seed));
			double a = rtest_range(seed, 0, 2 * M_PI);
			x = r * cos(a);
			z = r * sin(a);
		}
		rtest_mesh_add(m, x, y, z);
	}
}

static void cloud_make(struct cloud *c, const struct geometry *g, uint32_t per)
{
	memset(c, 0, sizeof(*c));
	uint64_t seed = 0x6d61736b + g->images_per_rev;
	for (int i = 0; i < DRAWS; i++)
		add_points(g, &c->mesh, &seed, per);
	c->rgb = malloc(3 * (size_t)per);
	CHECK(c->rgb != NULL);
	for (uint32_t i = 0; c->rgb && i < per; i++)
		rtest_colour(i, c->rgb + 3 * i);
	for (int i = 0; i < DRAWS; i++) {
		struct scene_draw *d = &c->draws[i];
		*d = rtest_draw(SCENE_POINTS, &c->mesh, 90, 90, 90);
		d->xyz = c->mesh.xyz + 3 * (size_t)i * per;
		d->count = per;
		if (i < MASKED)
			memcpy(d->rgb, colour[i], 3);
		d->point_size = (uint8_t)(i % 2); /* 0 counts as 1 */
		d->data_id = (uint64_t)i + 1;     /* binning kept (render_cpu_options.keep) */
	}
	float *t = c->draws[1].transform; /* scaled and moved: diagonal */
	t[0] = 0.8f, t[5] = 1.25f, t[10] = -0.9f, t[12] = 0.05f, t[13] = -0.1f, t[14] = 0.02f;
	t = c->draws[2].transform; /* tilted */
	t[0] = 0.8f, t[1] = 0.3f, t[4] = -0.2f, t[5] = 1.1f, t[9] = 0.25f, t[10] = 0.9f;
	t = c->draws[3].transform; /* huge: most past the float range */
	t[0] = t[5] = t[10] = 1e37f;
	c->draws[4].prim_rgb = c->rgb;                            /* records: per-point colours */
	c->draws[5].turn = (uint16_t)(g->images_per_rev / 3 + 1); /* records: turned */
	c->draws[6].point_size = 3;                               /* records: squares */
}

static void cloud_free(struct cloud *c)
{
	rtest_mesh_free(&c->mesh);
	free(c->rgb);
}

/* The voxels of ref's records of colour rgb, a mask's bits. */
static void records_mask(const struct bin_set *ref, const uint8_t rgb[3], uint32_t *bits)
{
	uint32_t tiles_x = volume_tiles_across(ref->geom.width), tiles = volume_geometry_tiles(&ref->geom);
	memset(bits, 0, bin_mask_words(ref) * sizeof(uint32_t));
	for (uint32_t k = 0; k < ref->images; k++)
		for (uint32_t i = ref->point_start[k]; i < ref->point_start[k + 1]; i++) {
			const struct bin_point *p = &ref->points[i];
			if (memcmp(p->rgb, rgb, 3) != 0)
				continue;
			CHECK(p->size == 1);
			size_t t = (size_t)k * tiles + (p->v / VOLUME_TILE) * tiles_x + p->u / VOLUME_TILE;
			bits[t * VOLUME_TILE + p->v % VOLUME_TILE] |= 1u << ((p->u % VOLUME_TILE) ^ 7);
		}
}

/* The masks against the scalar rule's records, colour by colour. */
static void check_bins(const struct geometry *g, const struct cloud *c, unsigned threads)
{
	struct scene scene = { .draw_count = DRAWS, .draws = (struct scene_draw *)c->draws };
	struct pool *pool = pool_create(threads);
	struct bin_set ref, got;
	CHECK(pool && bin_init(&ref, g) == 0 && bin_init(&got, g) == 0);
	ref.points_isa = BIN_POINTS_SCALAR;
	got.point_masks = true;
	CHECK(bin_build(&ref, &scene, pool) == 0);
	for (int pass = 0; pass < 2; pass++) { /* the second in the storage kept */
		CHECK(bin_build(&got, &scene, pool) == 0);
		CHECK_MSG(got.mask_count >= MASKED && got.mask_points >= (uint64_t)MASKED * c->draws[0].count,
			  "N %u, %u threads: %u masks of %llu points", g->images_per_rev, threads, got.mask_count,
			  (unsigned long long)got.mask_points);
		size_t words = bin_mask_words(&got);
		uint32_t *want = malloc(words * sizeof(uint32_t)), *have = calloc(words, sizeof(uint32_t));
		CHECK(want && have);
		for (int i = 0; want && have && i < MASKED; i++) {
			records_mask(&ref, colour[i], want);
			memset(have, 0, words * sizeof(uint32_t));
			for (uint32_t m = 0; m < got.mask_count; m++)
				for (size_t w = 0; memcmp(got.masks[m].rgb, colour[i], 3) == 0 && w < words; w++)
					have[w] |= got.masks[m].bits[w];
			CHECK_MSG(memcmp(want, have, words * sizeof(uint32_t)) == 0,
				  "N %u, %u threads: draw %d's mask is not its records' voxels", g->images_per_rev,
				  threads, i);
		}
		free(want);
		free(have);
	}
	bin_finish(&ref);
	bin_finish(&got);
	pool_destroy(pool);
}

static struct renderer *renderer(const struct geometry *g, const char *simd, unsigned threads, bool keep)
{
	struct render_cpu_options o = { .threads = threads, .simd = simd, .keep = keep };
	struct renderer *r = render_cpu_create_opts(g, &o);
	CHECK(r != NULL);
	return r;
}

/* The default renderer (masks) against the scalar one (records): the
 * volume, again from the binning kept (as the daemon renders), and the
 * canvases render_canvas() keeps as bytes. */
static void check_render(const struct geometry *g, const struct cloud *c, unsigned threads)
{
	struct scene scene = { .draw_count = DRAWS, .draws = (struct scene_draw *)c->draws };
	struct renderer *ref = renderer(g, "scalar", 1, false), *got = renderer(g, NULL, threads, true);
	struct volume *want = volume_create(g), *have = volume_create(g);
	CHECK(ref && got && want && have);
	CHECK(render_volume(ref, &scene, want) == 0);
	CHECK(rtest_count(want, 0) + rtest_count(want, 1) + rtest_count(want, 2) > 0);
	for (int pass = 0; pass < 2; pass++) {
		CHECK(render_volume(got, &scene, have) == 0);
		CHECK(got->stats.bins_kept == (pass == 1));
		CHECK_MSG(rtest_same(have, want), "%ux%u N %u %s, %u threads, pass %d: the volume differs", g->width,
			  g->height, g->images_per_rev, geometry_brightness_name(g->brightness), threads, pass);
	}
	uint32_t M = geometry_images_per_volume(g), tiles = volume_geometry_tiles(g);
	struct rle_volume *cw = rle_volume_new(M, (tiles + 7) / 8, tiles, CANVAS_TILE_BYTES);
	struct rle_volume *ch = rle_volume_new(M, (tiles + 7) / 8, tiles, CANVAS_TILE_BYTES);
	CHECK(cw && ch);
	CHECK(ref->impl->render_canvas(ref, &scene, cw) == 0 && got->impl->render_canvas(got, &scene, ch) == 0);
	uint32_t differ = 0;
	for (uint32_t k = 0; k < M; k++)
		differ += cw->images[k].len != ch->images[k].len ||
			  memcmp(cw->images[k].data, ch->images[k].data, cw->images[k].len) != 0;
	CHECK_MSG(differ == 0, "%ux%u N %u, %u threads: %u images' canvases differ", g->width, g->height,
		  g->images_per_rev, threads, differ);
	rle_volume_free(cw);
	rle_volume_free(ch);
	volume_destroy(want);
	volume_destroy(have);
	render_destroy(ref);
	render_destroy(got);
}

static void check_geometry(struct geometry g, unsigned max_threads)
{
	/* enough points a draw that each thread's share is as many as a mask's words */
	struct bin_set probe;
	CHECK(bin_init(&probe, &g) == 0);
	uint32_t per = (uint32_t)bin_mask_words(&probe) * max_threads + 61;
	bin_finish(&probe);
	struct cloud c;
	cloud_make(&c, &g, per);
	if (!bin_points_isa_supported(BIN_POINTS_AVX512)) {
		printf("no AVX-512 here: points stay records, masks not compared\n");
	} else {
		for (unsigned t = 1; t <= max_threads; t++)
			check_bins(&g, &c, t);
	}
	for (uint8_t b = GEOMETRY_BRIGHTNESS_EXACT; b <= GEOMETRY_BRIGHTNESS_UNIFORM; b++) {
		g.brightness = b;
		check_render(&g, &c, b == GEOMETRY_BRIGHTNESS_EXACT ? max_threads : 1);
	}
	cloud_free(&c);
}

int main(void)
{
	struct geometry few = { 64, 64, 32, true, 1.0f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	struct geometry many = { 72, 40, 160, true, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	check_geometry(few, 3);
	check_geometry(many, 2);
	check_geometry(rtest_small(), 1); /* 64 images: the last that picks from registers */
	return check_done();
}
