/* Points lit straight as halftoned bits (section_lit_pixel(), the canvas's
 * lit bits) give the volume of points lit as bytes and halftoned with the
 * rest: the default CPU renderer, which takes the bits, against the
 * "scalar" variant, which keeps every point as bytes, bit for bit. Points
 * of every level about the thresholds, draw colours and per-point colours,
 * many on one pixel (the MAX), squares (bytes on both), alone and sharing
 * tiles with triangles of the plain colour and of another (bits ORed into a
 * halftoned tile), turned; mirrored and not, in each brightness model
 * (its band's own thresholds), on one and two threads. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "renderer.h"
#include "rtest.h"

#define DRAWS 6

struct cloud {
	struct rtest_mesh mesh[DRAWS];
	uint8_t *rgb; /* per point of mesh[1] */
	struct scene_draw draws[DRAWS];
};

/* n points in the cylinder of radius r about (cx, cz), |y| <= h. */
static void scatter(struct rtest_mesh *m, uint64_t *seed, uint32_t n, double cx, double cz, double r, double h)
{
	for (uint32_t i = 0; i < n; i++) {
		double a = rtest_range(seed, 0, 6.283185307179586), s = r * rtest_rnd(seed);
		rtest_mesh_add(m, cx + s * __builtin_cos(a), rtest_range(seed, -h, h), cz + s * __builtin_sin(a));
	}
}

/* Levels on both sides of the thresholds (0..254) and at the ends. */
static uint8_t level(uint64_t *seed)
{
	static const uint8_t ends[] = { 0, 1, 127, 128, 254, 255 };
	double x = rtest_rnd(seed);
	return x < 0.2 ? ends[(int)(x * 30)] : (uint8_t)(rtest_rnd(seed) * 256);
}

static void cloud_make(struct cloud *c, const struct geometry *g, uint64_t seed)
{
	memset(c, 0, sizeof(*c));
	double h = g->half_height;
	scatter(&c->mesh[0], &seed, 3000, 0, 0, 1.05, 1.05 * h);      /* everywhere, some clamped */
	scatter(&c->mesh[1], &seed, 3000, 0.3, -0.2, 0.02, 0.02 * h); /* a ball: many per pixel */
	scatter(&c->mesh[2], &seed, 400, 0, 0, 0.6, h);               /* squares */
	scatter(&c->mesh[3], &seed, 600, 0, 0, 0.004, h);             /* at the axis */
	rtest_sphere(&c->mesh[4], 0.5, 24, 12);
	rtest_sphere(&c->mesh[5], 0.32, 20, 10);
	c->rgb = malloc(3 * (size_t)c->mesh[1].count);
	CHECK(c->rgb);
	for (uint32_t i = 0; i < 3 * c->mesh[1].count; i++)
		c->rgb[i] = level(&seed);
	for (int i = 0; i < DRAWS; i++) {
		enum scene_prim prim = i < 4 ? SCENE_POINTS : SCENE_TRIANGLES;
		c->draws[i] = rtest_draw(prim, &c->mesh[i], level(&seed), level(&seed), level(&seed));
	}
	c->draws[1].prim_rgb = c->rgb;
	c->draws[2].point_size = 3;
	/* the outer sphere, the triangle draw with the most vertices and so
	 * the canvases' plain colour, in the first cloud's colour */
	memcpy(c->draws[4].rgb, c->draws[0].rgb, 3);
}

static void cloud_free(struct cloud *c)
{
	for (int i = 0; i < DRAWS; i++)
		rtest_mesh_free(&c->mesh[i]);
	free(c->rgb);
}

static struct volume *render(const struct geometry *g, const struct scene_draw *d, uint32_t n, const char *simd,
			     unsigned threads)
{
	struct render_cpu_options o = { .threads = threads, .simd = simd };
	struct renderer *r = render_cpu_create_opts(g, &o);
	struct volume *vol = volume_create(g);
	CHECK(r && vol);
	struct scene s = { .draw_count = n, .draws = (struct scene_draw *)d };
	CHECK(render_volume(r, &s, vol) == 0);
	render_destroy(r);
	return vol;
}

/* The default renderer against the scalar one on draws d[0..n). */
static void compare(const struct geometry *g, const struct scene_draw *d, uint32_t n, const char *what)
{
	struct volume *ref = render(g, d, n, "scalar", 1);
	CHECK(rtest_count(ref, 0) + rtest_count(ref, 1) + rtest_count(ref, 2) > 0);
	for (unsigned threads = 1; threads <= 2; threads++) {
		struct volume *got = render(g, d, n, NULL, threads);
		CHECK_MSG(rtest_same(got, ref), "%ux%u N %u %s, %s, %u thread(s): lit points differ from bytes",
			  g->width, g->height, g->images_per_rev, geometry_brightness_name(g->brightness), what,
			  threads);
		volume_destroy(got);
	}
	volume_destroy(ref);
}

static void check_geometry(struct geometry g)
{
	struct cloud c;
	cloud_make(&c, &g, 0x5eed + g.images_per_rev);
	for (uint8_t b = GEOMETRY_BRIGHTNESS_EXACT; b <= GEOMETRY_BRIGHTNESS_UNIFORM; b++) {
		g.brightness = b;
		compare(&g, c.draws, 4, "points alone");
		compare(&g, c.draws, DRAWS, "points and triangles");
		struct scene_draw turned[DRAWS];
		memcpy(turned, c.draws, sizeof(turned));
		for (int i = 0; i < DRAWS; i++)
			turned[i].turn = (uint16_t)((7 + 5 * i) % g.images_per_rev);
		compare(&g, turned, DRAWS, "turned");
	}
	cloud_free(&c);
}

int main(void)
{
	check_geometry(rtest_small());
	check_geometry(rtest_odd());
	return check_done();
}
