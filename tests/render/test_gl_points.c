/* Point sizes and per-primitive colours on the GL renderers (EGL, and
 * OSMesa where the build has it), against the CPU reference:
 * - points of every size (0 .. 16 and 255) at and beyond the image edges
 *   and corners (rtest_edge_points()), mirrored and not, and points with
 *   their own colours: bit for bit the CPU renderer's volume, since both
 *   draw the same binned squares (test_point_size.c checks the CPU's);
 * - segments and triangles with their own colours: exactly what GL draws
 *   for one draw per primitive in that colour, and, in saturated colours,
 *   within one voxel of the CPU renderer per channel (test_gl.c's coverage
 *   >= 99.5%, stray <= 5%).
 * The GL renderer is reused from scene to scene, as the daemon does; the
 * points are also drawn by the naive pipeline. All of it again at small in
 * the even and uniform brightness models (brightness.h): points are never
 * weighted, and the pack pass thresholds them as the CPU renderer does
 * (the Bresenham pattern in the thinned band), so they stay bit for bit
 * the CPU renderer's. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "coverage.h"
#include "rtest.h"

#define MIN_COVERAGE 0.995
#define MAX_STRAY 0.05
/* In the uniform model, as in test_gl.c: under thinning that strong a
 * voxel the CPU adds beside GL's sometimes has a dark neighbourhood. */
#define MIN_COVERAGE_UNIFORM 0.98

/* A CPU and a GL renderer of one geometry. */
struct pair {
	const char *name; /* "small egl" */
	struct renderer *cpu, *gl;
};

static struct volume *render_with(struct renderer *r, const struct scene_draw *draws, uint32_t n)
{
	struct scene s = { .draw_count = n, .draws = draws };
	struct volume *vol = volume_create(&r->geom);
	CHECK(vol);
	int e = render_volume(r, &s, vol);
	CHECK_MSG(e == 0, "%s: render failed: %s", r->impl->name, strerror(-e));
	return vol;
}

/* The draws render identically on both renderers. */
static void check_exact(const struct pair *p, const struct scene_draw *draws, uint32_t n, const char *what)
{
	struct volume *ref = render_with(p->cpu, draws, n), *test = render_with(p->gl, draws, n);
	CHECK_MSG(rtest_count(ref, 0) > 0, "%s %s: the reference lights nothing", p->name, what);
	CHECK_MSG(rtest_same(ref, test), "%s %s: GL lights %llu/%llu/%llu voxels, the CPU %llu/%llu/%llu", p->name,
		  what, (unsigned long long)rtest_count(test, 0), (unsigned long long)rtest_count(test, 1),
		  (unsigned long long)rtest_count(test, 2), (unsigned long long)rtest_count(ref, 0),
		  (unsigned long long)rtest_count(ref, 1), (unsigned long long)rtest_count(ref, 2));
	volume_destroy(ref);
	volume_destroy(test);
}

static void check_sizes(const struct pair *p, const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	rtest_edge_points(g, &m);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	for (int s = 0; s <= 17; s++) {
		char what[32];
		d.point_size = (uint8_t)(s == 17 ? 255 : s);
		snprintf(what, sizeof(what), "points of size %u", d.point_size);
		check_exact(p, &d, 1, what);
	}
	rtest_mesh_free(&m);
}

/* The edge points in their own colours, twice: at sizes 3 and 4, the
 * second draw turned by a quarter turn (so its squares land in other
 * images, some overlapping the first's: MAX). */
static void check_point_colours(const struct pair *p, const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	uint32_t n = rtest_edge_points(g, &m);
	uint8_t *rgb = malloc(3 * (size_t)n);
	CHECK(rgb);
	for (uint32_t i = 0; i < n; i++)
		rtest_colour(i, rgb + 3 * i);
	struct scene_draw d[2] = { rtest_draw(SCENE_POINTS, &m, 255, 255, 255),
				   rtest_draw(SCENE_POINTS, &m, 255, 255, 255) };
	d[0].prim_rgb = d[1].prim_rgb = rgb;
	d[0].point_size = 3;
	d[1].point_size = 4;
	/* x' = -z, z' = x: a quarter turn about the axis. */
	d[1].transform[0] = d[1].transform[10] = 0.0f;
	d[1].transform[2] = 1.0f;
	d[1].transform[8] = -1.0f;
	check_exact(p, d, 2, "points in their own colours");
	free(rgb);
	rtest_mesh_free(&m);
}

/* Compares GL with the CPU reference per channel, within one voxel. */
static void check_agreement(const struct pair *p, const struct scene_draw *draws, uint32_t n, const char *what)
{
	struct volume *ref = render_with(p->cpu, draws, n), *test = render_with(p->gl, draws, n);
	struct coverage c;
	CHECK(coverage_compare(ref, test, &c) == 0);
	double cov = coverage_score(&c), stray = coverage_stray(&c);
	double min_cov = p->cpu->geom.brightness == GEOMETRY_BRIGHTNESS_UNIFORM ? MIN_COVERAGE_UNIFORM : MIN_COVERAGE;
	printf("  %s %-28s coverage %7.3f%%  stray %6.3f%%\n", p->name, what, 100 * cov, 100 * stray);
	for (int ch = 0; ch < 3; ch++)
		CHECK_MSG(c.ref_lit[ch] > 0, "%s %s: the reference lights nothing in c%d", p->name, what, ch);
	CHECK_MSG(cov >= min_cov && stray <= MAX_STRAY, "%s %s: coverage %.3f%%, stray %.3f%%", p->name, what,
		  100 * cov, 100 * stray);
	CHECK_MSG(rtest_padding_clear(test), "%s %s: padding bits set", p->name, what);
	volume_destroy(ref);
	volume_destroy(test);
}

/* The primitives of m (nv vertices each) as two draws with prim_rgb from
 * colour(): the same as one draw per primitive on GL, and, for saturated
 * colours, within one voxel of the CPU renderer (dithered colours are not
 * compared so: a neighbouring voxel has another threshold). */
static void check_prims(const struct pair *p, enum scene_prim prim, uint32_t nv, const struct rtest_mesh *m,
			void (*colour)(uint32_t, uint8_t *), const char *what)
{
	uint32_t n = m->count / nv, half = n / 2;
	uint8_t *rgb = malloc(3 * (size_t)n);
	struct scene_draw *each = calloc(n, sizeof(*each));
	CHECK(rgb && each);
	for (uint32_t i = 0; i < n; i++) {
		colour(i, rgb + 3 * i);
		each[i] = rtest_draw(prim, m, rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
		each[i].xyz = m->xyz + (size_t)i * nv * 3;
		each[i].count = nv;
	}
	struct scene_draw two[2] = { rtest_draw(prim, m, 255, 255, 255), rtest_draw(prim, m, 255, 255, 255) };
	two[0].prim_rgb = rgb;
	two[0].count = half * nv;
	two[1].prim_rgb = rgb + 3 * half;
	two[1].xyz = m->xyz + (size_t)half * nv * 3;
	two[1].count = (n - half) * nv;
	struct volume *a = render_with(p->gl, two, 2), *b = render_with(p->gl, each, n);
	CHECK_MSG(rtest_same(a, b), "%s %s: prim_rgb differs from a draw per primitive", p->name, what);
	volume_destroy(a);
	volume_destroy(b);
	if (colour == rtest_saturated)
		check_agreement(p, two, 2, what);
	free(each);
	free(rgb);
}

/* An off-axis sphere's triangles, and its vertices paired as segments. */
static void check_prim_colours(const struct pair *p)
{
	struct rtest_mesh sphere = { 0 }, m = { 0 };
	rtest_sphere(&sphere, 0.35, 12, 6);
	for (uint32_t i = 0; i < sphere.count; i++) {
		const float *v = sphere.xyz + 3 * i;
		rtest_mesh_add(&m, v[0] + 0.4, v[1], v[2] - 0.2);
	}
	check_prims(p, SCENE_TRIANGLES, 3, &m, rtest_saturated, "triangles, saturated");
	check_prims(p, SCENE_TRIANGLES, 3, &m, rtest_colour, "triangles, any colour");
	m.count &= ~1u;
	check_prims(p, SCENE_LINES, 2, &m, rtest_saturated, "segments, saturated");
	check_prims(p, SCENE_LINES, 2, &m, rtest_colour, "segments, any colour");
	rtest_mesh_free(&sphere);
	rtest_mesh_free(&m);
}

/* The checks on one backend, and the point checks on its naive variant
 * (one image a batch, read back whole). */
static void check_backend(const char *gname, const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .no_fallback = true };
	char name[32], naive_name[40];
	snprintf(name, sizeof(name), "%s %s", gname, backend);
	snprintf(naive_name, sizeof(naive_name), "%s-naive", name);
	struct pair p = { name, render_cpu_create(g, 2), render_gl_create(g, &o) };
	CHECK_MSG(p.cpu && p.gl, "%s: no renderer: %s", name, strerror(errno));
	check_sizes(&p, g);
	check_point_colours(&p, g);
	check_prim_colours(&p);
	o.naive = true;
	struct pair naive = { naive_name, p.cpu, render_gl_create(g, &o) };
	CHECK_MSG(naive.gl, "%s: no renderer: %s", naive_name, strerror(errno));
	check_sizes(&naive, g);
	check_point_colours(&naive, g);
	render_destroy(naive.gl);
	render_destroy(p.gl);
	render_destroy(p.cpu);
}

int main(void)
{
	setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the renderer's log lines */
	static const char *const backends[] = { "egl", "osmesa" };
	struct geometry small = rtest_small(), odd = rtest_odd();
	for (int i = 0; i < 2; i++) {
		if (!rtest_have_gl(&small, backends[i]))
			continue;
		check_backend("small", &small, backends[i]);
		check_backend("odd", &odd, backends[i]);
		for (uint8_t m = GEOMETRY_BRIGHTNESS_EVEN; m <= GEOMETRY_BRIGHTNESS_UNIFORM; m++) {
			struct geometry g = small;
			char name[32];
			g.brightness = m;
			snprintf(name, sizeof(name), "small %s", geometry_brightness_name(m));
			check_backend(name, &g, backends[i]);
		}
	}
	return check_done();
}
