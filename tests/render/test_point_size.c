/* Point sizes (scene.h) on the CPU renderer, the reference: a point of
 * size s lights, in each volume image it lies in, the s x s square of
 * columns u - (s-1)/2 .. u + s/2 and rows v - (s-1)/2 .. v + s/2 around its
 * voxel (u, v), clipped to the image; 0 counts as 1, sizes above 16 as 16.
 * The expected squares come from docs/design.md section 3's formulas
 * (rtest_point_voxels()) for points at and beyond the image edges and
 * corners (rtest_edge_points()), mirrored (the square lies in the volume
 * image's own columns) and not, and are compared pixel for pixel. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "rtest.h"

/* A volume's worth of expected pixels, one byte each. */
struct expect {
	const struct geometry *g;
	uint32_t images;
	uint8_t *lit;
	uint64_t count;
};

static uint8_t *expect_at(struct expect *e, uint32_t k, uint32_t u, uint32_t v)
{
	return &e->lit[((size_t)k * e->g->height + v) * e->g->width + u];
}

/* The square of size s around pixel (u, v) of image k, clipped. */
static void expect_square(struct expect *e, uint32_t k, uint32_t u, uint32_t v, int s)
{
	const struct geometry *g = e->g;
	for (int dv = -(s - 1) / 2; dv <= s / 2; dv++) {
		for (int du = -(s - 1) / 2; du <= s / 2; du++) {
			long x = (long)u + du, y = (long)v + dv;
			if (x < 0 || y < 0 || x >= (long)g->width || y >= (long)g->height)
				continue;
			uint8_t *px = expect_at(e, k, (uint32_t)x, (uint32_t)y);
			e->count += !*px;
			*px = 1;
		}
	}
}

/* Point p's squares in both of its images (rtest_point_voxels()). */
static void expect_point(struct expect *e, const float *p, int s)
{
	struct rtest_voxel vx[2];
	rtest_point_voxels(e->g, p, vx);
	for (int i = 0; i < 2; i++)
		expect_square(e, vx[i].k, vx[i].u, vx[i].v, s);
}

/* Every channel of vol lit exactly where e says. */
static void check_expected(const struct volume *vol, const struct expect *e, const char *what)
{
	const struct geometry *g = e->g;
	for (int c = 0; c < 3; c++)
		CHECK_MSG(rtest_count(vol, c) == e->count, "%s c%d: %llu lit, want %llu", what, c,
			  (unsigned long long)rtest_count(vol, c), (unsigned long long)e->count);
	for (uint32_t k = 0; k < e->images; k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++)
				if (e->lit[((size_t)k * g->height + v) * g->width + u])
					for (int c = 0; c < 3; c++)
						CHECK_MSG(rtest_lit(vol, k, u, v, c), "%s: image %u (%u,%u) c%d dark",
							  what, k, u, v, c);
}

/* The edge points drawn at point_size `size`, which lights squares of
 * `want` pixels a side. */
static void check_size(const struct geometry *g, const char *gname, uint8_t size, int want)
{
	struct rtest_mesh m = { 0 };
	rtest_edge_points(g, &m);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	d.point_size = size;
	struct expect e = { g, geometry_images_per_volume(g), NULL, 0 };
	e.lit = calloc((size_t)e.images * g->width * g->height, 1);
	CHECK(e.lit);
	for (uint32_t i = 0; i < m.count; i++)
		expect_point(&e, m.xyz + 3 * i, want);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	char what[64];
	snprintf(what, sizeof(what), "%s size %u", gname, size);
	check_expected(vol, &e, what);
	CHECK_MSG(rtest_padding_clear(vol), "%s: padding bits set", what);
	volume_destroy(vol);
	free(e.lit);
	rtest_mesh_free(&m);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	for (int s = 1; s <= 16; s++) {
		check_size(&small, "small", (uint8_t)s, s);
		check_size(&odd, "odd", (uint8_t)s, s);
	}
	/* 0 counts as 1; larger than 16 as 16. */
	check_size(&small, "small", 0, 1);
	check_size(&odd, "odd", 0, 1);
	check_size(&small, "small", 17, 16);
	check_size(&odd, "odd", 255, 16);
	return check_done();
}
