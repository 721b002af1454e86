/* Points light exactly the voxels docs/design.md section 3 assigns them: image
 * round(phi / D) mod N (lobe s >= 0) and round((phi - pi) / D) mod N (lobe
 * s < 0), folded onto N/2 volume images when mirrored, column from
 * s = p . d_k of the volume image, row from y, both clamped. */
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "rtest.h"

struct voxel {
	uint32_t k, u, v;
};

/* The expected voxels of point p; returns how many distinct (1 or 2). */
static int expect_voxels(const struct geometry *g, const double p[3], struct voxel out[2])
{
	uint32_t m = geometry_images_per_volume(g);
	double phi = atan2(p[2], p[0]);
	uint32_t j[2] = { geometry_image_of_azimuth(g, phi), geometry_image_of_azimuth_back(g, phi) };
	int n = 0;
	for (int i = 0; i < 2; i++) {
		uint32_t k = j[i] % m;
		double th = geometry_image_angle(g, k);
		struct voxel vx = { k, geometry_column(g, p[0] * cos(th) + p[2] * sin(th)), geometry_row(g, p[1]) };
		if (n == 1 && out[0].k == vx.k && out[0].u == vx.u && out[0].v == vx.v)
			continue;
		out[n++] = vx;
	}
	return n;
}

/* Renders one point; checks that exactly the expected voxels are lit, in
 * all three channels. Returns how many voxels were expected. */
static int check_point(const struct geometry *g, double x, double y, double z)
{
	struct rtest_mesh m = { 0 };
	rtest_mesh_add(&m, x, y, z);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 1);
	double p[3] = { m.xyz[0], m.xyz[1], m.xyz[2] }; /* as the renderer sees it */
	struct voxel want[2];
	int n = expect_voxels(g, p, want);
	for (int c = 0; c < 3; c++) {
		CHECK_MSG(rtest_count(vol, c) == (uint64_t)n, "point (%g,%g,%g) c%d: %llu lit, want %d", x, y, z, c,
			  (unsigned long long)rtest_count(vol, c), n);
		for (int i = 0; i < n; i++)
			CHECK_MSG(rtest_lit(vol, want[i].k, want[i].u, want[i].v, c),
				  "point (%g,%g,%g): voxel k%u u%u v%u not lit", x, y, z, want[i].k, want[i].u,
				  want[i].v);
	}
	volume_destroy(vol);
	rtest_mesh_free(&m);
	return n;
}

static void check_azimuths(const struct geometry *g)
{
	double dd = 2 * M_PI / g->images_per_rev;
	const double az[] = { 0.0,  0.3,       1.0, M_PI / 2, 2.5,     M_PI,       M_PI + 0.1,    4.0,
			      -0.2, -M_PI / 2, 5.9, dd / 2,   -dd / 2, 3 * dd / 2, M_PI + dd / 2, 7 * dd + 0.49 * dd };
	const double radii[] = { 0.05, 0.5, 0.97, 1.4 };
	const double ys[] = { 0.0, 0.33, -0.71 * g->half_height, 1.2 * g->half_height };
	for (size_t a = 0; a < sizeof(az) / sizeof(az[0]); a++) {
		for (size_t r = 0; r < sizeof(radii) / sizeof(radii[0]); r++) {
			double y = ys[(a + r) % 4];
			int n = check_point(g, radii[r] * cos(az[a]), y, radii[r] * sin(az[a]));
			/* A mirrored device lights a point once, off rounding ties. */
			if (g->mirrored && a < 11)
				CHECK_MSG(n == 1, "mirrored point at azimuth %g: %d voxels", az[a], n);
			if (!g->mirrored)
				CHECK(n == 2);
		}
	}
}

static void check_axis_points(const struct geometry *g)
{
	/* On the axis phi = atan2(0, 0) = 0: image 0, column of s = 0. */
	check_point(g, 0, 0, 0);
	check_point(g, 0, 0.5 * g->half_height, 0);
	check_point(g, 0, -g->half_height, 0);
	struct rtest_mesh m = { 0 };
	rtest_mesh_add(&m, 0, 0, 0);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 1);
	CHECK(rtest_lit(vol, 0, g->width / 2, geometry_row(g, 0), 0));
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* Points out of range, and not finite, in one scene with a good one. */
static void check_garbage_points(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	rtest_mesh_add(&m, NAN, 0, 0);
	rtest_mesh_add(&m, 0.5, INFINITY, 0);
	rtest_mesh_add(&m, 0.25, 0.25, 0.25);
	rtest_mesh_add(&m, 0, 0, -NAN);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	double p[3] = { 0.25, 0.25, 0.25 };
	struct voxel want[2];
	int n = expect_voxels(g, p, want);
	CHECK(rtest_count(vol, 0) == (uint64_t)n);
	CHECK(rtest_lit(vol, want[0].k, want[0].u, want[0].v, 0));
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* The transform is column-major (translation in elements 12..14) and
 * applied before ownership: a point moved and scaled lands where its
 * volume-space position says. */
static void check_transform(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	rtest_mesh_add(&m, 0.25, 0.125, -0.5);
	struct scene_draw d = rtest_draw(SCENE_POINTS, &m, 255, 255, 255);
	/* x' = 2x + 0.5 z + 0.125, y' = y - 0.25, z' = -x + 0.75 */
	d.transform[0] = 2.0f, d.transform[2] = -1.0f;
	d.transform[8] = 0.5f, d.transform[10] = 0.0f;
	d.transform[12] = 0.125f, d.transform[13] = -0.25f, d.transform[14] = 0.75f;
	double p[3] = { 0.5 - 0.25 + 0.125, 0.125 - 0.25, -0.25 + 0.75 };
	struct volume *vol = rtest_render(g, &d, 1, 1);
	struct voxel want[2];
	int n = expect_voxels(g, p, want);
	CHECK(rtest_count(vol, 0) == (uint64_t)n);
	for (int i = 0; i < n; i++)
		CHECK(rtest_lit(vol, want[i].k, want[i].u, want[i].v, 0));
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	check_azimuths(&small);
	check_axis_points(&small);
	check_garbage_points(&small);
	check_transform(&small);
	check_azimuths(&odd);
	check_axis_points(&odd);
	check_garbage_points(&odd);
	check_transform(&odd);
	return check_done();
}
