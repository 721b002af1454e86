/* Grids (scene.h, SCENE_GRID) on the CPU renderer, against expectations
 * computed here from docs/design.md section 3 with a transform inverted
 * independently (Gauss-Jordan), never with grid.c's:
 *
 * 1. A solid box, placed by a general affine transform (turned, tilted,
 *    sheared, moved), lights exactly the pixels of each image whose
 *    centres lie in the box, in both lobes (pixels within 1e-9 of a face
 *    are not judged).
 * 2. A sphere sampled from a 32^3 grid: nearest sampling lights every
 *    pixel whose centre is inside the analytic sphere by more than half a
 *    voxel diagonal and none outside it by more (holes and fat: 0);
 *    trilinear differs from nearest only within a voxel of the surface.
 * 3. The transfer: threshold, window, lookup table, RGBA8, NaN, and the
 *    five sample types, through grid_sample().
 * 4. Turns: a turned grid draw lights in image k what the unturned one
 *    lights in geometry_turn_source()'s image, mirrored as it says.
 * 5. Threads: 1 and 3 give the same volume; a singular transform lights
 *    nothing; the even brightness model thins only inside r0.
 * 7. The upright paths (the grid's up axis the display's): column by
 *    column (dark bricks skipped by their maxima) and by tiles in every
 *    vector variant this machine runs (grid_tiles.h), each light the same
 *    canvas as the reference loop, byte for byte, for every sample type,
 *    both samplings, thresholds that skip most bricks or none, a lookup
 *    table, unweighted and under the even and uniform brightness models,
 *    mirrored too.
 * 6. GL (EGL, OSMesa where a context can be made): a scene with a grid
 *    is drawn on GL (3-D textures), here the CPU renderer's volume bit for
 *    bit (test_gl_grid.c compares the two in depth).
 *
 * On the small profile (mirrored) and rtest_odd() (unmirrored). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "grid.h"
#include "grid_tiles.h"
#include "render_gl.h"
#include "rtest.h"

/* The model point that pixel (u, v) of volume image k shows. */
static void pixel_model(const struct geometry *g, const double inv[16], uint32_t k, uint32_t u, uint32_t v,
			double out[3])
{
	double th = 2.0 * M_PI * k / g->images_per_rev;
	double s = (u + 0.5) * 2.0 / g->width - 1.0, y = g->half_height - (v + 0.5) * 2.0 * g->half_height / g->height;
	double p[3] = { s * cos(th), y, s * sin(th) };
	for (int r = 0; r < 3; r++)
		out[r] = inv[12 + r] + inv[r] * p[0] + inv[4 + r] * p[1] + inv[8 + r] * p[2];
}

static uint32_t images_of(const struct geometry *g)
{
	return g->mirrored ? g->images_per_rev / 2 : g->images_per_rev;
}

/* A draw of grid gr with transform m, white, window 0..1 (every value of
 * at least the threshold 0.5 saturated). */
static struct scene_draw grid_draw(const struct scene_grid *gr, const float m[16])
{
	struct scene_draw d = {
		.prim = SCENE_GRID,
		.rgb = { 255, 255, 255 },
		.grid = gr,
		.transfer = { .threshold = 0.5f, .lo = 0.0f, .hi = 1.0f },
	};
	memcpy(d.transform, m, sizeof(d.transform));
	return d;
}

/* A general affine placement: turned about y by a, tilted, sheared,
 * scaled, moved. */
static void placement(float m[16], double a)
{
	double c = cos(a), s = sin(a);
	const float t[16] = {
		(float)c,  0.1f,  (float)s, 0, 0.05f,  0.9f,   -0.08f, 0,
		(float)-s, 0.07f, (float)c, 0, -0.31f, -0.27f, -0.22f, 1,
	};
	memcpy(m, t, sizeof(t));
}

/* 1. */
static void check_box(const char *name, const struct geometry *g)
{
	static uint8_t data[7 * 5 * 6];
	memset(data, 1, sizeof(data));
	struct scene_grid gr = { SCENE_GRID_U8, { 7, 5, 6 }, { 0.09f, 0.11f, 0.1f }, data, NULL };
	float m[16];
	placement(m, 0.7);
	struct scene_draw d = grid_draw(&gr, m);
	struct volume *vol = rtest_render(g, &d, 1, 2);
	double inv[16];
	rtest_invert(m, inv);
	uint64_t lit = 0, ambiguous = 0;
	for (uint32_t k = 0; k < images_of(g); k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				double p[3];
				pixel_model(g, inv, k, u, v, p);
				bool in = true, edge = false;
				for (int a = 0; a < 3; a++) {
					double hi = gr.n[a] * (double)gr.spacing[a];
					in &= p[a] >= 0.0 && p[a] < hi;
					edge |= fabs(p[a]) < 1e-9 || fabs(p[a] - hi) < 1e-9;
				}
				if (edge) {
					ambiguous++;
					continue;
				}
				bool got = rtest_lit(vol, k, u, v, 0);
				CHECK_MSG(got == in, "%s: image %u pixel (%u, %u): %s", name, k, u, v,
					  in ? "inside the box, dark" : "outside, lit");
				lit += got;
			}
	CHECK(lit > 1000);
	printf("%s: a solid box placed by a general affine transform lights exactly the pixels whose centres lie "
	       "in it (%llu lit, %llu on a face not judged)\n",
	       name, (unsigned long long)lit, (unsigned long long)ambiguous);
	volume_destroy(vol);
}

/* 2. */
static void check_sphere(const char *name, const struct geometry *g)
{
	enum { N = 32 };
	static float data[N * N * N];
	const double r = 0.4; /* in the grid's unit cube */
	for (uint32_t k = 0; k < N; k++)
		for (uint32_t i = 0; i < N; i++)
			for (uint32_t j = 0; j < N; j++) {
				double x = (i + 0.5) / N - 0.5, y = (j + 0.5) / N - 0.5, z = (k + 0.5) / N - 0.5;
				data[(k * N + i) * N + j] = x * x + y * y + z * z <= r * r ? 1.0f : 0.0f;
			}
	struct scene_grid gr = { SCENE_GRID_F32, { N, N, N }, { 1.0f / N, 1.0f / N, 1.0f / N }, data, NULL };
	const float scale = 1.5f;
	const float m[16] = { scale, 0, 0, 0, 0, scale, 0, 0, 0, 0, scale, 0, -scale / 2, -scale / 2, -scale / 2, 1 };
	struct scene_draw d = grid_draw(&gr, m);
	struct volume *nearest = rtest_render(g, &d, 1, 2);
	d.transfer.sampling = SCENE_TRILINEAR;
	struct volume *tri = rtest_render(g, &d, 1, 2);
	double voxel = scale / N, half_diag = voxel * sqrt(3.0) / 2, R = r * scale;
	uint64_t inside = 0, holes = 0, lit = 0, fat = 0, differ = 0;
	for (uint32_t k = 0; k < images_of(g); k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				double s = (u + 0.5) * 2.0 / g->width - 1.0;
				double y = g->half_height - (v + 0.5) * 2.0 * g->half_height / g->height;
				double dist = hypot(s, y) - R;
				bool a = rtest_lit(nearest, k, u, v, 0), b = rtest_lit(tri, k, u, v, 0);
				inside += dist < -half_diag;
				holes += dist < -half_diag && !a;
				lit += a;
				fat += a && dist > half_diag;
				if (a != b) {
					differ++;
					CHECK_MSG(fabs(dist) <= 2 * half_diag,
						  "%s: trilinear and nearest differ %.3f voxels "
						  "from the surface",
						  name, dist / voxel);
				}
			}
	CHECK(inside > 1000);
	CHECK_MSG(holes == 0 && fat == 0, "%s: sphere holes %llu of %llu, fat %llu of %llu", name,
		  (unsigned long long)holes, (unsigned long long)inside, (unsigned long long)fat,
		  (unsigned long long)lit);
	printf("%s: a 32^3 sphere, nearest: 0 holes in %llu pixels inside, 0 fat in %llu lit (half a voxel "
	       "diagonal either side); trilinear differs at %llu pixels, all within a voxel of the surface\n",
	       name, (unsigned long long)inside, (unsigned long long)lit, (unsigned long long)differ);
	volume_destroy(nearest);
	volume_destroy(tri);
}

/* 3. The colour of a one-sample grid of type t holding the bytes at p. */
static bool colour_of(uint32_t t, const void *p, const struct scene_transfer *tf, const uint8_t rgb[3], uint8_t out[3])
{
	struct scene_grid gr = { t, { 1, 1, 1 }, { 1, 1, 1 }, p, NULL };
	struct scene_draw d = { .prim = SCENE_GRID, .grid = &gr, .transfer = *tf };
	memcpy(d.rgb, rgb, 3);
	const double f[3] = { 0.2, -0.3, 0.1 };
	return grid_sample(&d, f, out);
}

static void check_transfer(void)
{
	const uint8_t rgb[3] = { 200, 100, 50 };
	uint8_t out[3];
	const uint16_t u16 = 300;
	struct scene_transfer tf = { .threshold = 250, .lo = 100, .hi = 500 };
	CHECK(colour_of(SCENE_GRID_U16, &u16, &tf, rgb, out) && out[0] == 100 && out[1] == 50 && out[2] == 25);
	tf.threshold = 301;
	CHECK(!colour_of(SCENE_GRID_U16, &u16, &tf, rgb, out));
	const int16_t i16 = -1000; /* air in Hounsfield units */
	struct scene_transfer ct = { .threshold = -500, .lo = -160, .hi = 240 };
	CHECK(!colour_of(SCENE_GRID_I16, &i16, &ct, rgb, out));
	const int16_t bone = 700;
	CHECK(colour_of(SCENE_GRID_I16, &bone, &ct, rgb, out) && out[0] == 200 && out[1] == 100 && out[2] == 50);
	const float nan = NAN, f32 = 0.25f;
	struct scene_transfer unit = { .threshold = 0.0f, .lo = 0.0f, .hi = 1.0f };
	CHECK(!colour_of(SCENE_GRID_F32, &nan, &unit, rgb, out));
	CHECK(colour_of(SCENE_GRID_F32, &f32, &unit, rgb, out) && out[0] == 50 && out[1] == 25 && out[2] == 13);
	const uint8_t u8 = 128, lut[5 * 3] = { 0, 0, 0, 10, 0, 0, 20, 30, 40, 50, 0, 0, 60, 0, 0 };
	struct scene_transfer table = { .threshold = 1, .lo = 0, .hi = 256, .lut = lut, .lut_count = 5 };
	CHECK(colour_of(SCENE_GRID_U8, &u8, &table, rgb, out) && out[0] == 20 && out[1] == 30 && out[2] == 40);
	const uint8_t rgba[4] = { 100, 200, 50, 128 };
	struct scene_transfer alpha = { .threshold = 128, .lo = 0, .hi = 1 };
	CHECK(colour_of(SCENE_GRID_RGBA8, rgba, &alpha, rgb, out) && out[0] == 50 && out[1] == 100 && out[2] == 25);
	alpha.threshold = 129;
	CHECK(!colour_of(SCENE_GRID_RGBA8, rgba, &alpha, rgb, out));
	printf("transfer: threshold, window, lookup table, RGBA8 and NaN on every sample type\n");
}

/* 4. */
static void check_turn(const char *name, const struct geometry *g)
{
	static uint8_t data[4 * 6 * 3];
	for (size_t i = 0; i < sizeof(data); i++)
		data[i] = (uint8_t)(i % 3 != 0);
	struct scene_grid gr = { SCENE_GRID_U8, { 4, 6, 3 }, { 0.1f, 0.12f, 0.09f }, data, NULL };
	float m[16];
	placement(m, 0.3);
	struct scene_draw d = grid_draw(&gr, m);
	struct volume *plain = rtest_render(g, &d, 1, 2);
	const uint32_t turns[] = { 1, 5, images_of(g) - 1, images_of(g) + 3 };
	for (size_t t = 0; t < sizeof(turns) / sizeof(turns[0]); t++) {
		d.turn = (uint16_t)turns[t];
		struct volume *turned = rtest_render(g, &d, 1, 2);
		for (uint32_t k = 0; k < images_of(g); k++) {
			bool mirror;
			uint32_t src = geometry_turn_source(g, k, turns[t] % g->images_per_rev, &mirror);
			for (uint32_t v = 0; v < g->height; v++)
				for (uint32_t u = 0; u < g->width; u++)
					CHECK_MSG(rtest_lit(turned, k, u, v, 0) ==
							  rtest_lit(plain, src, mirror ? g->width - 1 - u : u, v, 0),
						  "%s: turn %u image %u (%u, %u)", name, turns[t], k, u, v);
		}
		volume_destroy(turned);
	}
	printf("%s: a turned grid lights in image k what the unturned one lights in its source image, mirrored "
	       "where that is shown mirrored\n",
	       name);
	volume_destroy(plain);
}

/* 5. */
static void check_threads_and_models(const char *name, const struct geometry *g)
{
	static uint8_t data[5 * 5 * 5];
	memset(data, 1, sizeof(data));
	struct scene_grid gr = { SCENE_GRID_U8, { 5, 5, 5 }, { 0.2f, 0.2f, 0.2f }, data, NULL };
	float m[16];
	placement(m, 1.1);
	struct scene_draw d = grid_draw(&gr, m);
	struct volume *one = rtest_render(g, &d, 1, 1), *three = rtest_render(g, &d, 1, 3);
	CHECK_MSG(rtest_same(one, three), "%s: 1 and 3 threads differ", name);
	/* A singular transform: nothing, and no failure. */
	struct scene_draw flat = d;
	flat.transform[5] = 0.0f;
	flat.transform[1] = flat.transform[9] = 0.0f;
	struct volume *none = rtest_render(g, &flat, 1, 2);
	CHECK(rtest_count(none, 0) == 0);
	/* Even: inside r0 fewer voxels, beyond it the same. */
	struct geometry ge = *g;
	ge.brightness = GEOMETRY_BRIGHTNESS_EVEN;
	struct volume *even = rtest_render(&ge, &d, 1, 2);
	double r0 = geometry_r0_px(g);
	uint64_t exact_in = 0, even_in = 0;
	for (uint32_t k = 0; k < images_of(g); k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				double r = fabs(u + 0.5 - g->width / 2.0);
				bool a = rtest_lit(one, k, u, v, 0), b = rtest_lit(even, k, u, v, 0);
				if (r > r0 + 1)
					CHECK_MSG(a == b, "%s: even changed a voxel %.1f px out", name, r);
				else {
					exact_in += a;
					even_in += b;
					CHECK(!b || a);
				}
			}
	CHECK(even_in < exact_in);
	printf("%s: 1 and 3 threads give the same volume; a singular transform lights nothing; even thins inside "
	       "r0 only (%llu of %llu voxels kept there)\n",
	       name, (unsigned long long)even_in, (unsigned long long)exact_in);
	volume_destroy(one);
	volume_destroy(three);
	volume_destroy(none);
	volume_destroy(even);
}

/* 6. */
static void check_gl(const char *name, const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2, .no_fallback = true };
	struct renderer *r = render_gl_create(g, &o);
	if (!r) {
		printf("%s %s: no GL renderer here, skipped\n", name, backend);
		return;
	}
	static uint8_t data[3 * 4 * 5];
	memset(data, 1, sizeof(data));
	struct scene_grid gr = { SCENE_GRID_U8, { 3, 4, 5 }, { 0.2f, 0.2f, 0.2f }, data, NULL };
	float m[16];
	placement(m, 0.5);
	struct scene_draw d = grid_draw(&gr, m);
	struct scene sc = { .draw_count = 1, .draws = &d };
	struct volume *vol = volume_create(g), *cpu = rtest_render(g, &d, 1, 2);
	CHECK(vol && render_volume(r, &sc, vol) == 0);
	CHECK_MSG(r->stats.engine == RENDER_ENGINE_GL, "%s %s: a grid not drawn on GL", name, backend);
	CHECK_MSG(rtest_same(vol, cpu), "%s %s: not the CPU renderer's volume", name, backend);
	printf("%s %s: a scene with a grid is drawn on GL, the CPU renderer's volume (more: render-gl-grid)\n", name,
	       backend);
	volume_destroy(vol);
	volume_destroy(cpu);
	render_destroy(r);
}

/* 7. Canvas of image k by the reference loop or the upright path. */
static void draw_canvas(struct section_canvas *c, struct grid_job *job, uint32_t k, bool mirror, bool reference)
{
	size_t tiles = (size_t)c->tiles_x * c->tiles_y;
	memset(c->rgb, 0, tiles * HALFTONE_TILE_BYTES);
	memset(c->rows, 0, tiles * sizeof(*c->rows));
	job->reference = reference;
	grid_draw_image(c, job, k, mirror);
}

/* Every third image of job, mirrored and not: the column path and each
 * tile variant against the reference loop, byte for byte. Returns the
 * canvas rows the reference lit. */
static uint64_t compare_upright(const char *name, const char *what, struct grid_job *job, struct section_canvas *ref,
				struct section_canvas *fast)
{
	const struct geometry *g = &ref->geom;
	size_t tiles = (size_t)ref->tiles_x * ref->tiles_y;
	uint64_t rows = 0;
	for (uint32_t k = 0; k < images_of(g); k += 3)
		for (int mirror = 0; mirror < 2; mirror++) {
			draw_canvas(ref, job, k, mirror, true);
			for (int way = -1; way < 0 || grid_tiles_variant((unsigned)way); way++) {
				const char *path = way < 0 ? "columns" : grid_tiles_variant((unsigned)way);
				job->columns = way < 0;
				CHECK(way < 0 || grid_tiles_use(path));
				draw_canvas(fast, job, k, mirror, false);
				CHECK_MSG(!memcmp(ref->rgb, fast->rgb, tiles * HALFTONE_TILE_BYTES) &&
						  !memcmp(ref->rows, fast->rows, tiles * sizeof(*ref->rows)),
					  "%s: %s image %u%s: the upright path (%s) differs", name, what, k,
					  mirror ? " mirrored" : "", path);
			}
			CHECK(grid_tiles_use(grid_tiles_variant(0)));
			for (size_t i = 0; i < tiles; i++)
				rows += __builtin_popcount(ref->rows[i]);
		}
	return rows;
}

static void check_upright(const char *name, const struct geometry *g)
{
	enum { NX = 9, NY = 75, NZ = 7, S = NX * NY * NZ };
	static uint8_t bytes[S * 4];
	static uint16_t u16[S];
	static int16_t i16[S];
	static float f32[S], brick_max[NX * NZ * 3];
	static const uint8_t lut[15] = { 0, 0, 0, 200, 10, 0, 0, 0, 90, 255, 255, 0, 30, 60, 120 };
	uint32_t seed = 99;
	for (int i = 0; i < S; i++) {
		seed = seed * 1103515245u + 12345u;
		uint32_t r = seed >> 8;
		bytes[4 * i] = (uint8_t)r, bytes[4 * i + 1] = (uint8_t)(r >> 8), bytes[4 * i + 2] = (uint8_t)(r >> 16);
		bytes[4 * i + 3] = (uint8_t)(r >> 3);
		u16[i] = (uint16_t)(r % 60000);
		i16[i] = (int16_t)((int)(r % 3000) - 1000);
		f32[i] = i % 97 == 0 ? NAN : (float)(r % 1000) / 10.0f;
	}
	const struct {
		uint32_t type;
		const void *data;
		float threshold[2], lo, hi; /* a threshold most columns pass, and one few do */
	} kinds[] = {
		{ SCENE_GRID_U8, bytes, { 10, 250 }, 0, 200 },      { SCENE_GRID_U16, u16, { 100, 59000 }, 0, 60000 },
		{ SCENE_GRID_I16, i16, { -900, 1990 }, -160, 240 }, { SCENE_GRID_F32, f32, { 1, 99.9f }, 0, 50 },
		{ SCENE_GRID_RGBA8, bytes, { 10, 250 }, 0, 1 },
	};
	struct section_canvas ref, fast;
	CHECK(section_canvas_init(&ref, g) == 0 && section_canvas_init(&fast, g) == 0);
	uint64_t pixels = 0;
	/* Unweighted, then under the even and uniform brightness models (a
	 * solid grid is weighted as a crossing surface, lane by lane). */
	struct brightness_map maps[3];
	for (int b = 0; b < 3; b++) {
		struct geometry gb = *g;
		gb.brightness = b == 0   ? GEOMETRY_BRIGHTNESS_EXACT
				: b == 1 ? GEOMETRY_BRIGHTNESS_EVEN
					 : GEOMETRY_BRIGHTNESS_UNIFORM;
		CHECK(brightness_map_init(&maps[b], &gb) == 0);
	}
	for (int model = 0; model < 3; model++)
		for (size_t t = 0; t < sizeof(kinds) / sizeof(kinds[0]); t++)
			for (int sampling = 0; sampling < 2; sampling++)
				for (int th = 0; th < 4; th++) { /* thresholds 0 and 1, then with a lut */
					struct scene_grid gr = { kinds[t].type,
								 { NX, NY, NZ },
								 { 0.1f, 0.13f, 0.12f },
								 kinds[t].data,
								 NULL };
					grid_brick_max(&gr, brick_max);
					gr.brick_max = brick_max;
					/* Turned about y, scaled unevenly, moved: upright. */
					double a = 0.4 + t + sampling;
					const float m[16] = {
						(float)(1.1 * cos(a)),
						0,
						(float)(-1.1 * sin(a)),
						0,
						0,
						0.9f,
						0,
						0,
						(float)(0.8 * sin(a)),
						0,
						(float)(0.8 * cos(a)),
						0,
						-0.45f,
						-0.5f,
						-0.35f,
						1
					};
					struct scene_draw d = grid_draw(&gr, m);
					d.transfer = (struct scene_transfer){
						kinds[t].threshold[th & 1], kinds[t].lo,          kinds[t].hi,
						(uint32_t)sampling,         th >= 2 ? lut : NULL, th >= 2 ? 5u : 0u
					};
					struct grid_job job;
					CHECK(grid_prepare(&job, &d) && job.upright && grid_prepare_rows(&job, g) &&
					      job.rows);
					ref.bright = fast.bright = model ? &maps[model] : NULL;
					char what[96];
					snprintf(what, sizeof(what), "model %d type %u sampling %d threshold %g%s",
						 model, kinds[t].type, sampling, (double)kinds[t].threshold[th & 1],
						 th >= 2 ? " lut" : "");
					pixels += compare_upright(name, what, &job, &ref, &fast);
					grid_job_finish(&job);
				}
	section_canvas_finish(&ref);
	section_canvas_finish(&fast);
	for (int b = 0; b < 3; b++)
		brightness_map_finish(&maps[b]);
	CHECK(pixels > 100);
	printf("%s: the upright path lights the reference loop's canvas byte for byte (5 types, both samplings, 2 "
	       "thresholds, a lookup table, 3 brightness models, mirrored too; %llu canvas rows lit)\n",
	       name, (unsigned long long)pixels);
}

int main(void)
{
	setvbuf(stdout, NULL, _IOLBF, 0);
	struct geometry small = rtest_small(), odd = rtest_odd();
	const struct {
		const char *name;
		const struct geometry *g;
	} geoms[] = { { "small", &small }, { "odd", &odd } };
	check_transfer();
	for (int i = 0; i < 2; i++) {
		check_box(geoms[i].name, geoms[i].g);
		check_sphere(geoms[i].name, geoms[i].g);
		check_turn(geoms[i].name, geoms[i].g);
		check_threads_and_models(geoms[i].name, geoms[i].g);
		check_upright(geoms[i].name, geoms[i].g);
		check_gl(geoms[i].name, geoms[i].g, "egl");
		check_gl(geoms[i].name, geoms[i].g, "osmesa");
	}
	return check_done();
}
