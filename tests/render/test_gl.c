/* The GL renderers (EGL, and OSMesa where the build has it) against the CPU
 * reference. They are not bit-identical to it (docs/design.md section 5: a
 * jittered perspective slab, shader clipping with a bias at the axis), but
 * they must light what it lights within one voxel (coverage >= 99.5%) and
 * little else (stray <= 5%), with clear padding, at the small profile and
 * at odd sizes, unmirrored, h != 1 (rtest_odd). Also: the sphere centred on
 * the axis (edge-on to every slice) lights its whole section in every
 * image; a renderer reused
 * for another scene gives what a fresh one gives (its tile atlas is left
 * clean); and the injected faults (SPINDLE_GL_FAULT) fail creation or hand
 * over to the CPU renderer, whose output is then exactly the reference's.
 * argv[1]: tests/data (the bunny). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "coverage.h"
#include "rng.h"
#include "rtest.h"
#include "scenes.h"
#include "shapes.h"

#define MIN_COVERAGE 0.995
#define MAX_STRAY 0.05
#define MAX_DRAWS 2

static const char *data_dir;

/* A scene of up to MAX_DRAWS draws over meshes it owns, or a bench scene. */
struct tscene {
	const char *name;
	struct scene scene;
	struct scene_draw draws[MAX_DRAWS];
	struct rtest_mesh mesh[MAX_DRAWS];
	struct bench_scene bench;
	bool centred; /* on the axis: every image lights its whole section */
};

static void tscene_free(struct tscene *s)
{
	for (int i = 0; i < MAX_DRAWS; i++)
		rtest_mesh_free(&s->mesh[i]);
	bench_scene_free(&s->bench);
	memset(s, 0, sizeof(*s));
}

/* Adds mesh i of s as a draw of prim in one colour (saturated colours keep
 * the comparison about geometry, except where a scene says otherwise). */
static void tscene_draw(struct tscene *s, enum scene_prim prim, uint8_t r, uint8_t g, uint8_t b)
{
	uint32_t i = s->scene.draw_count++;
	s->draws[i] = rtest_draw(prim, &s->mesh[i], r, g, b);
	s->scene.draws = s->draws;
}

/* A point uniform in the cylinder r <= rmax, |y| <= 0.9 h. */
static void random_point(struct rng *rng, const struct geometry *g, double rmax, double p[3])
{
	double rad = rmax * sqrt(rng_unit(rng)), a = rng_range(rng, 0, 2 * M_PI);
	p[0] = rad * cos(a);
	p[1] = rng_range(rng, -0.9, 0.9) * g->half_height;
	p[2] = rad * sin(a);
}

/* p + size * (a random direction), pulled back inside r <= 0.95, |y| <= 0.95 h
 * (the renderers clamp what lies outside to the image edges; that is not
 * what this test compares). */
static void random_near(struct rng *rng, const struct geometry *g, const double p[3], double size, struct rtest_mesh *m)
{
	double z = rng_range(rng, -1, 1), a = rng_range(rng, 0, 2 * M_PI), c = sqrt(1 - z * z);
	double q[3] = { p[0] + size * c * cos(a), p[1] + size * z, p[2] + size * c * sin(a) };
	double rad = hypot(q[0], q[2]), ymax = 0.95 * g->half_height;
	if (rad > 0.95) {
		q[0] *= 0.95 / rad;
		q[2] *= 0.95 / rad;
	}
	q[1] = q[1] > ymax ? ymax : q[1] < -ymax ? -ymax : q[1];
	rtest_mesh_add(m, q[0], q[1], q[2]);
}

enum scene_id {
	SC_SPHERE_AXIS,
	SC_SPHERE_OFF,
	SC_DISK,
	SC_WALL,
	SC_AXIS_LINE,
	SC_SEGMENTS,
	SC_TRIANGLES,
	SC_POINTS,
	SC_BUNNY,
	SC_COUNT
};

/* Builds scene id for g. */
static void build_scene(enum scene_id id, const struct geometry *g, struct tscene *s)
{
	memset(s, 0, sizeof(*s));
	double h = g->half_height;
	struct rng rng = rng_seed(0x676c74657374u + id);
	switch (id) {
	case SC_SPHERE_AXIS:
		s->name = "sphere-axis";
		s->centred = true;
		rtest_sphere(&s->mesh[0], 0.6 * (h < 1 ? h : 1), 32, 16);
		tscene_draw(s, SCENE_TRIANGLES, 255, 255, 255);
		break;
	case SC_SPHERE_OFF: {
		/* Moved by the draw's transform, which the renderers apply. */
		s->name = "sphere-off";
		double t[3] = { 0.45, 0.25 * h, -0.3 };
		rtest_sphere(&s->mesh[0], 0.3, 24, 12);
		tscene_draw(s, SCENE_TRIANGLES, 255, 0, 0);
		mat4_pose(s->draws[0].transform, t, 0.4, 0.7, 1.0);
		break;
	}
	case SC_DISK:
		/* Half-intensity green: the GPU's halftone against the CPU's. */
		s->name = "disk";
		rtest_disk(&s->mesh[0], 0.85, rtest_row_mid(g, g->height / 3), 48);
		tscene_draw(s, SCENE_TRIANGLES, 0, 128, 255);
		break;
	case SC_WALL:
		/* The plane z = 0 through the axis: edge-on to images 0 and N/2. */
		s->name = "wall";
		rtest_wall(&s->mesh[0], 0.7, 0.6 * h);
		tscene_draw(s, SCENE_TRIANGLES, 0, 0, 255);
		break;
	case SC_AXIS_LINE:
		s->name = "axis-line";
		rtest_mesh_add(&s->mesh[0], 0, -0.9 * h, 0);
		rtest_mesh_add(&s->mesh[0], 0, 0.9 * h, 0);
		tscene_draw(s, SCENE_LINES, 255, 255, 0);
		break;
	case SC_SEGMENTS:
		/* 200 segments of every length; every fourth goes from a point
		 * to near its mirror image through the axis, so it crosses the
		 * dead zone. */
		s->name = "segments";
		for (int i = 0; i < 200; i++) {
			double p[3];
			random_point(&rng, g, 0.95, p);
			rtest_mesh_add(&s->mesh[0], p[0], p[1], p[2]);
			if (i % 4 == 0) {
				double q[3] = { -p[0], -p[1], -p[2] }, e = 0.01;
				random_near(&rng, g, q, e, &s->mesh[0]);
			} else {
				random_near(&rng, g, p, exp(rng_range(&rng, log(0.005), log(1.2))), &s->mesh[0]);
			}
		}
		tscene_draw(s, SCENE_LINES, 0, 255, 255);
		break;
	case SC_TRIANGLES:
		/* 150 triangles from a few thousandths of the radius (well
		 * below a voxel) to larger than the radius; every fifth is
		 * centred on the axis. */
		s->name = "triangles";
		for (int i = 0; i < 150; i++) {
			double p[3], size = exp(rng_range(&rng, log(0.002), log(1.0)));
			random_point(&rng, g, 0.9, p);
			if (i % 5 == 0)
				p[0] = p[2] = 0;
			for (int v = 0; v < 3; v++)
				random_near(&rng, g, p, size, &s->mesh[0]);
		}
		tscene_draw(s, SCENE_TRIANGLES, 255, 0, 255);
		break;
	case SC_POINTS:
		/* Sparse, so that a misplaced point is not covered by others. */
		s->name = "points";
		for (int d = 0; d < 2; d++) {
			for (int i = 0; i < 1500; i++) {
				double p[3];
				random_point(&rng, g, 0.95, p);
				rtest_mesh_add(&s->mesh[d], p[0], p[1], p[2]);
			}
		}
		tscene_draw(s, SCENE_POINTS, 255, 0, 0);
		tscene_draw(s, SCENE_POINTS, 0, 255, 0);
		break;
	case SC_BUNNY: {
		/* The benchmark's bunny scene (bench/scenes.c), fitted to 0.95. */
		s->name = "bunny";
		char path[4096], err[256];
		snprintf(path, sizeof(path), "%s/bunny.ply", data_dir);
		struct bench_files files = { .bunny = path };
		int e = bench_scene_build("S3-bunny", g, &files, &s->bench, err, sizeof(err));
		CHECK_MSG(e == 0, "%s", err);
		s->scene = s->bench.scene;
		break;
	}
	case SC_COUNT:
		break;
	}
}

static struct volume *render_with(struct renderer *r, const struct scene *s)
{
	struct volume *vol = volume_create(&r->geom);
	CHECK(vol);
	int e = render_volume(r, s, vol);
	CHECK_MSG(e == 0, "%s: render failed: %s", r->impl->name, strerror(-e));
	return vol;
}

/* Agreement failures so far. Every case is rendered and its numbers printed
 * before the verdict (at the end of main), so that one run shows them all. */
static int disagreements;

__attribute__((format(printf, 2, 3))) static void disagree(const char *what, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	printf("  %-32s DISAGREES: ", what);
	vprintf(fmt, ap);
	printf("\n");
	va_end(ap);
	disagreements++;
}

/* Compares test with the reference ref: coverage >= 99.5% and stray <= 5%
 * (printed for every case), and padding bits clear. */
static void check_agreement(const char *what, const struct volume *ref, const struct volume *test)
{
	struct coverage c;
	CHECK(coverage_compare(ref, test, &c) == 0);
	double cov = coverage_score(&c), stray = coverage_stray(&c);
	uint64_t ref_lit = c.ref_lit[0] + c.ref_lit[1] + c.ref_lit[2];
	uint64_t test_lit = c.test_lit[0] + c.test_lit[1] + c.test_lit[2];
	printf("  %-32s coverage %7.3f%%  stray %6.3f%%  (lit: cpu %llu, gl %llu)\n", what, 100 * cov, 100 * stray,
	       (unsigned long long)ref_lit, (unsigned long long)test_lit);
	CHECK_MSG(ref_lit > 0, "%s: the reference lights nothing", what);
	if (cov < MIN_COVERAGE)
		disagree(what, "coverage %.3f%% < 99.5%%", 100 * cov);
	if (stray > MAX_STRAY)
		disagree(what, "stray %.3f%% > 5%%", 100 * stray);
	CHECK_MSG(rtest_padding_clear(test), "%s: padding bits set", what);
}

/* Whether channel c of vol is lit at (u +- 1, v +- 1) in image k itself. */
static bool lit_near_in_image(const struct volume *vol, uint32_t k, uint32_t u, uint32_t v, int c)
{
	for (uint32_t y = v ? v - 1 : 0; y <= v + 1 && y < vol->geom.height; y++)
		for (uint32_t x = u ? u - 1 : 0; x <= u + 1 && x < vol->geom.width; x++)
			if (rtest_lit(vol, k, x, y, c))
				return true;
	return false;
}

/* The sphere on the axis crosses every slice plane at right angles (edge-on
 * to every image's projection): every image must light its section, the
 * whole of it. The volume comparison cannot see a hole here, since it
 * forgives a voxel lit in the next image instead; so per image: each voxel
 * the reference lights has a lit voxel within one column and row in the
 * same image. */
static void check_every_image(const char *what, const struct volume *ref, const struct volume *test)
{
	uint32_t bad_images = 0, worst = 0;
	uint64_t worst_missed = 0, worst_lit = 0;
	for (uint32_t k = 0; k < test->image_count; k++) {
		uint64_t missed = 0, lit = rtest_count_image(test, k, 0);
		for (uint32_t v = 0; v < ref->geom.height; v++)
			for (uint32_t u = 0; u < ref->geom.width; u++)
				missed += rtest_lit(ref, k, u, v, 0) && !lit_near_in_image(test, k, u, v, 0);
		CHECK_MSG(lit > 0, "%s: image %u is dark", what, k);
		bad_images += missed > 0;
		if (missed > worst_missed) {
			worst = k;
			worst_missed = missed;
			worst_lit = rtest_count_image(ref, k, 0);
		}
	}
	if (bad_images)
		disagree(what,
			 "%u images miss part of their section; worst, image %u: %llu of its %llu "
			 "reference voxels have no lit voxel within one",
			 bad_images, worst, (unsigned long long)worst_missed, (unsigned long long)worst_lit);
}

static struct renderer *gl_create(const struct geometry *g, const char *backend, bool naive)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .naive = naive, .no_fallback = true };
	struct renderer *r = render_gl_create(g, &o);
	CHECK_MSG(r, "%s%s: render_gl_create failed: %s", backend, naive ? " naive" : "", strerror(errno));
	return r;
}

/* Every scene with one renderer of each kind (the GL renderer reused from
 * scene to scene, as the daemon does); the naive variant on two scenes. */
static void check_scenes(const char *gname, const struct geometry *g, const char *backend)
{
	struct renderer *cpu = render_cpu_create(g, 2);
	struct renderer *gl = gl_create(g, backend, false);
	struct renderer *naive = gl_create(g, backend, true);
	CHECK(cpu);
	for (int id = 0; id < SC_COUNT; id++) {
		struct tscene s;
		char what[96];
		build_scene(id, g, &s);
		struct volume *ref = render_with(cpu, &s.scene);
		struct volume *test = render_with(gl, &s.scene);
		snprintf(what, sizeof(what), "%s %s %s", gname, backend, s.name);
		check_agreement(what, ref, test);
		if (s.centred)
			check_every_image(what, ref, test);
		volume_destroy(test);
		if (id == SC_SPHERE_AXIS || id == SC_TRIANGLES) {
			test = render_with(naive, &s.scene);
			snprintf(what, sizeof(what), "%s %s-naive %s", gname, backend, s.name);
			check_agreement(what, ref, test);
			if (s.centred)
				check_every_image(what, ref, test);
			volume_destroy(test);
		}
		volume_destroy(ref);
		tscene_free(&s);
	}
	render_destroy(naive);
	render_destroy(gl);
	render_destroy(cpu);
}

/* A renderer that has drawn a full scene gives, for another scene, exactly
 * what a fresh renderer gives (the atlas and tile marks are left clean
 * between volumes, also after a partial last batch: rtest_odd has 50
 * images), and an empty scene after a full one is an empty volume. */
static void check_reuse(const struct geometry *g, const char *backend)
{
	struct tscene full, other;
	build_scene(SC_TRIANGLES, g, &full);
	build_scene(SC_SPHERE_OFF, g, &other);
	struct renderer *used = gl_create(g, backend, false), *fresh = gl_create(g, backend, false);
	struct volume *a = render_with(used, &full.scene);
	CHECK(volume_tile_count(a) > 0);
	struct volume *b = render_with(used, &other.scene), *c = render_with(fresh, &other.scene);
	CHECK_MSG(rtest_same(b, c), "%s: a reused renderer differs from a fresh one", backend);
	volume_destroy(a);
	volume_destroy(b);
	volume_destroy(c);

	struct scene empty = { 0 };
	a = render_with(used, &full.scene);
	b = render_with(used, &empty);
	CHECK_MSG(volume_tile_count(b) == 0, "%s: the empty scene after a full one lights %llu tiles", backend,
		  (unsigned long long)volume_tile_count(b));
	volume_destroy(a);
	volume_destroy(b);
	render_destroy(used);
	render_destroy(fresh);
	tscene_free(&full);
	tscene_free(&other);
}

/* SPINDLE_GL_FAULT is read by render_gl_create(); set it around each
 * creation only. */
static struct renderer *faulty_create(const struct geometry *g, const char *backend, const char *fault,
				      bool no_fallback)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .no_fallback = no_fallback };
	CHECK(setenv("SPINDLE_GL_FAULT", fault, 1) == 0);
	errno = 0;
	struct renderer *r = render_gl_create(g, &o);
	int e = errno;
	CHECK(unsetenv("SPINDLE_GL_FAULT") == 0);
	errno = e;
	return r;
}

/* No display: no renderer, ENODEV. Shaders that do not compile: no
 * renderer. A context lost after the first volume: the second volume is
 * the CPU renderer's, bit for bit (and so are the later ones), or, with
 * no_fallback, an error. (The renderer logs these failures.) */
static void check_faults(const struct geometry *g, const char *backend)
{
	printf("  %s: faults injected (error lines expected)\n", backend);
	fflush(stdout);
	struct renderer *r = faulty_create(g, backend, "display", false);
	CHECK_MSG(!r && errno == ENODEV, "%s display: %p, errno %d", backend, (void *)r, errno);
	r = faulty_create(g, backend, "shader", false);
	CHECK_MSG(!r, "%s shader: a renderer was created", backend);

	struct tscene first, second;
	build_scene(SC_SPHERE_OFF, g, &first);
	build_scene(SC_WALL, g, &second);
	struct volume *ref = rtest_render(g, second.scene.draws, second.scene.draw_count, 2);
	r = faulty_create(g, backend, "lost", false);
	CHECK_MSG(r, "%s lost: no renderer: %s", backend, strerror(errno));
	struct volume *vol = render_with(r, &first.scene);
	volume_destroy(vol);
	for (int i = 0; i < 2; i++) {
		vol = render_with(r, &second.scene);
		CHECK_MSG(rtest_same(vol, ref), "%s lost: volume %d is not the CPU renderer's", backend, i + 2);
		volume_destroy(vol);
	}
	render_destroy(r);

	r = faulty_create(g, backend, "lost", true);
	CHECK_MSG(r, "%s lost: no renderer: %s", backend, strerror(errno));
	vol = render_with(r, &first.scene);
	int e = render_volume(r, &second.scene, vol);
	CHECK_MSG(e < 0, "%s lost, no fallback: the second render returned %d", backend, e);
	volume_destroy(vol);
	render_destroy(r);
	volume_destroy(ref);
	tscene_free(&first);
	tscene_free(&second);
}

/* A scene with more primitives than the GL renderer takes (max_prims,
 * standing in for the texture's limit) renders on the CPU, bit for bit the
 * CPU renderer's; the next scene that fits renders on GL again, exactly as
 * a fresh GL renderer draws it. */
static void check_too_big(const struct geometry *g, const char *backend)
{
	struct tscene big, wall;
	build_scene(SC_TRIANGLES, g, &big);
	build_scene(SC_WALL, g, &wall);
	struct render_gl_options o = { .backend = backend, .threads = 2, .max_prims = 2 };
	struct renderer *r = render_gl_create(g, &o), *fresh = gl_create(g, backend, false);
	CHECK_MSG(r, "%s max_prims: %s", backend, strerror(errno));
	struct volume *ref = rtest_render(g, big.scene.draws, big.scene.draw_count, 2);
	struct volume *vol = render_with(r, &big.scene);
	CHECK_MSG(rtest_same(vol, ref), "%s: a scene over max_prims is not the CPU renderer's", backend);
	volume_destroy(vol);
	volume_destroy(ref);
	ref = render_with(fresh, &wall.scene);
	vol = render_with(r, &wall.scene);
	CHECK_MSG(rtest_same(vol, ref), "%s: after a scene over max_prims, one that fits is not GL's", backend);
	volume_destroy(vol);
	volume_destroy(ref);
	render_destroy(r);
	render_destroy(fresh);
	tscene_free(&big);
	tscene_free(&wall);
}

/* hardware_only ("auto"'s probe): no renderer on a software rasterizer
 * (ENODEV), or one that is not one. */
static void check_hardware_only(const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .hardware_only = true };
	errno = 0;
	struct renderer *r = render_gl_create(g, &o);
	if (!r) {
		CHECK_MSG(errno == ENODEV, "%s hardware_only: errno %d", backend, errno);
		return;
	}
	CHECK_MSG(!strstr(render_gl_describe(r), "(software)"), "%s hardware_only gave %s", backend,
		  render_gl_describe(r));
	render_destroy(r);
}

/* Whether the build has this backend: only OSMesa may be missing (ENOENT);
 * any other failure to create a renderer fails the test. */
static bool have_backend(const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2 };
	struct renderer *r = render_gl_create(g, &o);
	if (!r && errno == ENOENT && !strcmp(backend, "osmesa")) {
		printf("%s: not in this build (no OSMesa), skipped\n", backend);
		return false;
	}
	CHECK_MSG(r, "%s: render_gl_create failed: %s", backend, strerror(errno));
	render_destroy(r);
	return true;
}

int main(int argc, char **argv)
{
	CHECK_MSG(argc == 2, "usage: %s tests/data", argv[0]);
	data_dir = argv[1];
	setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the renderer's log lines */
	static const char *const backends[] = { "egl", "osmesa" };
	struct geometry small = rtest_small(), odd = rtest_odd();
	for (int i = 0; i < 2; i++) {
		const char *b = backends[i];
		if (!have_backend(&small, b))
			continue;
		printf("%s:\n", b);
		check_scenes("small", &small, b);
		check_scenes("odd", &odd, b);
		check_reuse(&small, b);
		check_reuse(&odd, b);
		check_faults(&small, b);
		check_too_big(&small, b);
		check_hardware_only(&small, b);
	}
	CHECK_MSG(disagreements == 0, "%d disagreements with the CPU reference (above)", disagreements);
	return check_done();
}
