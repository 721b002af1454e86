/* Bad input never crashes the renderer and gives sane output: empty scenes
 * and draws, short counts, unknown primitive kinds, NaN and infinite
 * coordinates or transforms (the primitive or grid is skipped), enormous coordinates
 * (clamped to the image), degenerate primitives (still lit). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "rtest.h"

static void check_empty(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	struct scene_draw d[4] = { rtest_draw(SCENE_TRIANGLES, &m, 255, 255, 255),
				   rtest_draw(SCENE_LINES, &m, 255, 255, 255),
				   rtest_draw(SCENE_POINTS, &m, 255, 255, 255) };
	d[3] = d[0];
	d[3].count = 9; /* no vertex data: skipped */
	struct volume *vol = rtest_render(g, NULL, 0, 1);
	CHECK(volume_tile_count(vol) == 0);
	volume_destroy(vol);
	vol = rtest_render(g, d, 4, 2);
	CHECK(volume_tile_count(vol) == 0);
	volume_destroy(vol);
	struct renderer *r = render_cpu_create(g, 1);
	vol = volume_create(g);
	CHECK(render_volume(r, NULL, vol) == 0 && volume_tile_count(vol) == 0);
	render_destroy(r);
	volume_destroy(vol);
}

/* Triangles with NaN or infinite vertices, a NaN transform, a short count
 * and an unknown primitive kind, beside one good segment: only the segment
 * shows. */
static void check_not_finite(const struct geometry *g)
{
	struct rtest_mesh bad = { 0 }, good = { 0 };
	rtest_mesh_add(&bad, NAN, 0, 0);
	rtest_mesh_add(&bad, 0.5, 0, 0);
	rtest_mesh_add(&bad, 0, 0.5, 0);
	rtest_mesh_add(&bad, INFINITY, 0, 0.1);
	rtest_mesh_add(&bad, 0.5, -INFINITY, 0);
	rtest_mesh_add(&bad, 0, 0.5, NAN);
	rtest_mesh_add(&bad, 0.3, 0.3, 0.3); /* a 7th vertex: not a triangle */
	rtest_mesh_add(&good, 0.2, -0.3, 0.4);
	rtest_mesh_add(&good, -0.5, 0.6, 0.1);
	struct scene_draw seg = rtest_draw(SCENE_LINES, &good, 255, 255, 255);
	/* Grids with no grid, a NaN or infinite transform: nothing. */
	static const uint8_t one = 255;
	static const struct scene_grid tiny = { SCENE_GRID_U8, { 1, 1, 1 }, { 0.5f, 0.5f, 0.5f }, &one, NULL };
	struct scene_draw grid = { .prim = SCENE_GRID, .rgb = { 255, 255, 255 }, .transfer = { 1, 0, 255 } };
	rtest_identity(grid.transform);
	struct scene_draw d[8] = {
		rtest_draw(SCENE_TRIANGLES, &bad, 255, 255, 255),
		rtest_draw(SCENE_TRIANGLES, &good, 255, 255, 255),
		seg,
		seg,
		rtest_draw(SCENE_POINTS, &good, 255, 255, 255),
		grid,
		grid,
		grid
	};
	d[1].count = 2; /* too short for a triangle */
	d[3].transform[5] = NAN;
	d[4].prim = (enum scene_prim)7;
	d[6].grid = d[7].grid = &tiny;
	d[6].transform[0] = NAN;
	d[7].transform[13] = INFINITY;
	struct volume *want = rtest_render(g, &seg, 1, 1), *got = rtest_render(g, d, 8, 2);
	CHECK(rtest_count(want, 0) > 0);
	CHECK(rtest_same(want, got));
	volume_destroy(want);
	volume_destroy(got);
	rtest_mesh_free(&bad);
	rtest_mesh_free(&good);
}

/* Enormous coordinates are clamped to the image: a far point lands on the
 * edge column; a huge flat triangle at y = 0 lights row(0) only, in every
 * image, and float-max vertices scaled further by the transform don't
 * crash. */
static void check_enormous(const struct geometry *g)
{
	struct rtest_mesh pt = { 0 }, tri = { 0 }, max = { 0 };
	rtest_mesh_add(&pt, 1e30, 0.2, 0);
	rtest_mesh_add(&tri, 1e30, 0, 1e30);
	rtest_mesh_add(&tri, -3e30, 0, 2e29);
	rtest_mesh_add(&tri, 1e29, 0, -4e30);
	rtest_mesh_add(&max, 3.4e38, 3.4e38, -3.4e38);
	rtest_mesh_add(&max, -3.4e38, 0, 3.4e38);
	rtest_mesh_add(&max, 1, -3.4e38, 3.4e38);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &pt, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 1);
	CHECK(rtest_lit(vol, 0, g->width - 1, geometry_row(g, F(0.2)), 0));
	volume_destroy(vol);
	d = rtest_draw(SCENE_TRIANGLES, &tri, 255, 255, 255);
	vol = rtest_render(g, &d, 1, 2);
	uint32_t row = geometry_row(g, 0.0);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		uint64_t in_row = 0;
		for (uint32_t u = 0; u < g->width; u++)
			in_row += rtest_lit(vol, k, u, row, 0);
		CHECK(in_row > 0 && in_row == rtest_count_image(vol, k, 0));
	}
	CHECK(rtest_padding_clear(vol));
	volume_destroy(vol);
	struct scene_draw dm[2] = { rtest_draw(SCENE_TRIANGLES, &max, 255, 255, 255),
				    rtest_draw(SCENE_LINES, &max, 255, 255, 255) };
	dm[0].transform[0] = 3e38f;
	dm[1].transform[12] = 3e38f;
	vol = rtest_render(g, dm, 2, 2);
	CHECK(volume_tile_count(vol) <= (uint64_t)vol->image_count * volume_tiles_per_image(vol));
	CHECK(rtest_padding_clear(vol));
	volume_destroy(vol);
	rtest_mesh_free(&pt);
	rtest_mesh_free(&tri);
	rtest_mesh_free(&max);
}

/* Zero-area triangles light their section like the segment they are. */
static void check_degenerate(const struct geometry *g)
{
	struct rtest_mesh seg = { 0 }, tri = { 0 }, dot = { 0 };
	double a[3] = { 0.7, -0.4, 0.2 }, b[3] = { -0.3, 0.5, -0.6 };
	rtest_mesh_add(&seg, a[0], a[1], a[2]);
	rtest_mesh_add(&seg, b[0], b[1], b[2]);
	rtest_mesh_add(&tri, a[0], a[1], a[2]);
	rtest_mesh_add(&tri, b[0], b[1], b[2]);
	rtest_mesh_add(&tri, a[0], a[1], a[2]);
	for (int i = 0; i < 3; i++)
		rtest_mesh_add(&dot, 0.4, 0.1, 0.4);
	struct scene_draw ds = rtest_draw(SCENE_LINES, &seg, 255, 255, 255);
	struct scene_draw dt = rtest_draw(SCENE_TRIANGLES, &tri, 255, 255, 255);
	struct scene_draw dd = rtest_draw(SCENE_TRIANGLES, &dot, 255, 255, 255);
	struct volume *vs = rtest_render(g, &ds, 1, 1), *vt = rtest_render(g, &dt, 1, 1);
	struct volume *vd = rtest_render(g, &dd, 1, 1);
	CHECK(rtest_count(vs, 0) > 0);
	CHECK(rtest_same(vs, vt));
	/* A triangle shrunk to a point lights it in its image(s), at most one
	 * voxel each per image that touches it (wedge boundaries are shared). */
	CHECK(rtest_count(vd, 0) >= 1 && rtest_count(vd, 0) <= 4);
	volume_destroy(vs);
	volume_destroy(vt);
	volume_destroy(vd);
	rtest_mesh_free(&seg);
	rtest_mesh_free(&tri);
	rtest_mesh_free(&dot);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	check_empty(&small);
	check_not_finite(&small);
	check_not_finite(&odd);
	check_enormous(&small);
	check_enormous(&odd);
	check_degenerate(&small);
	check_degenerate(&odd);
	return check_done();
}
