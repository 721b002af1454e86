/* Per-primitive colours (scene.h prim_rgb) on the CPU renderer: each point,
 * segment and triangle lights in its own colour instead of the draw's,
 * colours still combine per channel by MAX and dither as docs/design.md section
 * 3 says, and a primitive dropped for a non-finite vertex does not shift
 * the colours of those after it. The draws' own rgb is white throughout,
 * so a renderer that ignored prim_rgb would light every channel. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "halftone.h"
#include "rtest.h"

static const uint8_t white[3] = { 255, 255, 255 };

static struct scene_draw colour_draw(enum scene_prim prim, const struct rtest_mesh *m, const uint8_t *rgb)
{
	struct scene_draw d = rtest_draw(prim, m, white[0], white[1], white[2]);
	d.prim_rgb = rgb;
	return d;
}

/* Expected 8-bit values of a volume, per pixel and channel. */
struct expect {
	const struct geometry *g;
	uint32_t images;
	uint8_t *rgb;
};

static uint8_t *expect_at(const struct expect *e, uint32_t k, uint32_t u, uint32_t v)
{
	return &e->rgb[3 * (((size_t)k * e->g->height + v) * e->g->width + u)];
}

/* MAX of rgb into the square of size s around each voxel of point p. */
static void expect_point(struct expect *e, const float *p, int s, const uint8_t rgb[3])
{
	const struct geometry *g = e->g;
	struct rtest_voxel vx[2];
	rtest_point_voxels(g, p, vx);
	for (int i = 0; i < 2; i++)
		for (int dv = -(s - 1) / 2; dv <= s / 2; dv++)
			for (int du = -(s - 1) / 2; du <= s / 2; du++) {
				long x = (long)vx[i].u + du, y = (long)vx[i].v + dv;
				if (x < 0 || y < 0 || x >= (long)g->width || y >= (long)g->height)
					continue;
				uint8_t *px = expect_at(e, vx[i].k, (uint32_t)x, (uint32_t)y);
				for (int c = 0; c < 3; c++)
					px[c] = px[c] > rgb[c] ? px[c] : rgb[c];
			}
}

/* Every pixel of vol dithered from e's values: lit exactly where the
 * value exceeds the image's threshold there. */
static void check_expected(const struct volume *vol, const struct expect *e)
{
	const struct geometry *g = e->g;
	uint64_t want[3] = { 0 };
	for (uint32_t k = 0; k < e->images; k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				const uint8_t *px = expect_at(e, k, u, v);
				if (!(px[0] | px[1] | px[2]))
					continue;
				for (int c = 0; c < 3; c++) {
					bool lit = px[c] > halftone_threshold(k, u, v);
					want[c] += lit;
					CHECK_MSG(rtest_lit(vol, k, u, v, c) == lit, "image %u (%u,%u) c%d: value %u",
						  k, u, v, c, px[c]);
				}
			}
	for (int c = 0; c < 3; c++)
		CHECK_MSG(rtest_count(vol, c) == want[c], "c%d: %llu lit, want %llu", c,
			  (unsigned long long)rtest_count(vol, c), (unsigned long long)want[c]);
}

/* The edge points, then in a second draw (its colours from its own
 * primitive 0 on) a NaN point and point 0 again in another colour (the two
 * combine by MAX); at size 3. */
static void check_points(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	uint32_t n = rtest_edge_points(g, &m);
	rtest_mesh_add(&m, NAN, 0, 0);
	rtest_mesh_add(&m, m.xyz[0], m.xyz[1], m.xyz[2]);
	uint8_t *rgb = malloc(3 * (size_t)m.count);
	CHECK(rgb);
	for (uint32_t i = 0; i < m.count; i++)
		rtest_colour(i, rgb + 3 * i);
	struct scene_draw d[2] = { colour_draw(SCENE_POINTS, &m, rgb), colour_draw(SCENE_POINTS, &m, rgb + 3 * n) };
	d[0].count = n;
	d[1].xyz = m.xyz + 3 * n;
	d[1].count = m.count - n;
	d[0].point_size = d[1].point_size = 3;
	struct expect e = { g, geometry_images_per_volume(g), NULL };
	e.rgb = calloc((size_t)e.images * g->width * g->height, 3);
	CHECK(e.rgb);
	for (uint32_t i = 0; i < m.count; i++)
		if (i != n) /* the NaN lights nothing */
			expect_point(&e, m.xyz + 3 * i, 3, rgb + 3 * i);
	struct volume *vol = rtest_render(g, d, 2, 2);
	check_expected(vol, &e);
	volume_destroy(vol);
	free(e.rgb);
	free(rgb);
	rtest_mesh_free(&m);
}

/* Horizontal segments in the plane z = 0 (image 0's, lobe s < 0), one row
 * apart from the next, each in its own saturated colour, with a NaN
 * segment among them: each row lit in its segment's channels only. */
static void check_segments(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	uint8_t rgb[8 * 3];
	uint32_t rows[8];
	for (uint32_t i = 0; i < 8; i++) {
		rows[i] = g->height / 4 + 3 * i;
		double y = rtest_row_mid(g, rows[i]);
		rtest_mesh_add(&m, i == 3 ? NAN : -0.8, y, 0);
		rtest_mesh_add(&m, -0.2, y, 0);
		rtest_saturated(i, rgb + 3 * i);
	}
	struct scene_draw d = colour_draw(SCENE_LINES, &m, rgb);
	struct volume *vol = rtest_render(g, &d, 1, 1);
	uint32_t u0 = geometry_column(g, -F(0.8)), u1 = geometry_column(g, -F(0.2));
	for (uint32_t i = 0; i < 8; i++)
		for (uint32_t u = u0; u <= u1; u++)
			for (int c = 0; c < 3; c++)
				CHECK_MSG(rtest_lit(vol, 0, u, rows[i], c) == (i != 3 && rgb[3 * i + c]),
					  "segment %u column %u c%d", i, u, c);
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* A wall in the plane z = 0 split along its diagonal (rtest_wall): the
 * lower right triangle red, the upper left blue, seen by image 0. */
static void check_wall(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	rtest_wall(&m, 0.9, 0.9 * g->half_height);
	const uint8_t rgb[6] = { 255, 0, 0, 0, 0, 255 };
	struct scene_draw d = colour_draw(SCENE_TRIANGLES, &m, rgb);
	struct volume *vol = rtest_render(g, &d, 1, 1);
	double h = g->half_height;
	uint32_t lr_u = geometry_column(g, 0.6), lr_v = geometry_row(g, -0.6 * h);
	uint32_t ul_u = geometry_column(g, -0.6), ul_v = geometry_row(g, 0.6 * h);
	CHECK(rtest_lit(vol, 0, lr_u, lr_v, 0) && !rtest_lit(vol, 0, lr_u, lr_v, 1) &&
	      !rtest_lit(vol, 0, lr_u, lr_v, 2));
	CHECK(!rtest_lit(vol, 0, ul_u, ul_v, 0) && !rtest_lit(vol, 0, ul_u, ul_v, 1) &&
	      rtest_lit(vol, 0, ul_u, ul_v, 2));
	CHECK(rtest_count(vol, 0) > 0 && rtest_count(vol, 1) == 0 && rtest_count(vol, 2) > 0);
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* The primitives of m as two draws with prim_rgb (the second's colours
 * from its own primitive 0 on) render exactly as one draw per primitive in
 * its colour. */
static void check_same_as_draws(const struct geometry *g, enum scene_prim prim, const struct rtest_mesh *m)
{
	uint32_t nv = prim == SCENE_LINES ? 2 : 3, n = m->count / nv;
	uint8_t *rgb = malloc(3 * (size_t)n);
	struct scene_draw *draws = calloc(n, sizeof(*draws));
	CHECK(rgb && draws);
	for (uint32_t i = 0; i < n; i++) {
		rtest_colour(i, rgb + 3 * i);
		draws[i] = rtest_draw(prim, m, rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
		draws[i].xyz = m->xyz + (size_t)i * nv * 3;
		draws[i].count = nv;
	}
	uint32_t half = n / 2;
	struct scene_draw two[2] = { colour_draw(prim, m, rgb), colour_draw(prim, m, rgb + 3 * half) };
	two[0].count = half * nv;
	two[1].xyz = m->xyz + (size_t)half * nv * 3;
	two[1].count = (n - half) * nv;
	struct volume *a = rtest_render(g, two, 2, 2), *b = rtest_render(g, draws, n, 2);
	CHECK_MSG(rtest_count(a, 0) > 0, "prim %d lights nothing", prim);
	CHECK_MSG(rtest_same(a, b), "prim %d: prim_rgb differs from a draw per primitive", prim);
	volume_destroy(a);
	volume_destroy(b);
	free(draws);
	free(rgb);
}

/* An off-axis sphere's triangles, with a NaN triangle among them, and its
 * vertices paired up as segments: overlapping primitives of many
 * colours. */
static void check_meshes(const struct geometry *g)
{
	struct rtest_mesh sphere = { 0 }, tris = { 0 };
	rtest_sphere(&sphere, 0.35, 12, 6);
	for (uint32_t i = 0; i < sphere.count; i++) {
		const float *p = sphere.xyz + 3 * i;
		rtest_mesh_add(&tris, i == 31 ? NAN : p[0] + 0.4, p[1], p[2] - 0.2);
	}
	check_same_as_draws(g, SCENE_TRIANGLES, &tris);
	tris.count &= ~1u;
	check_same_as_draws(g, SCENE_LINES, &tris);
	rtest_mesh_free(&sphere);
	rtest_mesh_free(&tris);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	const struct geometry *gs[2] = { &small, &odd };
	for (int i = 0; i < 2; i++) {
		check_points(gs[i]);
		check_segments(gs[i]);
		check_wall(gs[i]);
		check_meshes(gs[i]);
	}
	return check_done();
}
