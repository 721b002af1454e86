/* Binning is conservative and exact in its bookkeeping: the renderer, which
 * sections each primitive only in the images its outcode/slope bin gives,
 * produces the same volume bit for bit as sectioning every primitive in
 * every image; the slope table agrees with atan2 wherever it does not flag
 * a boundary as near; and every thread count and halftone variant gives the
 * same bytes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "halftone.h"
#include "rtest.h"
#include "section.h"
#include "slot.h"

static uint64_t rng = 0x9e3779b97f4a7c15ull;

static double range(double a, double b)
{
	return rtest_range(&rng, a, b);
}

static uint32_t exact_slot(uint32_t n, double x, double z)
{
	long long k = llround(atan2(z, x) / (2.0 * M_PI / n)) % (long long)n;
	return (uint32_t)(k < 0 ? k + n : k);
}

/* Slot s against atan2's: the same where not near, a neighbour at most
 * where near. */
static void check_slot_is(const struct slot_table *t, double phi, uint32_t s, uint32_t want, bool near,
			  const char *which)
{
	uint32_t diff = (s + t->n - want) % t->n;
	if (near)
		CHECK_MSG(diff == 0 || diff == 1 || diff == t->n - 1, "N=%u phi=%.17g: %s %u, atan2 %u", t->n, phi,
			  which, s, want);
	else
		CHECK_MSG(diff == 0, "N=%u phi=%.17g: %s %u, atan2 %u (not near)", t->n, phi, which, s, want);
}

static void check_slot_at(const struct slot_table *t, double phi, double r)
{
	float x = (float)(r * cos(phi)), z = (float)(r * sin(phi));
	bool near = false;
	uint32_t want = exact_slot(t->n, x, z), s = slot_of(t, x, z, &near);
	check_slot_is(t, phi, s, want, near, "slot");
}

static void check_slots(uint32_t n)
{
	struct slot_table t;
	CHECK(slot_table_init(&t, n) == 0);
	double d = 2.0 * M_PI / n;
	for (int i = 0; i < 200000; i++)
		check_slot_at(&t, range(-M_PI, M_PI), range(1e-3, 2.0));
	/* On and around every boundary, and on the four planes. */
	for (uint32_t j = 0; j < n; j++)
		for (int e = -3; e <= 3; e++)
			check_slot_at(&t, (j + 0.5) * d + e * 1e-7, range(0.01, 1.5));
	/* Within 4e-5 of every boundary, where a bucket border may lie close */
	for (uint32_t j = 0; j < n; j++)
		for (int e = -400; e <= 400; e += 3)
			check_slot_at(&t, (j + 0.5) * d + e * 1e-7, range(0.01, 1.5));
	for (int q = 0; q < 8; q++)
		check_slot_at(&t, q * M_PI / 4, 0.7);
	bool near = false;
	CHECK(slot_of(&t, 0.0f, 0.0f, &near) == SLOT_AXIS);
	CHECK(slot_of(&t, -0.0f, 0.0f, &near) == SLOT_AXIS);
	slot_table_finish(&t);
}

/* Vertices as the renderer keeps them: transformed in double, stored as
 * float. */
static void place(const float m[16], const float *in, double out[3])
{
	for (int i = 0; i < 3; i++)
		out[i] =
			(float)((double)m[i] * in[0] + (double)m[4 + i] * in[1] + (double)m[8 + i] * in[2] + m[12 + i]);
}

/* Every primitive sectioned in every image, halftoned with the scalar
 * variant: what a renderer with no binning at all would produce. */
static struct volume *brute_force(const struct geometry *g, const struct scene_draw *draws, uint32_t nd)
{
	struct volume *vol = volume_create(g);
	struct section_canvas c;
	CHECK(vol && section_canvas_init(&c, g) == 0);
	halftone_fn ht = halftone_pick("scalar");
	for (uint32_t k = 0; k < vol->image_count; k++) {
		struct section_wedge w;
		section_wedge_init(&w, g, k);
		for (uint32_t i = 0; i < nd; i++) {
			int nv = draws[i].prim == SCENE_LINES ? 2 : 3;
			for (uint32_t p = 0; p + nv <= draws[i].count; p += nv) {
				double v[3][3];
				for (int a = 0; a < nv; a++)
					place(draws[i].transform, draws[i].xyz + 3 * (p + a), v[a]);
				section_prim(&c, &w, (const double(*)[3])v, nv, draws[i].rgb);
			}
		}
		struct halftone_table thr;
		halftone_table_init(&thr, k);
		for (uint32_t t = 0; t < c.tiles_x * c.tiles_y; t++) {
			uint8_t tile[VOLUME_TILE_BYTES];
			if (c.rows[t] && ht(c.rgb + (size_t)t * HALFTONE_TILE_BYTES, c.rows[t], &thr, tile))
				CHECK(volume_image_append(vol, k, t, tile) == 0);
			section_canvas_clear_tile(&c, t);
		}
	}
	section_canvas_finish(&c);
	return vol;
}

static void add_prim(struct rtest_mesh *m, int nv, double cx, double cy, double cz, double size)
{
	for (int i = 0; i < nv; i++)
		rtest_mesh_add(m, cx + range(-size, size), cy + range(-size, size), cz + range(-size, size));
}

/* Small, medium and long primitives everywhere, some across or next to the
 * axis, some with vertices exactly on slot boundaries. */
static void random_mesh(const struct geometry *g, struct rtest_mesh *m, int nv, int count)
{
	double d = 2.0 * M_PI / g->images_per_rev, h = g->half_height;
	for (int i = 0; i < count; i++) {
		double r = range(0.0, 1.0), phi = range(-M_PI, M_PI), y = range(-h, h);
		double size = i % 4 == 0 ? 0.002 : i % 4 == 1 ? 0.03 : i % 4 == 2 ? 0.2 : 0.8;
		if (i % 7 == 0)
			r = range(0.0, 0.01);
		if (i % 5 == 0) {
			phi = (floor(range(0, g->images_per_rev)) + 0.5) * d;
			for (int j = 0; j < nv; j++)
				rtest_mesh_add(m, r * cos(phi) * (1 + j), y + 0.05 * j, r * sin(phi) * (1 + j));
			continue;
		}
		add_prim(m, nv, r * cos(phi), y, r * sin(phi), size);
	}
}

static void check_against_brute_force(const struct geometry *g)
{
	struct rtest_mesh tri = { 0 }, seg = { 0 };
	random_mesh(g, &tri, 3, 600);
	random_mesh(g, &seg, 2, 600);
	struct scene_draw d[3] = {
		rtest_draw(SCENE_TRIANGLES, &tri, 200, 90, 0),
		rtest_draw(SCENE_LINES, &seg, 30, 255, 140),
		rtest_draw(SCENE_TRIANGLES, &tri, 0, 0, 255),
	};
	/* A rotation about y by 0.3 rad plus a shift: slopes change. */
	float c = cosf(0.3f), s = sinf(0.3f);
	d[2].transform[0] = c, d[2].transform[2] = -s, d[2].transform[8] = s, d[2].transform[10] = c;
	d[2].transform[12] = 0.05f, d[2].transform[14] = -0.1f;
	struct volume *want = brute_force(g, d, 3);
	for (unsigned threads = 1; threads <= 3; threads++) {
		struct volume *got = rtest_render(g, d, 3, threads);
		CHECK_MSG(rtest_same(want, got), "N=%u %s, %u threads: binned render differs from brute force",
			  g->images_per_rev, g->mirrored ? "mirrored" : "plain", threads);
		volume_destroy(got);
	}
	volume_destroy(want);
	rtest_mesh_free(&tri);
	rtest_mesh_free(&seg);
}

/* Every runnable halftone variant gives the scalar variant's bytes, on a
 * scene with points, lines and triangles in many colours. */
static void check_variants(const struct geometry *g)
{
	struct rtest_mesh tri = { 0 }, pts = { 0 };
	random_mesh(g, &tri, 3, 300);
	for (int i = 0; i < 5000; i++)
		rtest_mesh_add(&pts, range(-1, 1), range(-1, 1), range(-1, 1));
	struct scene_draw d[2] = {
		rtest_draw(SCENE_TRIANGLES, &tri, 77, 128, 201),
		rtest_draw(SCENE_POINTS, &pts, 255, 1, 254),
	};
	struct scene scene = { .draw_count = 2, .draws = d };
	struct volume *ref = NULL;
	for (const struct halftone_variant *v = halftone_variants(); v->name; v++) {
		struct render_cpu_options o = { .threads = 2, .simd = v->name };
		struct renderer *r = render_cpu_create_opts(g, &o);
		struct volume *vol = volume_create(g);
		CHECK(r && vol && render_volume(r, &scene, vol) == 0);
		if (ref)
			CHECK_MSG(rtest_same(ref, vol), "halftone %s differs", v->name);
		else
			ref = vol;
		if (vol != ref)
			volume_destroy(vol);
		render_destroy(r);
	}
	struct render_cpu_options bad = { .threads = 1, .simd = "mmx" };
	CHECK(render_cpu_create_opts(g, &bad) == NULL);
	volume_destroy(ref);
	rtest_mesh_free(&tri);
	rtest_mesh_free(&pts);
}

int main(void)
{
	check_slots(128);
	check_slots(396);
	check_slots(50);
	check_slots(45);
	struct geometry small = rtest_small(), odd = rtest_odd();
	struct geometry odd_n = { 96, 64, 45, false, 1.25f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	check_against_brute_force(&small);
	check_against_brute_force(&odd);
	check_against_brute_force(&odd_n);
	check_variants(&small);
	check_variants(&odd);
	return check_done();
}
