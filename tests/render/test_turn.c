/* Turns and lifts (scene.h, scene_draw.turn and .lift) on the CPU renderer,
 * the reference, and on the GL renderers, which hand a scene with a turn or
 * a lift to their CPU fallback.
 *
 * The definition (scene.h): a draw with turn m lights in volume image k
 * what it lights unturned in image j = k - m, taken mod N unmirrored; on a
 * mirrored device j is brought into [0, M) by adding or subtracting M, each
 * time flipping the mirror, and with odd flips the columns are mirrored
 * (u -> W-1-u). Rows never change; the halftone keeps image k's phase. A
 * draw with lift L lights in row v what it lights unlifted in row v + L
 * (nothing where that is outside the image), before the halftone.
 *
 * 1. Saturated colours (channels 0 or 255, whose halftone does not depend
 *    on the phase): the turned render is the unturned one with its images
 *    shifted and mirrored, pixel for pixel (volume_pixel()), for one turn on
 *    every draw and for a different turn on each draw (their union); the
 *    same with lifts, rows shifted too.
 * 2. Any colours: turned and lifted image k is lit exactly where the draws
 *    covering the source pixel (lit unturned and unlifted in white) give a
 *    value above image k's threshold there.
 * 3. A renderer that drew turns and lifts draws an unmoved scene as a fresh
 *    one, and any thread count gives the same volume.
 * 4. Geometry: a draw with turn m lights, within one voxel both ways
 *    (bench/coverage.h: coverage 100%, no stray voxel), what the same draw
 *    turned by m * 2 pi / N through its transform lights; a draw with lift
 *    L inside the image what it lights moved up by L rows.
 * 5. GL (EGL, OSMesa where built and where a context can be made): a scene
 *    with a turned or lifted draw renders on the CPU fallback (stats.engine
 *    RENDER_ENGINE_CPU), equal to the CPU renderer's volume; one without
 *    stays on GL.
 *
 * On the small profile (mirrored, M = N/2) and rtest_odd() (unmirrored). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "coverage.h"
#include "halftone.h"
#include "render_gl.h"
#include "rng.h"
#include "rtest.h"

#define MAX_DRAWS 8

/* The draws of a random scene, over meshes and colours it owns. */
struct tscene {
	uint32_t n;
	struct scene_draw draws[MAX_DRAWS];
	struct rtest_mesh mesh[MAX_DRAWS];
	uint8_t *prim_rgb[MAX_DRAWS];
};

static void tscene_free(struct tscene *s)
{
	for (uint32_t i = 0; i < MAX_DRAWS; i++) {
		rtest_mesh_free(&s->mesh[i]);
		free(s->prim_rgb[i]);
	}
	memset(s, 0, sizeof(*s));
}

static uint32_t images_of(const struct geometry *g)
{
	return g->mirrored ? g->images_per_rev / 2 : g->images_per_rev;
}

/* scene.h's definition, literally: the image whose unturned content image
 * k shows at turn m, and whether mirrored. */
static uint32_t source_image(const struct geometry *g, uint32_t k, uint32_t m, bool *mirror)
{
	long n = g->images_per_rev, M = images_of(g), j = (long)k - (long)m;
	*mirror = false;
	if (!g->mirrored)
		return (uint32_t)(((j % n) + n) % n);
	while (j < 0) {
		j += M;
		*mirror = !*mirror;
	}
	while (j >= M) {
		j -= M;
		*mirror = !*mirror;
	}
	return (uint32_t)j;
}

/* A point uniform in the cylinder r <= rmax, |y| <= ymax h. */
static void random_point(struct rng *rng, const struct geometry *g, double rmax, double ymax, double p[3])
{
	double rad = rmax * sqrt(rng_unit(rng)), a = rng_range(rng, 0, 2 * M_PI);
	p[0] = rad * cos(a);
	p[1] = rng_range(rng, -ymax, ymax) * g->half_height;
	p[2] = rad * sin(a);
}

/* n random primitives of nv vertices: tiny to larger than the volume, some
 * across the axis, some partly outside (clamped to the image edges). */
static void random_prims(struct rng *rng, const struct geometry *g, int nv, uint32_t n, struct rtest_mesh *m)
{
	for (uint32_t i = 0; i < n; i++) {
		double c[3], size = i % 9 == 0 ? 1.5 : i % 3 == 0 ? 0.3 : rng_range(rng, 0.003, 0.08);
		random_point(rng, g, i % 5 == 0 ? 0.05 : 1.1, 1.1, c);
		for (int v = 0; v < nv; v++)
			rtest_mesh_add(m, c[0] + rng_range(rng, -size, size), c[1] + rng_range(rng, -size, size),
				       c[2] + rng_range(rng, -size, size));
	}
}

/* A non-trivial affine transform: a tilt about x, a scale, a shift. */
static void tilted(float t[16])
{
	double a = 0.3, s = 0.9;
	memset(t, 0, 16 * sizeof(float));
	t[0] = (float)s;
	t[5] = (float)(s * cos(a));
	t[6] = (float)(s * sin(a));
	t[9] = (float)(-s * sin(a));
	t[10] = (float)(s * cos(a));
	t[12] = 0.07f;
	t[13] = -0.05f;
	t[14] = 0.11f;
	t[15] = 1.0f;
}

/* Adds a draw over mesh i with one colour per primitive (saturated) or the
 * draw's colour (any, from rtest_colour()). */
static void add_draw(struct tscene *s, enum scene_prim prim, int nv, bool saturated, struct rng *rng)
{
	uint32_t i = s->n++;
	uint8_t rgb[3];
	rtest_colour(i * 5 + 1, rgb);
	s->draws[i] = rtest_draw(prim, &s->mesh[i], rgb[0], rgb[1], rgb[2]);
	if (saturated) {
		uint32_t prims = s->mesh[i].count / (uint32_t)nv;
		s->prim_rgb[i] = malloc(3 * (size_t)prims + 1);
		CHECK(s->prim_rgb[i]);
		for (uint32_t p = 0; p < prims; p++)
			rtest_saturated((uint32_t)(rng_next(rng) % 7), s->prim_rgb[i] + 3 * p);
		s->draws[i].prim_rgb = s->prim_rgb[i];
	}
}

/* Triangles (tilted), segments, points of sizes 1..4 (random, and at the
 * image edges and corners), and many small triangles: more than the
 * renderer bins and draws on one thread. */
static void build_scene(struct tscene *s, const struct geometry *g, uint64_t seed, bool saturated)
{
	struct rng rng = rng_seed(seed);
	memset(s, 0, sizeof(*s));
	random_prims(&rng, g, 3, 90, &s->mesh[0]);
	add_draw(s, SCENE_TRIANGLES, 3, saturated, &rng);
	tilted(s->draws[0].transform);
	random_prims(&rng, g, 2, 90, &s->mesh[1]);
	add_draw(s, SCENE_LINES, 2, saturated, &rng);
	for (int size = 1; size <= 4; size++) {
		struct rtest_mesh *m = &s->mesh[s->n];
		for (int i = 0; i < 40; i++) {
			double p[3];
			random_point(&rng, g, 1.1, 1.1, p);
			rtest_mesh_add(m, p[0], p[1], p[2]);
		}
		rtest_edge_points(g, m);
		add_draw(s, SCENE_POINTS, 1, saturated, &rng);
		s->draws[s->n - 1].point_size = (uint8_t)size;
	}
	struct rtest_mesh *m = &s->mesh[s->n];
	for (int i = 0; i < 400; i++) {
		double c[3];
		random_point(&rng, g, 0.95, 0.9, c);
		for (int v = 0; v < 3; v++)
			rtest_mesh_add(m, c[0] + rng_range(&rng, -0.01, 0.01), c[1] + rng_range(&rng, -0.01, 0.01),
				       c[2] + rng_range(&rng, -0.01, 0.01));
	}
	add_draw(s, SCENE_TRIANGLES, 3, saturated, &rng);
}

/* Every pixel of a volume, [k][v][u][c], 0 or 1. */
static uint8_t *dense_read(const struct volume *vol)
{
	const struct geometry *g = &vol->geom;
	uint32_t W = g->width, H = g->height, M = images_of(g);
	uint8_t *d = malloc((size_t)M * H * W * 3);
	CHECK(d);
	for (uint32_t k = 0; k < M; k++)
		for (uint32_t v = 0; v < H; v++)
			for (uint32_t u = 0; u < W; u++)
				for (int c = 0; c < 3; c++)
					d[(((size_t)k * H + v) * W + u) * 3 + c] =
						(uint8_t)volume_pixel(vol, k, u, v, c);
	return d;
}

/* "t0 t1 ...": the turns of n draws. */
static const char *turn_list(const uint32_t *turns, uint32_t n, char *buf, size_t size)
{
	size_t len = 0;
	buf[0] = 0;
	for (uint32_t i = 0; i < n && len < size; i++)
		len += (size_t)snprintf(buf + len, size - len, "%s%u", i ? " " : "", turns[i]);
	return buf;
}

static size_t at(const struct geometry *g, uint32_t k, uint32_t u, uint32_t v)
{
	return (((size_t)k * g->height + v) * g->width + u) * 3;
}

/* Row v + lift, when it is one of the image's. */
static bool lifted_row(const struct geometry *g, uint32_t v, int32_t lift, uint32_t *src)
{
	int64_t r = (int64_t)v + lift;
	*src = (uint32_t)r;
	return r >= 0 && r < g->height;
}

/* OR into want the unturned, unlifted pixels src (of one draw, or all
 * draws moved alike) shown at turn m and lift L. */
static void expect_shifted(const struct geometry *g, const uint8_t *src, uint32_t m, int32_t lift, uint8_t *want)
{
	uint32_t W = g->width;
	for (uint32_t k = 0; k < images_of(g); k++) {
		bool mirror;
		uint32_t j = source_image(g, k, m, &mirror), sv;
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; lifted_row(g, v, lift, &sv) && u < W; u++)
				for (int c = 0; c < 3; c++)
					want[at(g, k, u, v) + c] |= src[at(g, j, mirror ? W - 1 - u : u, sv) + c];
	}
}

/* Renders s's draws with turns[i] and lifts[i] (NULL: none) on draw i (2
 * threads). */
static struct volume *render_moved(const struct geometry *g, const struct tscene *s, const uint32_t *turns,
				   const int32_t *lifts)
{
	struct scene_draw d[MAX_DRAWS];
	for (uint32_t i = 0; i < s->n; i++) {
		d[i] = s->draws[i];
		d[i].turn = (uint16_t)turns[i];
		d[i].lift = lifts ? (int16_t)lifts[i] : 0;
	}
	return rtest_render(g, d, s->n, 2);
}

static struct volume *render_turned(const struct geometry *g, const struct tscene *s, const uint32_t *turns)
{
	return render_moved(g, s, turns, NULL);
}

/* got equals want everywhere; reports the first difference. */
static void check_dense(const struct geometry *g, const uint8_t *got, const uint8_t *want, const char *what)
{
	size_t n = at(g, images_of(g), 0, 0), lit = 0;
	for (size_t i = 0; i < n; i++) {
		lit += want[i];
		if (got[i] != want[i]) {
			size_t p = i / 3;
			CHECK_MSG(false, "%s: image %zu column %zu row %zu channel %zu: %d, want %d", what,
				  p / ((size_t)g->width * g->height), p % g->width, p / g->width % g->height, i % 3,
				  got[i], want[i]);
		}
	}
	CHECK_MSG(lit > 1000, "%s: only %zu voxels lit", what, lit);
}

/* 1b. Saturated colours, every draw lifted alike (and turned): the unmoved
 * volume src with its rows shifted, bit for bit. want: scratch. */
static void check_lift_shift(const char *name, const struct geometry *g, const struct tscene *s, const uint8_t *src,
			     uint8_t *want)
{
	int32_t H = (int32_t)g->height;
	const int32_t lifts[] = { 1, -1, 5, -31, 32, 33, H / 2, -(H / 2 + 9), H };
	for (size_t t = 0; t < sizeof(lifts) / sizeof(lifts[0]); t++) {
		uint32_t m = t % 3 == 2 ? 7 : 0, turns[MAX_DRAWS];
		int32_t all[MAX_DRAWS];
		for (uint32_t i = 0; i < MAX_DRAWS; i++) {
			turns[i] = m;
			all[i] = lifts[t];
		}
		struct volume *vol = render_moved(g, s, turns, all);
		uint8_t *got = dense_read(vol);
		memset(want, 0, at(g, images_of(g), 0, 0));
		expect_shifted(g, src, m, lifts[t], want);
		char what[64];
		snprintf(what, sizeof(what), "%s lift %d turn %u", name, lifts[t], m);
		if (lifts[t] == H) { /* everything lifted out of the image */
			CHECK_MSG(memcmp(got, want, at(g, images_of(g), 0, 0)) == 0, "%s: lit", what);
			CHECK_MSG(vol->images[0].tile_count == 0, "%s: tiles", what);
		} else {
			check_dense(g, got, want, what);
		}
		CHECK_MSG(rtest_padding_clear(vol), "%s: padding", what);
		printf("%s: saturated, every draw lifted %d rows and turned %u: the unmoved volume shifted, bit for "
		       "bit\n",
		       name, lifts[t], m);
		free(got);
		volume_destroy(vol);
	}
}

/* 1. Saturated colours: shifted and mirrored, bit for bit. */
static void check_shift(const char *name, const struct geometry *g)
{
	uint32_t N = g->images_per_rev, M = images_of(g);
	struct tscene s;
	build_scene(&s, g, 0x7e57 + N, true);
	uint32_t zero[MAX_DRAWS] = { 0 };
	struct volume *flat = render_turned(g, &s, zero);
	uint8_t *src = dense_read(flat);
	size_t bytes = at(g, M, 0, 0);
	uint8_t *want = malloc(bytes);
	CHECK(want);
	const uint32_t turns[] = { 1, 2, M - 1, M, M + 3, N / 2 + 1, N - 1, N + 5 /* counts mod N */ };
	for (size_t t = 0; t < sizeof(turns) / sizeof(turns[0]); t++) {
		uint32_t m = turns[t], all[MAX_DRAWS];
		for (uint32_t i = 0; i < MAX_DRAWS; i++)
			all[i] = m;
		struct volume *vol = render_turned(g, &s, all);
		uint8_t *got = dense_read(vol);
		memset(want, 0, bytes);
		expect_shifted(g, src, m % N, 0, want);
		char what[64];
		snprintf(what, sizeof(what), "%s turn %u", name, m);
		check_dense(g, got, want, what);
		CHECK_MSG(rtest_padding_clear(vol), "%s: padding", what);
		printf("%s: saturated, every draw turned %u: the unturned volume shifted%s, bit for bit\n", name, m,
		       g->mirrored ? " and mirrored" : "");
		free(got);
		volume_destroy(vol);
	}

	check_lift_shift(name, g, &s, src, want);
	/* A turn of its own on each draw (and from round 3 a lift): the union
	 * of each draw's own unmoved render, shifted. */
	struct rng rng = rng_seed(99 + N);
	for (int round = 0; round < 5; round++) {
		uint32_t mixed[MAX_DRAWS];
		int32_t lifts[MAX_DRAWS] = { 0 };
		memset(want, 0, bytes);
		for (uint32_t i = 0; i < s.n; i++) {
			mixed[i] = round == 0 && i % 2 == 0 ? 0 : (uint32_t)(rng_next(&rng) % N);
			if (round >= 3)
				lifts[i] = (int32_t)(rng_next(&rng) % (2 * g->height + 1)) - (int32_t)g->height;
			struct volume *one = rtest_render(g, &s.draws[i], 1, 1);
			uint8_t *d = dense_read(one);
			expect_shifted(g, d, mixed[i], lifts[i], want);
			free(d);
			volume_destroy(one);
		}
		struct volume *vol = render_moved(g, &s, mixed, lifts);
		uint8_t *got = dense_read(vol);
		char what[64];
		snprintf(what, sizeof(what), "%s mixed turns %d", name, round);
		check_dense(g, got, want, what);
		char list[96];
		printf("%s: saturated, a turn per draw (%s)%s: each draw's unmoved volume shifted, bit for bit\n", name,
		       turn_list(mixed, s.n, list, sizeof(list)), round >= 3 ? " and a lift per draw" : "");
		free(got);
		volume_destroy(vol);
	}
	free(want);
	free(src);
	volume_destroy(flat);
	tscene_free(&s);
}

/* 2. Any colours: the halftone at image k's phase of the MAX of the colours
 * of the draws covering the source pixel. */
static void check_halftone(const char *name, const struct geometry *g)
{
	uint32_t N = g->images_per_rev, M = images_of(g), W = g->width;
	struct tscene s;
	build_scene(&s, g, 0xc01 + N, false);
	uint8_t *cover[MAX_DRAWS];
	for (uint32_t i = 0; i < s.n; i++) {
		struct scene_draw white = s.draws[i];
		memset(white.rgb, 255, 3);
		struct volume *vol = rtest_render(g, &white, 1, 1);
		cover[i] = dense_read(vol);
		volume_destroy(vol);
	}
	struct rng rng = rng_seed(7 + N);
	for (int round = 0; round < 6; round++) {
		uint32_t turns[MAX_DRAWS];
		int32_t lifts[MAX_DRAWS] = { 0 };
		for (uint32_t i = 0; i < s.n; i++) {
			turns[i] = round == 0 ? 0 : round == 1 ? M + 3 : (uint32_t)(rng_next(&rng) % N);
			if (round >= 4) /* rows within the halftone's period and beyond it */
				lifts[i] = (int32_t)(rng_next(&rng) % 81) - 40;
		}
		struct volume *vol = render_moved(g, &s, turns, lifts);
		uint8_t *got = dense_read(vol);
		uint64_t lit = 0;
		for (uint32_t k = 0; k < M; k++) {
			for (uint32_t v = 0; v < g->height; v++) {
				for (uint32_t u = 0; u < W; u++) {
					uint8_t value[3] = { 0, 0, 0 };
					for (uint32_t i = 0; i < s.n; i++) {
						bool mirror;
						uint32_t j = source_image(g, k, turns[i], &mirror), sv;
						if (!lifted_row(g, v, lifts[i], &sv) ||
						    !cover[i][at(g, j, mirror ? W - 1 - u : u, sv)])
							continue;
						for (int c = 0; c < 3; c++)
							if (value[c] < s.draws[i].rgb[c])
								value[c] = s.draws[i].rgb[c];
					}
					uint8_t thr = halftone_threshold(k, u, v);
					for (int c = 0; c < 3; c++) {
						int want = value[c] > thr;
						lit += (uint64_t)want;
						CHECK_MSG(got[at(g, k, u, v) + c] == want,
							  "%s round %d: image %u column %u row %u channel %d: %d, want "
							  "%d "
							  "(value %u, threshold %u)",
							  name, round, k, u, v, c, got[at(g, k, u, v) + c], want,
							  value[c], thr);
					}
				}
			}
		}
		CHECK_MSG(lit > 1000, "%s round %d: only %llu lit", name, round, (unsigned long long)lit);
		char list[96];
		printf("%s: any colours, turns %s%s: image k is the halftone at k's phase of the covering draws' "
		       "colours (%llu voxels lit)\n",
		       name, turn_list(turns, s.n, list, sizeof(list)), round >= 4 ? ", lifts -40..40" : "",
		       (unsigned long long)lit);
		free(got);
		volume_destroy(vol);
	}
	for (uint32_t i = 0; i < s.n; i++)
		free(cover[i]);
	tscene_free(&s);
}

/* 3. Reuse and threads. */
static void check_reuse(const char *name, const struct geometry *g)
{
	struct tscene s;
	build_scene(&s, g, 0x5eed, true);
	uint32_t zero[MAX_DRAWS] = { 0 }, turns[MAX_DRAWS] = { 3, 0, 5, 1, 0, 7, 2, 9 };
	int32_t lifts[MAX_DRAWS] = { 0, 4, -9, 4, 0, 40, -1, 4 };
	struct volume *flat = render_turned(g, &s, zero), *turned = render_moved(g, &s, turns, lifts);
	struct scene_draw d[MAX_DRAWS];
	memcpy(d, s.draws, sizeof(d));
	struct scene sc = { .draw_count = s.n, .draws = d };
	struct volume *vol = volume_create(g);
	CHECK(vol);
	for (unsigned threads = 1; threads <= 3; threads++) {
		struct renderer *r = render_cpu_create(g, threads);
		CHECK(r);
		for (uint32_t i = 0; i < s.n; i++) {
			d[i].turn = (uint16_t)turns[i];
			d[i].lift = (int16_t)lifts[i];
		}
		CHECK(render_volume(r, &sc, vol) == 0);
		CHECK_MSG(rtest_same(vol, turned), "%s: turned, %u threads", name, threads);
		for (uint32_t i = 0; i < s.n; i++) {
			d[i].turn = 0;
			d[i].lift = 0;
		}
		CHECK(render_volume(r, &sc, vol) == 0);
		CHECK_MSG(rtest_same(vol, flat), "%s: unturned after turned, %u threads", name, threads);
		render_destroy(r);
	}
	printf("%s: 1, 2 and 3 threads give the same turned and lifted volume; a renderer that drew them "
	       "draws an unmoved scene as a fresh one\n",
	       name);
	volume_destroy(vol);
	volume_destroy(flat);
	volume_destroy(turned);
	tscene_free(&s);
}

/* out = R_y(a) * t (column-major affine), azimuths increasing. */
static void turn_transform(const float t[16], double a, float out[16])
{
	double c = cos(a), s = sin(a);
	for (int col = 0; col < 4; col++) {
		double x = t[4 * col], y = t[4 * col + 1], z = t[4 * col + 2];
		out[4 * col] = (float)(c * x - s * z);
		out[4 * col + 1] = (float)y;
		out[4 * col + 2] = (float)(s * x + c * z);
		out[4 * col + 3] = t[4 * col + 3];
	}
}

static void check_within_one(const char *what, const struct volume *ref, const struct volume *test)
{
	struct coverage c;
	CHECK(coverage_compare(ref, test, &c) == 0);
	uint64_t lit = c.ref_lit[0] + c.ref_lit[1] + c.ref_lit[2];
	uint64_t covered = c.ref_covered[0] + c.ref_covered[1] + c.ref_covered[2];
	uint64_t stray = c.test_stray[0] + c.test_stray[1] + c.test_stray[2];
	CHECK_MSG(lit > 1000, "%s: only %llu lit", what, (unsigned long long)lit);
	CHECK_MSG(covered == lit, "%s: coverage %llu of %llu", what, (unsigned long long)covered,
		  (unsigned long long)lit);
	CHECK_MSG(stray == 0, "%s: %llu stray voxels", what, (unsigned long long)stray);
}

/* 4. A turn is the rotation about the axis, to within one voxel. Except
 * for a point exactly on the axis: it lies in image 0 however it is
 * rotated (phi = atan2(0, 0) = 0, docs/design.md section 3), while a turn moves
 * it to image m with its draw (both within a voxel of the axis in space,
 * not in image index), so the scene here has none. */
static void check_geometry(const char *name, const struct geometry *g)
{
	uint32_t N = g->images_per_rev, M = images_of(g);
	struct tscene s;
	build_scene(&s, g, 0x9e0 + N, true);
	for (uint32_t i = 0; i < s.n; i++) {
		struct rtest_mesh *m = &s.mesh[i];
		uint32_t kept = 0;
		for (uint32_t p = 0; s.draws[i].prim == SCENE_POINTS && p < m->count; p++)
			if (m->xyz[3 * p] != 0 || m->xyz[3 * p + 2] != 0)
				memmove(m->xyz + 3 * kept++, m->xyz + 3 * p, 3 * sizeof(float));
		if (s.draws[i].prim == SCENE_POINTS) {
			CHECK(kept + 1 == m->count); /* rtest_edge_points()'s axis point */
			m->count = s.draws[i].count = kept;
		}
	}
	struct rng rng = rng_seed(5 + N);
	const uint32_t same[] = { 1, M - 1, M, M + 3, N - 1 };
	for (int round = 0; round < 7; round++) {
		uint32_t turns[MAX_DRAWS];
		struct scene_draw turned[MAX_DRAWS], rotated[MAX_DRAWS];
		for (uint32_t i = 0; i < s.n; i++) {
			turns[i] = round < 5 ? same[round] : (uint32_t)(rng_next(&rng) % N);
			turned[i] = rotated[i] = s.draws[i];
			turned[i].turn = (uint16_t)turns[i];
			turn_transform(s.draws[i].transform, 2 * M_PI * turns[i] / N, rotated[i].transform);
		}
		struct volume *a = rtest_render(g, turned, s.n, 2), *b = rtest_render(g, rotated, s.n, 2);
		char what[64];
		snprintf(what, sizeof(what), "%s round %d", name, round);
		check_within_one(what, b, a);
		check_within_one(what, a, b);
		char list[96];
		printf("%s: turns %s: within one voxel of the draws rotated through their transforms, both ways "
		       "(coverage 100%%, no stray)%s\n",
		       name, turn_list(turns, s.n, list, sizeof(list)), rtest_same(a, b) ? ", identical" : "");
		volume_destroy(a);
		volume_destroy(b);
	}
	tscene_free(&s);
}

/* 4b. A lift is the move up the axis by whole rows, to within one voxel,
 * for draws that stay inside the image (where the daemon lifts): the small
 * triangles (|y| <= 0.9 h + 0.01) and points of size 1 inside 0.8 h. */
static void check_lift_geometry(const char *name, const struct geometry *g)
{
	struct tscene s;
	build_scene(&s, g, 0x11f7 + g->images_per_rev, true);
	struct scene_draw d[2] = { s.draws[s.n - 1], s.draws[2] };
	struct rtest_mesh *pts = &s.mesh[2];
	uint32_t kept = 0;
	for (uint32_t p = 0; p < pts->count; p++)
		if (fabsf(pts->xyz[3 * p + 1]) <= 0.8f * (float)g->half_height)
			memmove(pts->xyz + 3 * kept++, pts->xyz + 3 * p, 3 * sizeof(float));
	pts->count = d[1].count = kept;
	double row_h = 2.0 * g->half_height / g->height;
	const int32_t lifts[] = { 1, -1, 2, -2 }; /* inside the image on both geometries */
	for (size_t t = 0; t < sizeof(lifts) / sizeof(lifts[0]); t++) {
		struct scene_draw lifted[2], moved[2];
		for (int i = 0; i < 2; i++) {
			lifted[i] = moved[i] = d[i];
			lifted[i].lift = (int16_t)lifts[t];
			moved[i].transform[13] += (float)(lifts[t] * row_h);
		}
		struct volume *a = rtest_render(g, lifted, 2, 2), *b = rtest_render(g, moved, 2, 2);
		char what[64];
		snprintf(what, sizeof(what), "%s lift %d", name, lifts[t]);
		check_within_one(what, b, a);
		check_within_one(what, a, b);
		printf("%s: lift %d: within one voxel of the draws moved up %d rows through their transforms, both "
		       "ways%s\n",
		       name, lifts[t], lifts[t], rtest_same(a, b) ? ", identical" : "");
		volume_destroy(a);
		volume_destroy(b);
	}
	tscene_free(&s);
}

/* 5. The GL renderers hand turned and lifted scenes to the CPU renderer. */
static void check_gl(const char *name, const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .no_fallback = true };
	struct renderer *r = render_gl_create(g, &o);
	if (!r) {
		printf("%s %s: no GL renderer here (%s), skipped\n", name, backend, strerror(errno));
		return;
	}
	struct tscene s;
	build_scene(&s, g, 0x61, false);
	struct scene sc = { .draw_count = s.n, .draws = s.draws };
	struct volume *vol = volume_create(g);
	CHECK(vol);
	CHECK(render_volume(r, &sc, vol) == 0);
	CHECK_MSG(r->stats.engine == RENDER_ENGINE_GL, "%s %s: unturned not on GL", name, backend);
	s.draws[3].turn = 1;
	struct volume *cpu = rtest_render(g, s.draws, s.n, 2);
	CHECK(render_volume(r, &sc, vol) == 0);
	CHECK_MSG(r->stats.engine == RENDER_ENGINE_CPU, "%s %s: turned scene not on the CPU", name, backend);
	CHECK_MSG(rtest_same(vol, cpu), "%s %s: not the CPU renderer's volume", name, backend);
	s.draws[3].turn = 0;
	s.draws[1].lift = -6;
	volume_destroy(cpu);
	cpu = rtest_render(g, s.draws, s.n, 2);
	CHECK(render_volume(r, &sc, vol) == 0);
	CHECK_MSG(r->stats.engine == RENDER_ENGINE_CPU, "%s %s: lifted scene not on the CPU", name, backend);
	CHECK_MSG(rtest_same(vol, cpu), "%s %s: lifted, not the CPU renderer's volume", name, backend);
	s.draws[1].lift = 0;
	CHECK(render_volume(r, &sc, vol) == 0);
	CHECK_MSG(r->stats.engine == RENDER_ENGINE_GL, "%s %s: not back on GL", name, backend);
	printf("%s %s: a scene with a turned or a lifted draw renders on the CPU fallback, the CPU renderer's "
	       "volume; the next without one on GL\n",
	       name, backend);
	volume_destroy(cpu);
	volume_destroy(vol);
	render_destroy(r);
	tscene_free(&s);
}

int main(void)
{
	setvbuf(stdout, NULL, _IOLBF, 0);
	struct geometry small = rtest_small(), odd = rtest_odd();
	const struct {
		const char *name;
		const struct geometry *g;
	} geoms[] = { { "small", &small }, { "odd", &odd } };
	for (int i = 0; i < 2; i++) {
		check_shift(geoms[i].name, geoms[i].g);
		check_halftone(geoms[i].name, geoms[i].g);
		check_reuse(geoms[i].name, geoms[i].g);
		check_geometry(geoms[i].name, geoms[i].g);
		check_lift_geometry(geoms[i].name, geoms[i].g);
		check_gl(geoms[i].name, geoms[i].g, "egl");
		check_gl(geoms[i].name, geoms[i].g, "osmesa");
	}
	return check_done();
}
