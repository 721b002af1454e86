/* Colour: MAX combine, and the ordered dither of docs/design.md section 3 (0
 * never lit, 255 always, c lights about c/255, a fixed phase per image that
 * differs between images). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "halftone.h"
#include "rtest.h"

static void check_threshold_matrix(void)
{
	/* Any 16x16 window holds each Bayer rank once: exactly ceil(256 c / 255)
	 * thresholds below c. */
	for (uint32_t k = 0; k < 300; k += 7) {
		int below[256] = { 0 };
		for (uint32_t v = 0; v < 16; v++)
			for (uint32_t u = 0; u < 16; u++) {
				uint8_t t = halftone_threshold(k, u + 5, v + 3);
				CHECK(t <= 254);
				CHECK(t == halftone_threshold(k, u + 5 + 16 * 7, v + 3 + 16 * 3));
				below[t]++;
			}
		int n = 0;
		for (int c = 0; c < 256; c++) {
			CHECK_MSG(n == (int)ceil(256.0 * c / 255.0), "k %u c %d: %d below", k, c, n);
			if (c < 255)
				n += below[c];
		}
	}
	/* Phases: 256 consecutive images all dither differently. */
	static uint8_t pat[256][256];
	for (uint32_t k = 0; k < 256; k++)
		for (uint32_t i = 0; i < 256; i++)
			pat[k][i] = halftone_threshold(k + 11, i % 16, i / 16);
	for (uint32_t a = 0; a < 256; a++)
		for (uint32_t b = a + 1; b < 256; b++)
			CHECK_MSG(memcmp(pat[a], pat[b], 256) != 0, "images %u and %u share a phase", a + 11, b + 11);
}

/* Pixels of rectangle [u0, u1] x [v0, v1] of image k: channel c lit exactly
 * where value > threshold. */
static void check_dithered(const struct volume *vol, uint32_t k, uint32_t u0, uint32_t u1, uint32_t v0, uint32_t v1,
			   const uint8_t rgb[3])
{
	for (uint32_t v = v0; v <= v1; v++)
		for (uint32_t u = u0; u <= u1; u++)
			for (int c = 0; c < 3; c++) {
				bool want = rgb[c] > halftone_threshold(k, u, v);
				CHECK_MSG(rtest_lit(vol, k, u, v, c) == want, "image %u (%u,%u) c%d", k, u, v, c);
			}
}

/* A wall in the plane z = 0 at a uniform colour, seen whole by image 0. */
static void check_uniform(const struct geometry *g, uint8_t value)
{
	struct rtest_mesh m = { 0 };
	rtest_wall(&m, 0.9, 0.9 * g->half_height);
	struct scene_draw d = rtest_draw(SCENE_TRIANGLES, &m, value, value / 2, 255 - value);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	uint32_t u0 = geometry_column(g, -F(0.9)), u1 = geometry_column(g, F(0.9));
	uint32_t v0 = geometry_row(g, F(0.9 * g->half_height)), v1 = geometry_row(g, -F(0.9 * g->half_height));
	check_dithered(vol, 0, u0, u1, v0, v1, d.rgb);
	double area = (double)(u1 - u0 + 1) * (v1 - v0 + 1);
	double frac = rtest_count_image(vol, 0, 0) / area;
	CHECK_MSG(fabs(frac - value / 255.0) < 0.02, "value %u lights %.4f", value, frac);
	if (value == 0)
		CHECK(rtest_count_image(vol, 0, 0) == 0);
	if (value == 255)
		CHECK(rtest_count_image(vol, 0, 0) == (uint64_t)area);
	volume_destroy(vol);
	rtest_mesh_free(&m);
}

/* Two overlapping walls: per channel MAX, and drawing a mesh twice (shared
 * edges, overdraw) is the same as drawing it once. */
static void check_max(const struct geometry *g)
{
	struct rtest_mesh a = { 0 }, b = { 0 };
	rtest_wall(&a, 0.8, 0.5);
	rtest_wall(&b, 0.4, 0.8);
	struct scene_draw d[3] = { rtest_draw(SCENE_TRIANGLES, &a, 200, 30, 90),
				   rtest_draw(SCENE_TRIANGLES, &b, 100, 180, 90),
				   rtest_draw(SCENE_TRIANGLES, &a, 200, 30, 90) };
	struct volume *vol = rtest_render(g, d, 2, 1);
	uint8_t both[3] = { 200, 180, 90 };
	uint32_t u0 = geometry_column(g, -F(0.4)), u1 = geometry_column(g, F(0.4));
	uint32_t v0 = geometry_row(g, F(0.5)), v1 = geometry_row(g, -F(0.5));
	check_dithered(vol, 0, u0, u1, v0, v1, both);
	/* Left of the narrow wall only the wide one's colour. */
	check_dithered(vol, 0, geometry_column(g, -F(0.8)), u0 - 2, v0, v1, d[0].rgb);
	struct volume *twice = rtest_render(g, d, 3, 1);
	CHECK(rtest_same(vol, twice));
	volume_destroy(twice);
	volume_destroy(vol);
	rtest_mesh_free(&a);
	rtest_mesh_free(&b);
}

/* Not mirrored, images 0 and N/2 see the same wall: each dithers by its own
 * phase, and re-rendering dithers the same way. */
static void check_phases(const struct geometry *g)
{
	struct rtest_mesh m = { 0 };
	rtest_wall(&m, 0.6, 0.6);
	struct scene_draw d = rtest_draw(SCENE_TRIANGLES, &m, 128, 128, 128);
	struct volume *a = rtest_render(g, &d, 1, 1), *b = rtest_render(g, &d, 1, 3);
	uint32_t half = g->images_per_rev / 2;
	uint32_t u0 = geometry_column(g, -F(0.6)), u1 = geometry_column(g, F(0.6));
	uint32_t v0 = geometry_row(g, F(0.6)), v1 = geometry_row(g, -F(0.6));
	check_dithered(a, 0, u0, u1, v0, v1, d.rgb);
	check_dithered(a, half, u0, u1, v0, v1, d.rgb);
	bool differ = false;
	for (uint32_t v = v0; v <= v1; v++)
		for (uint32_t u = u0; u <= u1; u++)
			differ |= rtest_lit(a, 0, u, v, 0) != rtest_lit(a, half, u, v, 0);
	CHECK(differ);
	CHECK(rtest_same(a, b));
	volume_destroy(a);
	volume_destroy(b);
	rtest_mesh_free(&m);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	check_threshold_matrix();
	const uint8_t values[] = { 0, 1, 17, 64, 100, 128, 200, 254, 255 };
	for (size_t i = 0; i < sizeof(values); i++) {
		check_uniform(&small, values[i]);
		check_uniform(&odd, values[i]);
	}
	check_max(&small);
	check_phases(&odd);
	return check_done();
}
