/* The AVX2 and AVX-512 point binning (daemon/render/bin_points.c), and
 * the path picked by default, give exactly the records of the scalar rule,
 * in the same order: random points and points
 * exactly on slot boundaries, on the axis and on its planes (both signs of
 * zero), next to and past the float range (dropped), NaN and infinite
 * ones, under the identity, a turn about the axis, a tilt and a scale,
 * two diagonal ones (one moved by -0), with turns, even and odd point
 * sizes and per-point colours, on mirrored,
 * plain, odd-N, coarse (N = 32) and perspecta geometries, with 1, 2 and 3 workers, and in
 * draws whose lengths are no multiple of four or eight. Likewise the
 * triangles staged eight at a time (bin.c, on mirrored geometries) against
 * those staged one at a time (bin_set.prims_scalar): the same bins, records
 * and turns, from triangles of those points, small ones about every slot
 * boundary, on the axis and across it. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bin.h"
#include "check.h"
#include "pool.h"
#include "rtest.h"

static uint64_t rng = 0x243f6a8885a308d3ull;

static double rnd(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return (double)(rng >> 11) / 9007199254740992.0;
}

/* Points that stress the slot table and the clamps. */
static void make_points(const struct geometry *g, struct rtest_mesh *m, uint32_t random_count)
{
	double d = 2.0 * M_PI / g->images_per_rev;
	for (uint32_t i = 0; i < random_count; i++) {
		double r = 1.2 * sqrt(rnd()), a = 2.0 * M_PI * rnd();
		rtest_mesh_add(m, r * cos(a), (2.0 * rnd() - 1.0) * 1.2 * g->half_height, r * sin(a));
	}
	/* slot boundaries and centres, at several radii */
	for (uint32_t j = 0; j < 2 * g->images_per_rev; j++) {
		double a = 0.5 * j * d;
		for (double r = 1e-6; r < 2.0; r *= 7.0)
			rtest_mesh_add(m, r * cos(a), 0.1 * j / g->images_per_rev, r * sin(a));
		rtest_mesh_add(m, cos(a) * (1 + 1e-7), 0.0, sin(a) * (1 - 1e-7));
		for (int i = 0; i < 12; i++) { /* rounding puts these either side */
			double r = 1.5 * rnd() + 1e-3;
			rtest_mesh_add(m, r * cos(a), (2.0 * rnd() - 1.0) * g->half_height, r * sin(a));
		}
	}
	const double special[][3] = {
		{ 0, 0, 0 },        { -0.0, 0, -0.0 }, { 0.5, 0, 0 },      { -0.5, 0, 0 },      { 0, 0, 0.5 },
		{ 0, 0, -0.5 },     { -0.0, 1, 0.5 },  { 0.5, 1, -0.0 },   { 0.3, 0.2, 0.3 },   { -0.3, 0.2, 0.3 },
		{ 0.3, 0.2, -0.3 }, { -0.3, 5, -0.3 }, { 1e30, 0, 1 },     { 1, 1e30, 1 },      { 1, 0, -1e30 },
		{ 3e38, 0, 3e38 },  { 1e-40, 0, 0 },   { 0, 0, -1e-40 },   { 1e-40, 0, 1e-40 }, { FLT_MAX, 0, 1 },
		{ NAN, 0, 0 },      { 0, NAN, 0 },     { 0, 0, INFINITY }, { -INFINITY, 0, 0 },
	};
	for (size_t i = 0; i < sizeof(special) / sizeof(special[0]); i++)
		rtest_mesh_add(m, special[i][0], special[i][1], special[i][2]);
}

static void set_transforms(struct scene_draw *d, int kind)
{
	rtest_identity(d->transform);
	if (kind == 1) { /* a turn about the axis */
		double a = 0.377;
		d->transform[0] = (float)cos(a);
		d->transform[2] = (float)sin(a);
		d->transform[8] = (float)-sin(a);
		d->transform[10] = (float)cos(a);
	} else if (kind == 2) { /* tilted, scaled, moved */
		d->transform[0] = 0.8f;
		d->transform[1] = 0.3f;
		d->transform[4] = -0.2f;
		d->transform[5] = 1.1f;
		d->transform[9] = 0.25f;
		d->transform[10] = 0.9f;
		d->transform[12] = 0.05f;
		d->transform[14] = -0.1f;
	} else if (kind == 3) { /* huge: most points past the float range */
		d->transform[0] = d->transform[5] = d->transform[10] = 1e37f;
	} else if (kind >= 4) { /* diagonal: scaled and moved (the shortcuts) */
		d->transform[0] = 0.7f;
		d->transform[5] = 1.2f;
		d->transform[10] = -0.8f;
		d->transform[13] = 0.05f;
		d->transform[12] = kind == 4 ? -0.0f : 0.03f; /* -0: no shortcut for triangles */
	}
}

/* n colours of rtest_colour(), for per-item colours (freed by the caller). */
static uint8_t *colours(uint32_t n)
{
	uint8_t *rgbs = malloc(3 * (size_t)n);
	CHECK(rgbs != NULL);
	for (uint32_t i = 0; rgbs && i < n; i++)
		rtest_colour(i, rgbs + 3 * i);
	return rgbs;
}

/* The path pth's binning of scene against ref (the scalar rule's), record
 * for record, twice (the second time in the storage kept). */
static void compare_path(const struct geometry *g, const struct scene *scene, struct pool *pool,
			 const struct bin_set *ref, enum bin_points_isa path, const char *name, unsigned threads)
{
	struct bin_set simd;
	CHECK(bin_init(&simd, g) == 0);
	simd.points_isa = path;
	CHECK(bin_build(&simd, scene, pool) == 0);
	CHECK_MSG(ref->point_count == simd.point_count, "N %u, %s: %u points against %u", g->images_per_rev, name,
		  simd.point_count, ref->point_count);
	CHECK(memcmp(ref->point_start, simd.point_start, (ref->images + 1) * sizeof(uint32_t)) == 0);
	uint32_t differ = 0;
	for (uint32_t i = 0; i < ref->point_count && i < simd.point_count; i++)
		differ += memcmp(&ref->points[i], &simd.points[i], sizeof(struct bin_point)) != 0;
	CHECK_MSG(differ == 0, "N %u, %s, %u threads: %u of %u records differ", g->images_per_rev, name, threads,
		  differ, ref->point_count);
	CHECK(bin_build(&simd, scene, pool) == 0);
	CHECK(simd.point_count == ref->point_count &&
	      memcmp(ref->points, simd.points, ref->point_count * sizeof(struct bin_point)) == 0);
	bin_finish(&simd);
}

static void check_geometry(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	make_points(g, &m, 20000);
	uint32_t n = m.count / 3;
	uint8_t *rgbs = colours(n);
	/* draws of awkward lengths over the same vertices */
	struct scene_draw draws[8];
	uint32_t first = 0;
	for (int i = 0; i < 8; i++) {
		uint32_t len = i == 7 ? n - first : n / 9 + (uint32_t)i;
		draws[i] = rtest_draw(SCENE_POINTS, &m, 255, (uint8_t)(40 * i), 7);
		draws[i].xyz = m.xyz + 3 * (size_t)first;
		draws[i].count = len;
		draws[i].point_size = (uint8_t)(i % 4 == 0 ? 0 : i % 4 == 1 ? 2 : i % 4 == 2 ? 3 : 20);
		draws[i].turn = (uint16_t)(i % 3 == 0 ? 0 : i * 37 + 1);
		draws[i].prim_rgb = i % 2 ? rgbs + 3 * (size_t)first : NULL;
		set_transforms(&draws[i], i % 6);
		first += len;
	}
	struct scene scene = { .draw_count = 8, .draws = draws };
	static const enum bin_points_isa paths[] = { BIN_POINTS_AVX2, BIN_POINTS_AVX512, BIN_POINTS_AUTO };
	static const char *const names[] = { "avx2", "avx512", "auto" };
	for (unsigned threads = 1; threads <= 3; threads++) {
		struct pool *pool = pool_create(threads);
		CHECK(pool != NULL);
		struct bin_set ref;
		CHECK(bin_init(&ref, g) == 0);
		ref.points_isa = BIN_POINTS_SCALAR;
		CHECK(bin_build(&ref, &scene, pool) == 0);
		CHECK(ref.point_count > n / 2);
		for (size_t pth = 0; pth < sizeof(paths) / sizeof(paths[0]); pth++) {
			if (bin_points_isa_supported(paths[pth]))
				compare_path(g, &scene, pool, &ref, paths[pth], names[pth], threads);
			else
				printf("N %u: no %s on this CPU, not compared\n", g->images_per_rev, names[pth]);
		}
		bin_finish(&ref);
		pool_destroy(pool);
	}
	free(rgbs);
	rtest_mesh_free(&m);
}

/* Triangles: the stress points three at a time, then small ones about
 * every slot boundary and across the axis. */
static void make_triangles(const struct geometry *g, struct rtest_mesh *m)
{
	make_points(g, m, 6000);
	m->count -= m->count % 3;
	double d = 2.0 * M_PI / g->images_per_rev;
	for (uint32_t j = 0; j < 2 * g->images_per_rev; j++) {
		double a = (j + 0.5) * d * 0.5, r = 0.05 + 0.9 * rnd(), e = d * (rnd() - 0.5);
		rtest_mesh_add(m, r * cos(a), 0.01, r * sin(a));
		rtest_mesh_add(m, r * cos(a + e), 0.012, r * sin(a + e));
		rtest_mesh_add(m, (r + 1e-3) * cos(a - e), 0.011, (r + 1e-3) * sin(a - e));
		double b = 2.0 * M_PI * rnd(); /* across the axis */
		rtest_mesh_add(m, 1e-3 * cos(b), 0.2, 1e-3 * sin(b));
		rtest_mesh_add(m, -1e-3 * cos(b + 0.1), 0.2, -1e-3 * sin(b + 0.1));
		rtest_mesh_add(m, j % 2 ? 0.0 : 1e-4, 0.21, 0.0);
	}
	/* Spanning about half a turn, and thirds of one, with vertices on
	 * slot centres and boundaries (k half slots): the arcs' limits. */
	uint32_t halves = 2 * g->images_per_rev;
	for (uint32_t j = 0; j < 4 * halves; j++) {
		uint32_t k0 = (uint32_t)(rnd() * halves), k1 = k0 + halves / 2 + (uint32_t)(rnd() * 17) - 8;
		uint32_t k2 = j % 2 ? k0 + (uint32_t)(rnd() * 5) : k0 + halves / 3 + (uint32_t)(rnd() * 3) - 1;
		if (j % 4 == 3)
			k1 = k0 + 2 * halves / 3 + (uint32_t)(rnd() * 3) - 1;
		const uint32_t ks[3] = { k0, k1, k2 };
		for (int v = 0; v < 3; v++) {
			double a = 0.5 * ks[v] * d, r = 0.1 + rnd();
			rtest_mesh_add(m, r * cos(a), 0.3, r * sin(a));
		}
	}
}

/* The draws of the n triangles of m (per-triangle colours rgbs): six
 * over consecutive ranges, with and without turns and colours of their
 * own, under each transform of set_transforms(); then two of one colour
 * and no turn (records written eight at once) with lanes the scalar rule
 * drops: draw 4's range holds the special vertices (NaN, infinite, past
 * the float range), drawn as they are and under the huge transform. */
static void triangle_draws(struct rtest_mesh *m, uint32_t n, uint8_t *rgbs, struct scene_draw draws[8])
{
	uint32_t first = 0;
	for (int i = 0; i < 6; i++) {
		uint32_t len = i == 5 ? n - first : n / 7 + (uint32_t)i;
		draws[i] = rtest_draw(SCENE_TRIANGLES, m, 255, (uint8_t)(40 * i), 7);
		draws[i].xyz = m->xyz + 9 * (size_t)first;
		draws[i].count = 3 * len;
		draws[i].turn = (uint16_t)(i % 3 == 0 ? 0 : i * 37 + 1);
		draws[i].prim_rgb = i % 2 ? rgbs + 3 * (size_t)first : NULL;
		set_transforms(&draws[i], i % 6);
		first += len;
	}
	for (int i = 6; i < 8; i++) {
		draws[i] = draws[4];
		draws[i].turn = 0;
		draws[i].prim_rgb = NULL;
		set_transforms(&draws[i], i == 6 ? 0 : 3);
	}
}

static void check_triangles(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	make_triangles(g, &m);
	uint32_t n = m.count / 3;
	uint8_t *rgbs = colours(n);
	struct scene_draw draws[8];
	triangle_draws(&m, n, rgbs, draws);
	struct scene scene = { .draw_count = 8, .draws = draws };
	for (unsigned threads = 1; threads <= 2; threads++) {
		struct pool *pool = pool_create(threads);
		CHECK(pool != NULL);
		struct bin_set ref, wide;
		CHECK(bin_init(&ref, g) == 0 && bin_init(&wide, g) == 0);
		ref.prims_scalar = true;
		CHECK(bin_build(&ref, &scene, pool) == 0);
		CHECK(bin_build(&wide, &scene, pool) == 0);
		CHECK(ref.prim_count > n / 2);
		CHECK_MSG(ref.prim_count == wide.prim_count, "N %u: %u triangles against %u", g->images_per_rev,
			  wide.prim_count, ref.prim_count);
		CHECK(memcmp(ref.prim_start, wide.prim_start, (ref.classes * ref.images + 1) * sizeof(uint32_t)) == 0);
		uint32_t differ = 0;
		for (uint32_t i = 0; i < ref.prim_count && i < wide.prim_count; i++)
			differ += memcmp(&ref.prims[i], &wide.prims[i], sizeof(struct bin_prim)) != 0 ||
				  ref.prim_turn[i] != wide.prim_turn[i];
		CHECK_MSG(differ == 0, "N %u, %u threads: %u of %u triangles differ", g->images_per_rev, threads,
			  differ, ref.prim_count);
		bin_finish(&ref);
		bin_finish(&wide);
		pool_destroy(pool);
	}
	free(rgbs);
	rtest_mesh_free(&m);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd(), perspecta;
	struct geometry even_plain = { 200, 40, 64, false, 1.25f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	struct geometry odd_n = { 96, 64, 45, false, 1.25f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	struct geometry coarse = { 64, 64, 32, true, 1.0f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT }; /* wide slots */
	CHECK(geometry_from_profile("perspecta", &perspecta) == 0);
	check_geometry(&small);
	check_geometry(&odd);
	check_geometry(&even_plain);
	check_geometry(&odd_n);
	check_geometry(&coarse);
	check_geometry(&perspecta);
	check_triangles(&small);
	check_triangles(&odd);
	check_triangles(&even_plain);
	check_triangles(&perspecta);
	return check_done();
}
