/* Lines and surfaces are lit by their exact section with each image's bow
 * tie, conservatively rasterised: the axis line, a disk and a sphere through
 * the dead zone, and a wall edge-on to most images. */
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "rtest.h"

static double dist_to_axis_plane(double x, double y, double z)
{
	return sqrt(x * x + y * y + z * z);
}

/* A vertical segment on the axis: column of s = 0 (u = floor(W/2)), its
 * rows with no gap, nothing else, in every image. */
static void check_axis_line(const struct geometry *g)
{
	uint32_t va = 5, vb = g->height - 9;
	struct rtest_mesh m = { 0 };
	rtest_mesh_add(&m, 0, rtest_row_mid(g, va), 0);
	rtest_mesh_add(&m, 0, rtest_row_mid(g, vb), 0);
	struct scene_draw d = rtest_draw(SCENE_LINES, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	uint32_t u = geometry_column(g, 0.0);
	CHECK(u == g->width / 2);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		CHECK_MSG(rtest_count_image(vol, k, 0) == vb - va + 1, "image %u: %llu lit", k,
			  (unsigned long long)rtest_count_image(vol, k, 0));
		for (uint32_t v = va; v <= vb; v++)
			CHECK_MSG(rtest_lit(vol, k, u, v, 0), "image %u row %u", k, v);
	}
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* Every image lights row over s in [-r_in, r_in] with no hole, and nothing
 * outside that row or beyond s = +-r_out. */
static void check_flat_section(const struct geometry *g, const struct rtest_mesh *m, double r_in, double r_out,
			       uint32_t row)
{
	struct scene_draw d = rtest_draw(SCENE_TRIANGLES, m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	uint32_t u_in0 = geometry_column(g, -r_in), u_in1 = geometry_column(g, r_in);
	uint32_t u0 = geometry_column(g, -r_out), u1 = geometry_column(g, r_out);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		for (uint32_t u = u_in0; u <= u_in1; u++)
			CHECK_MSG(rtest_lit(vol, k, u, row, 0), "flat image %u: hole at u %u", k, u);
		uint64_t in_row = 0;
		for (uint32_t u = u0; u <= u1; u++)
			in_row += rtest_lit(vol, k, u, row, 0);
		CHECK_MSG(in_row == rtest_count_image(vol, k, 0), "flat image %u: lit off its row/span", k);
	}
	volume_destroy(vol);
}

/* A horizontal disk (triangle fan) centred on the axis, radius r; its
 * polygon's inner radius is r cos(pi / segments). */
static void check_disk(const struct geometry *g, double r, uint32_t row)
{
	int segs = 40;
	struct rtest_mesh m = { 0 };
	rtest_disk(&m, r, rtest_row_mid(g, row), segs);
	check_flat_section(g, &m, r * cos(M_PI / segs), r, row);
	rtest_mesh_free(&m);
}

/* One horizontal triangle around the axis, no vertex on it (binning must
 * still send it to every image): inner radius r / 2. */
static void check_triangle_around_axis(const struct geometry *g, double r, uint32_t row)
{
	struct rtest_mesh m = { 0 };
	double y = rtest_row_mid(g, row);
	for (int i = 0; i < 3; i++)
		rtest_mesh_add(&m, r * cos(0.3 + 2 * M_PI * i / 3), y, r * sin(0.3 + 2 * M_PI * i / 3));
	check_flat_section(g, &m, r / 2, r, row);
	rtest_mesh_free(&m);
}

/* Smallest distance from the origin to the mesh (to its triangles' planes,
 * a lower bound): the inner radius of the faceted sphere. */
static double mesh_inner_radius(const struct rtest_mesh *m)
{
	double best = INFINITY;
	for (uint32_t i = 0; i + 2 < m->count; i += 3) {
		const float *a = m->xyz + 3 * i, *b = a + 3, *c = a + 6;
		double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
		double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
				e1[0] * e2[1] - e1[1] * e2[0] };
		double len = dist_to_axis_plane(n[0], n[1], n[2]);
		double dist = fabs(n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / len;
		best = fmin(best, dist);
	}
	return best;
}

/* Range of distances from the origin over the cell of pixel (u, v). */
static void cell_radii(const struct geometry *g, uint32_t u, uint32_t v, double *lo, double *hi)
{
	double s0 = rtest_col_s0(g, u), s1 = rtest_col_s1(g, u);
	double y0 = rtest_row_y1(g, v), y1 = rtest_row_y0(g, v);
	double sn = s0 > 0 ? s0 : s1 < 0 ? -s1 : 0, yn = y0 > 0 ? y0 : y1 < 0 ? -y1 : 0;
	double sf = fmax(fabs(s0), fabs(s1)), yf = fmax(fabs(y0), fabs(y1));
	*lo = sqrt(sn * sn + yn * yn);
	*hi = sqrt(sf * sf + yf * yf);
}

static bool near_lit(const struct volume *vol, uint32_t k, int u, int v)
{
	if (u < 0 || v < 0 || u >= (int)vol->geom.width || v >= (int)vol->geom.height)
		return false;
	return rtest_lit(vol, k, (uint32_t)u, (uint32_t)v, 0);
}

/* A sphere centred on the axis is edge-on to every image. Its section
 * projects into the annulus [r_in cos(D/2), r] (facets are inside the sphere;
 * off the slice plane s shrinks by at most cos(D/2)). Every lit cell must
 * touch that annulus, and every point of the circle of radius r must have a
 * lit voxel within one voxel. */
static void check_sphere(const struct geometry *g, double r)
{
	struct rtest_mesh m = { 0 };
	rtest_sphere(&m, r, 48, 24);
	double lo_r = mesh_inner_radius(&m) * cos(M_PI / g->images_per_rev) - 1e-6;
	double hi_r = r + 1e-6;
	struct scene_draw d = rtest_draw(SCENE_TRIANGLES, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				if (!rtest_lit(vol, k, u, v, 0))
					continue;
				double a, b;
				cell_radii(g, u, v, &a, &b);
				CHECK_MSG(a <= hi_r && b >= lo_r, "sphere image %u: stray voxel %u,%u", k, u, v);
			}
		for (int i = 0; i < 2000; i++) {
			double t = 2 * M_PI * i / 2000;
			uint32_t u = geometry_column(g, r * cos(t)), v = geometry_row(g, r * sin(t));
			bool near = false;
			for (int dv = -1; dv <= 1 && !near; dv++)
				for (int du = -1; du <= 1 && !near; du++)
					near = near_lit(vol, k, (int)u + du, (int)v + dv);
			CHECK_MSG(near, "sphere image %u: circle at %g has no lit voxel", k, t);
		}
	}
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* A wall in the plane z = 0: images whose bow tie contains the plane (image
 * 0, and N/2 unmirrored) fill the rectangle; every other image meets it on
 * the axis only and lights the columns next to s = 0 over its rows. */
static void check_wall(const struct geometry *g, double a, double b)
{
	struct rtest_mesh m = { 0 };
	rtest_wall(&m, a, b);
	struct scene_draw d = rtest_draw(SCENE_TRIANGLES, &m, 255, 255, 255);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	uint32_t u0 = geometry_column(g, -F(a)), u1 = geometry_column(g, F(a));
	uint32_t v0 = geometry_row(g, F(b)), v1 = geometry_row(g, -F(b)), mid = g->width / 2;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		bool in_plane = k == 0 || (!g->mirrored && 2 * k == g->images_per_rev);
		uint64_t want = in_plane ? (uint64_t)(u1 - u0 + 1) * (v1 - v0 + 1) : 0, inside = 0;
		for (uint32_t v = v0; v <= v1; v++) {
			bool row_lit = false;
			for (uint32_t u = u0; u <= u1; u++) {
				bool lit = rtest_lit(vol, k, u, v, 0);
				inside += lit;
				if (lit && !in_plane)
					CHECK_MSG(u + 1 >= mid && u <= mid, "wall image %u: lit at u %u", k, u);
				row_lit |= lit;
			}
			CHECK_MSG(row_lit, "wall image %u: row %u dark", k, v);
		}
		CHECK(inside == rtest_count_image(vol, k, 0));
		if (in_plane)
			CHECK_MSG(inside == want, "wall image %u: %llu of %llu", k, (unsigned long long)inside,
				  (unsigned long long)want);
	}
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	check_axis_line(&small);
	check_axis_line(&odd);
	check_disk(&small, 0.6, 40);
	check_disk(&small, 0.95, 100);
	check_disk(&odd, 0.7, 30);
	check_triangle_around_axis(&small, 0.8, 70);
	check_triangle_around_axis(&odd, 0.9, 20);
	check_sphere(&small, 0.5);
	check_sphere(&small, 0.9);
	check_sphere(&odd, 0.6);
	check_wall(&small, 0.7, 0.5);
	check_wall(&odd, 0.55, 0.6);
	return check_done();
}
