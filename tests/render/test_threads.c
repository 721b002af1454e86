/* Determinism: any thread count gives byte-identical volumes, and a
 * renderer gives the same volume for the same scene every time, whatever it
 * rendered in between. Plus render_create() names and argument checks. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "rtest.h"

static uint32_t lcg(uint32_t *s)
{
	*s = *s * 1664525u + 1013904223u;
	return *s >> 8;
}

static double rnd(uint32_t *s, double lo, double hi)
{
	return lo + (hi - lo) * (lcg(s) / (double)(1u << 24));
}

/* A busy scene: a moved, rotated sphere, random triangles, lines, points. */
struct busy {
	struct rtest_mesh sphere, tris, lines, points;
	struct scene_draw draws[4];
};

static void busy_init(struct busy *b, uint32_t seed)
{
	*b = (struct busy){ 0 };
	rtest_sphere(&b->sphere, 0.3, 24, 12);
	for (int i = 0; i < 600; i++)
		rtest_mesh_add(&b->tris, rnd(&seed, -1, 1), rnd(&seed, -1, 1), rnd(&seed, -1, 1));
	for (int i = 0; i < 200; i++)
		rtest_mesh_add(&b->lines, rnd(&seed, -1.1, 1.1), rnd(&seed, -1, 1), rnd(&seed, -1.1, 1.1));
	for (int i = 0; i < 500; i++)
		rtest_mesh_add(&b->points, rnd(&seed, -1, 1), rnd(&seed, -1, 1), rnd(&seed, -1, 1));
	b->draws[0] = rtest_draw(SCENE_TRIANGLES, &b->sphere, 250, 120, 10);
	float *t = b->draws[0].transform;
	double a = 0.4;
	t[0] = (float)cos(a), t[2] = (float)sin(a), t[8] = (float)-sin(a), t[10] = (float)cos(a);
	t[12] = 0.4f, t[13] = 0.1f, t[14] = -0.2f;
	b->draws[1] = rtest_draw(SCENE_TRIANGLES, &b->tris, 90, 200, 140);
	b->draws[2] = rtest_draw(SCENE_LINES, &b->lines, 255, 255, 40);
	b->draws[3] = rtest_draw(SCENE_POINTS, &b->points, 30, 60, 255);
}

static void busy_free(struct busy *b)
{
	rtest_mesh_free(&b->sphere);
	rtest_mesh_free(&b->tris);
	rtest_mesh_free(&b->lines);
	rtest_mesh_free(&b->points);
}

static void check_thread_counts(const struct geometry *g, bool quick)
{
	struct busy b;
	busy_init(&b, 7);
	struct volume *ref = rtest_render(g, b.draws, 4, 1);
	CHECK(rtest_count(ref, 0) > 1000);
	CHECK(rtest_padding_clear(ref));
	const unsigned counts[] = { 2, 0, 3, 4, 7 };
	for (size_t i = 0; i < (quick ? 2 : sizeof(counts) / sizeof(counts[0])); i++) {
		struct volume *vol = rtest_render(g, b.draws, 4, counts[i]);
		CHECK_MSG(rtest_same(ref, vol), "%u threads differ from 1", counts[i]);
		volume_destroy(vol);
	}
	volume_destroy(ref);
	busy_free(&b);
}

static void check_repeat(const struct geometry *g)
{
	struct busy a, b;
	busy_init(&a, 1);
	busy_init(&b, 2);
	struct scene sa = { .draw_count = 4, .draws = a.draws }, sb = { .draw_count = 4, .draws = b.draws };
	struct renderer *r = render_create("cpu", g, 0);
	struct volume *v1 = volume_create(g), *v2 = volume_create(g), *vb = volume_create(g);
	CHECK(r && v1 && v2 && vb);
	CHECK(render_volume(r, &sa, v1) == 0);
	CHECK(render_volume(r, &sb, vb) == 0);
	CHECK(render_volume(r, &sb, v2) == 0); /* v2 now holds b's volume */
	CHECK(rtest_same(vb, v2));
	CHECK(!rtest_same(v1, v2));
	CHECK(render_volume(r, &sa, v2) == 0); /* over old content */
	CHECK(rtest_same(v1, v2));
	struct scene empty = { 0 };
	CHECK(render_volume(r, &empty, v2) == 0);
	CHECK(volume_tile_count(v2) == 0);
	volume_destroy(v1);
	volume_destroy(v2);
	volume_destroy(vb);
	render_destroy(r);
	busy_free(&a);
	busy_free(&b);
}

static void check_create(void)
{
	struct geometry g = rtest_small(), other = rtest_odd(), bad = g;
	struct renderer *r = render_create("auto", &g, 0);
	CHECK(r && r->impl && r->impl->name);
	struct volume *vol = volume_create(&other);
	struct scene empty = { 0 };
	CHECK(render_volume(r, &empty, vol) == -EINVAL);
	render_destroy(r);
	volume_destroy(vol);
	render_destroy(NULL);
	errno = 0;
	CHECK(render_create("no-such-renderer", &g, 0) == NULL && errno == ENOENT);
	bad.images_per_rev = 7; /* odd but mirrored */
	errno = 0;
	CHECK(render_cpu_create(&bad, 1) == NULL && errno == EINVAL);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd(), big;
	CHECK(geometry_from_profile("perspecta", &big) == 0);
	check_thread_counts(&small, false);
	check_thread_counts(&odd, false);
	check_thread_counts(&big, true);
	check_repeat(&small);
	check_repeat(&odd);
	check_create();
	return check_done();
}
