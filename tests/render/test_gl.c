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
 *
 * The brightness models (geometry.brightness, brightness.h): every scene
 * again in even and uniform against the CPU renderer in the same model,
 * within one voxel where that applies (below); and the light per unit area
 * of a horizontal disk, walls through the axis and tubes about it, in
 * radial bins, within 10% of the CPU renderer's in every bin.
 * argv[1]: tests/data (the bunny). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "check.h"
#include "coverage.h"
#include "rng.h"
#include "rtest.h"
#include "scenes.h"
#include "shapes.h"

#define MIN_COVERAGE 0.995
#define MAX_STRAY 0.05
/* Uniform thins every column, to about a third of the voxels at small and
 * a sixth at odd; GL lights 70-75% as many voxels as the CPU renderer's
 * conservative cover, and a voxel the CPU adds beside GL's lies in another
 * column, whose pattern over images is another: under thinning that
 * strong its neighbourhood in GL is sometimes dark (98.5-99.5% covered on
 * the meshes). The light itself agrees: check_light(). */
#define MIN_COVERAGE_UNIFORM 0.98
/* Light per unit area per radial bin, GL against the CPU renderer. */
#define MAX_LIGHT_ERROR 0.10
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

/* Compares test with the reference ref: coverage >= min_cov (99.5%, in
 * uniform 98%) and stray <= 5% (printed for every case), and padding bits
 * clear. */
static void check_agreement(const char *what, const struct volume *ref, const struct volume *test, double min_cov)
{
	struct coverage c;
	CHECK(coverage_compare(ref, test, &c) == 0);
	double cov = coverage_score(&c), stray = coverage_stray(&c);
	uint64_t ref_lit = c.ref_lit[0] + c.ref_lit[1] + c.ref_lit[2];
	uint64_t test_lit = c.test_lit[0] + c.test_lit[1] + c.test_lit[2];
	printf("  %-32s coverage %7.3f%%  stray %6.3f%%  (lit: cpu %llu, gl %llu)\n", what, 100 * cov, 100 * stray,
	       (unsigned long long)ref_lit, (unsigned long long)test_lit);
	CHECK_MSG(ref_lit > 0, "%s: the reference lights nothing", what);
	if (cov < min_cov)
		disagree(what, "coverage %.3f%% < %.1f%%", 100 * cov, 100 * min_cov);
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
 * same image. Only outside the columns a brightness model thins (skip_lo
 * .. skip_hi; none when skip_lo > skip_hi): inside them an image lights its
 * section only in some columns by design (the Bresenham pattern over
 * images, brightness.h). */
static void check_every_image(const char *what, const struct volume *ref, const struct volume *test, uint32_t skip_lo,
			      uint32_t skip_hi)
{
	uint32_t bad_images = 0, worst = 0;
	uint64_t worst_missed = 0, worst_lit = 0;
	for (uint32_t k = 0; k < test->image_count; k++) {
		uint64_t missed = 0, lit = rtest_count_image(test, k, 0);
		for (uint32_t v = 0; v < ref->geom.height; v++)
			for (uint32_t u = 0; u < ref->geom.width; u++)
				missed += (u < skip_lo || u > skip_hi) && rtest_lit(ref, k, u, v, 0) &&
					  !lit_near_in_image(test, k, u, v, 0);
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
 * scene to scene, as the daemon does); the naive variant on two scenes. In
 * g's brightness model: the CPU renderer's in the same model is the
 * reference. */
static void check_scenes(const char *gname, const struct geometry *g, const char *backend)
{
	struct renderer *cpu = render_cpu_create(g, 2);
	struct renderer *gl = gl_create(g, backend, false);
	struct renderer *naive = gl_create(g, backend, true);
	CHECK(cpu);
	struct brightness_map map;
	CHECK(brightness_map_init(&map, g) == 0);
	double min_cov = g->brightness == GEOMETRY_BRIGHTNESS_UNIFORM ? MIN_COVERAGE_UNIFORM : MIN_COVERAGE;
	for (int id = 0; id < SC_COUNT; id++) {
		struct tscene s;
		char what[96];
		build_scene(id, g, &s);
		struct volume *ref = render_with(cpu, &s.scene);
		struct volume *test = render_with(gl, &s.scene);
		snprintf(what, sizeof(what), "%s %s %s", gname, backend, s.name);
		check_agreement(what, ref, test, min_cov);
		if (s.centred)
			check_every_image(what, ref, test, map.band_lo, map.band_hi);
		volume_destroy(test);
		if (id == SC_SPHERE_AXIS || id == SC_TRIANGLES) {
			test = render_with(naive, &s.scene);
			snprintf(what, sizeof(what), "%s %s-naive %s", gname, backend, s.name);
			check_agreement(what, ref, test, min_cov);
			if (s.centred)
				check_every_image(what, ref, test, map.band_lo, map.band_hi);
			volume_destroy(test);
		}
		volume_destroy(ref);
		tscene_free(&s);
	}
	brightness_map_finish(&map);
	render_destroy(naive);
	render_destroy(gl);
	render_destroy(cpu);
}

/* Light per unit area against the distance from the axis (the issue "Even
 * brightness"): lit voxels (any channel) whose column's radius |u + 0.5 -
 * W/2| px lies in a bin [0,1), [1,2), [2,4), ... px, over the shape's
 * area in that bin in px^2. The shapes, in pixels: a horizontal disk of
 * radius r, a vertical wall through the axis (|s| <= r) at azimuth az, a
 * tube of radius r about the axis; walls and tubes span rows H/8 .. 7H/8
 * - 1, their edges a twentieth of a row inside them, and every radius ends
 * mid-column: no edge on a cell boundary, where the CPU renderer's closed
 * cells light a second column or row and GL one. */
enum light_kind { LIGHT_DISK, LIGHT_WALL, LIGHT_TUBE };

struct light_shape {
	const char *name;
	enum light_kind kind;
	double r_px, az;
};

#define LIGHT_BINS 16

static unsigned light_bins(const struct geometry *g, double lo[], double hi[])
{
	unsigned n = 0;
	for (double a = 0, b = 1; a < g->width / 2.0 && n < LIGHT_BINS; a = b, b *= 2, n++) {
		lo[n] = a;
		hi[n] = b < g->width / 2.0 ? b : g->width / 2.0;
	}
	return n;
}

static double light_area(const struct light_shape *s, double rows, double lo, double hi)
{
	double top = hi < s->r_px ? hi : s->r_px;
	switch (s->kind) {
	case LIGHT_DISK:
		return top > lo ? M_PI * (top * top - lo * lo) : 0;
	case LIGHT_WALL:
		return top > lo ? 2 * (top - lo) * rows : 0; /* both sides of the axis */
	case LIGHT_TUBE:
		return s->r_px >= lo && s->r_px < hi ? 2 * M_PI * s->r_px * rows : 0;
	}
	return 0;
}

static void light_mesh(const struct geometry *g, const struct light_shape *s, uint32_t v0, uint32_t v1,
		       struct rtest_mesh *m)
{
	double px = 2.0 / g->width, row = 2.0 * g->half_height / g->height, r = s->r_px * px;
	double top = rtest_row_y0(g, v0) - 0.05 * row, bottom = rtest_row_y1(g, v1) + 0.05 * row;
	if (s->kind == LIGHT_DISK) {
		rtest_disk(m, r, rtest_row_mid(g, 3 * g->height / 8), 256);
		return;
	}
	int segs = s->kind == LIGHT_WALL ? 1 : 96;
	for (int i = 0; i < segs; i++) {
		double a0 = s->az + 2 * M_PI * i / segs, a1 = s->az + 2 * M_PI * (i + 1) / segs;
		double x0 = r * cos(a0), z0 = r * sin(a0), x1 = r * cos(a1), z1 = r * sin(a1);
		if (s->kind == LIGHT_WALL) {
			x1 = -x0;
			z1 = -z0;
		}
		rtest_mesh_add(m, x0, bottom, z0);
		rtest_mesh_add(m, x1, bottom, z1);
		rtest_mesh_add(m, x1, top, z1);
		rtest_mesh_add(m, x0, bottom, z0);
		rtest_mesh_add(m, x1, top, z1);
		rtest_mesh_add(m, x0, top, z0);
	}
}

static void light_count(const struct volume *vol, const double lo[], const double hi[], unsigned nb, uint64_t *count)
{
	const struct geometry *g = &vol->geom;
	memset(count, 0, nb * sizeof(*count));
	for (uint32_t u = 0; u < g->width; u++) {
		double r = fabs(u + 0.5 - g->width / 2.0);
		unsigned b = 0;
		while (b < nb && !(r >= lo[b] && r < hi[b]))
			b++;
		if (b == nb)
			continue;
		for (uint32_t k = 0; k < vol->image_count; k++)
			for (uint32_t v = 0; v < g->height; v++)
				count[b] += rtest_lit(vol, k, u, v, 0) || rtest_lit(vol, k, u, v, 1) ||
					    rtest_lit(vol, k, u, v, 2);
	}
}

/* In even and uniform at small, each shape in white: per bin with area,
 * GL's light per unit area (and the naive pipeline's) within 10% of the CPU
 * renderer's. Prints GL / CPU per bin. */
static void check_light(const char *backend)
{
	static const struct light_shape shapes[] = {
		{ "disk", LIGHT_DISK, 60.5, 0 },         { "wall-1.2345", LIGHT_WALL, 60.5, 1.2345 },
		{ "wall-image5", LIGHT_WALL, 60.5, -1 }, { "tube-1.5", LIGHT_TUBE, 1.5, 0 },
		{ "tube-2.5", LIGHT_TUBE, 2.5, 0 },      { "tube-4.5", LIGHT_TUBE, 4.5, 0 },
		{ "tube-8.5", LIGHT_TUBE, 8.5, 0 },      { "tube-12.5", LIGHT_TUBE, 12.5, 0 },
		{ "tube-16.5", LIGHT_TUBE, 16.5, 0 },    { "tube-30.5", LIGHT_TUBE, 30.5, 0 },
	};
	static const uint8_t models[] = { GEOMETRY_BRIGHTNESS_EVEN, GEOMETRY_BRIGHTNESS_UNIFORM };
	for (size_t m = 0; m < sizeof(models); m++) {
		struct geometry g = rtest_small();
		g.brightness = models[m];
		uint32_t v0 = g.height / 8, v1 = 7 * g.height / 8 - 1;
		double lo[LIGHT_BINS], hi[LIGHT_BINS];
		unsigned nb = light_bins(&g, lo, hi);
		struct renderer *cpu = render_cpu_create(&g, 2),
				*gl[2] = { gl_create(&g, backend, false), gl_create(&g, backend, true) };
		CHECK(cpu);
		printf("  light per px^2, small %s %s, gl / cpu per bin:\n", geometry_brightness_name(g.brightness),
		       backend);
		for (size_t i = 0; i < sizeof(shapes) / sizeof(shapes[0]); i++) {
			struct light_shape sh = shapes[i];
			if (sh.az < 0)
				sh.az = geometry_image_angle(&g, 5); /* in image 5's plane */
			struct tscene s;
			memset(&s, 0, sizeof(s));
			light_mesh(&g, &sh, v0, v1, &s.mesh[0]);
			tscene_draw(&s, SCENE_TRIANGLES, 255, 255, 255);
			struct volume *ref = render_with(cpu, &s.scene);
			uint64_t want[LIGHT_BINS], got[LIGHT_BINS];
			light_count(ref, lo, hi, nb, want);
			for (int n = 0; n < 2; n++) {
				struct volume *test = render_with(gl[n], &s.scene);
				light_count(test, lo, hi, nb, got);
				char what[96], line[512];
				snprintf(what, sizeof(what), "small %s %s%s %s", geometry_brightness_name(g.brightness),
					 backend, n ? "-naive" : "", sh.name);
				int len = 0;
				for (unsigned b = 0; b < nb; b++) {
					double area = light_area(&sh, v1 - v0 + 1, lo[b], hi[b]);
					if (area <= 0)
						continue;
					double a = got[b] / area, e = want[b] / area;
					len += snprintf(line + len, sizeof(line) - (size_t)len, " [%g,%g) %.3f/%.3f",
							lo[b], hi[b], a, e);
					CHECK_MSG(want[b] > 0, "%s: the reference lights nothing in [%g, %g) px", what,
						  lo[b], hi[b]);
					if (fabs(a - e) > MAX_LIGHT_ERROR * e)
						disagree(what, "%.3f lit voxels per px^2 in [%g, %g) px, the CPU %.3f",
							 a, lo[b], hi[b], e);
				}
				if (n == 0)
					printf("  %-32s%s\n", what, line);
				volume_destroy(test);
			}
			volume_destroy(ref);
			tscene_free(&s);
		}
		render_destroy(gl[0]);
		render_destroy(gl[1]);
		render_destroy(cpu);
	}
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

int main(int argc, char **argv)
{
	CHECK_MSG(argc == 2, "usage: %s tests/data", argv[0]);
	data_dir = argv[1];
	setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the renderer's log lines */
	static const char *const backends[] = { "egl", "osmesa" };
	struct geometry small = rtest_small(), odd = rtest_odd();
	for (int i = 0; i < 2; i++) {
		const char *b = backends[i];
		if (!rtest_have_gl(&small, b))
			continue;
		printf("%s:\n", b);
		check_scenes("small", &small, b);
		check_scenes("odd", &odd, b);
		for (uint8_t m = GEOMETRY_BRIGHTNESS_EVEN; m <= GEOMETRY_BRIGHTNESS_UNIFORM; m++) {
			struct geometry gs = small, go = odd;
			char sname[32], oname[32];
			gs.brightness = go.brightness = m;
			snprintf(sname, sizeof(sname), "small %s", geometry_brightness_name(m));
			snprintf(oname, sizeof(oname), "odd %s", geometry_brightness_name(m));
			check_scenes(sname, &gs, b);
			check_scenes(oname, &go, b);
			if (m == GEOMETRY_BRIGHTNESS_EVEN)
				check_reuse(&go, b);
		}
		check_light(b);
		check_reuse(&small, b);
		check_reuse(&odd, b);
		check_faults(&small, b);
		check_too_big(&small, b);
		check_hardware_only(&small, b);
	}
	CHECK_MSG(disagreements == 0, "%d disagreements with the CPU reference (above)", disagreements);
	return check_done();
}
