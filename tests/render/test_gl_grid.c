/* Grids (scene.h, SCENE_GRID) on the GL renderers (EGL, and OSMesa where
 * the build has it) against the CPU renderer, the reference
 * (docs/rendering.md, "Grids"):
 *
 * 1. Every sample type (u8, u16, i16, f32 with NaN and infinite samples,
 *    RGBA8), nearest and trilinear, through the draw's colour and through
 *    a lookup table, placed upright (scaled, turned about the axis, moved)
 *    and tilted (a general affine transform), at the small profile
 *    (mirrored), at odd sizes (rtest_odd(): unmirrored, h != 1) and in the
 *    even and uniform brightness models: every bit (image, pixel, channel)
 *    where GL and the CPU differ must lie within one voxel of a transfer
 *    boundary: some point within one voxel of the pixel centre, in voxel
 *    coordinates (each axis -1, 0 or +1, outside the box dark), has a
 *    colour that, weighted and dithered as at that pixel, gives GL's bit.
 *    And they differ rarely: in at most MAX_DIFFER of the bits the CPU
 *    lights (float against double near the boundaries).
 * 2. Two grids overlapping in one scene combine by MAX (the same rule per
 *    draw), and the naive pipeline draws grids too.
 * 3. Textures kept between renders: the same scene again gives the same
 *    volume; a grid known by no id (0) whose data pointer changes, and a
 *    grid whose samples change in place under a new id, are drawn anew; a
 *    grid that leaves the scene and comes back is drawn again.
 * 4. The budget: grids beyond render_gl_options.max_grid_bytes fail the
 *    render with -EFBIG under no_fallback, and otherwise render that volume
 *    on the CPU renderer (its volume exactly), the next scene on GL.
 * 5. What grid.c lights nothing of lights nothing on GL either: no grid,
 *    no data, a singular or non-finite transform. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "check.h"
#include "grid.h"
#include "render_cpu.h"
#include "render_gl.h"
#include "rtest.h"

/* Differing bits, as a share of the bits the CPU lights. */
#define MAX_DIFFER 0.002

/* The daemon numbers its grids (scene_draw.grid_id); so do these tests,
 * since their grids come and go at addresses malloc may give again. */
static uint64_t next_id;

/* A smooth field in 0..1 over the grid: a blob off centre with ripples,
 * so that thresholds and windows cut it along curved surfaces. */
static double field(const uint32_t n[3], uint32_t i, uint32_t j, uint32_t k)
{
	double x = (i + 0.5) / n[0] * 2 - 1, y = (j + 0.5) / n[1] * 2 - 1, z = (k + 0.5) / n[2] * 2 - 1;
	double r = sqrt((x - 0.1) * (x - 0.1) + y * y + (z + 0.15) * (z + 0.15));
	double v = 1.15 - 1.2 * r + 0.2 * sin(5 * x) * cos(4 * y + z);
	return v < 0 ? 0 : v > 1 ? 1 : v;
}

struct tgrid {
	struct scene_grid grid;
	void *data;
	uint64_t id;
};

static const char *type_name(uint32_t t)
{
	static const char *const names[] = { "?", "u8", "u16", "i16", "f32", "rgba8" };
	return t < 6 ? names[t] : "?";
}

/* A grid of type t and size n, spacing sp, filled from field(). */
static void make_grid(struct tgrid *tg, uint32_t type, const uint32_t n[3], const float sp[3])
{
	size_t count = (size_t)n[0] * n[1] * n[2], bytes = type == SCENE_GRID_U8 ? 1 : type <= SCENE_GRID_I16 ? 2 : 4;
	uint8_t *data = malloc(count * bytes);
	CHECK(data);
	for (uint32_t k = 0; k < n[2]; k++)
		for (uint32_t i = 0; i < n[0]; i++)
			for (uint32_t j = 0; j < n[1]; j++) {
				size_t at = ((size_t)k * n[0] + i) * n[1] + j;
				double f = field(n, i, j, k);
				switch (type) {
				case SCENE_GRID_U8:
					data[at] = (uint8_t)lround(255 * f);
					break;
				case SCENE_GRID_U16:
					((uint16_t *)data)[at] = (uint16_t)lround(65535 * f);
					break;
				case SCENE_GRID_I16:
					((int16_t *)data)[at] = (int16_t)lround(-1000 + 2000 * f);
					break;
				case SCENE_GRID_F32:
					((float *)data)[at] = (float)f;
					break;
				case SCENE_GRID_RGBA8: {
					uint8_t *p = data + 4 * at;
					p[0] = (uint8_t)(255 * i / (n[0] - 1));
					p[1] = (uint8_t)(255 * j / (n[1] - 1));
					p[2] = (uint8_t)(255 - 255 * k / (n[2] - 1));
					p[3] = (uint8_t)lround(255 * f);
					break;
				}
				}
			}
	if (type == SCENE_GRID_F32) { /* not numbers and infinities inside the blob: dark, or full */
		float *v = (float *)data;
		size_t mid = ((size_t)(n[2] / 2) * n[0] + n[0] / 2) * n[1] + n[1] / 2;
		v[mid] = NAN;
		v[mid + 2] = INFINITY;
		v[mid + 2 * n[1]] = -INFINITY;
		v[mid - 3 * n[1] + 1] = NAN;
	}
	tg->data = data;
	tg->grid = (struct scene_grid){ type, { n[0], n[1], n[2] }, { sp[0], sp[1], sp[2] }, data, NULL };
	tg->id = ++next_id;
}

/* The transfer for type t: threshold and window over the field's range
 * (RGBA8: on alpha). */
static struct scene_transfer transfer_for(uint32_t type, bool trilinear)
{
	struct scene_transfer tf = { .sampling = trilinear ? SCENE_TRILINEAR : SCENE_NEAREST };
	double scale = type == SCENE_GRID_U16 ? 65535 : type == SCENE_GRID_F32 ? 1 : 255;
	double base = type == SCENE_GRID_I16 ? -1000 : 0;
	if (type == SCENE_GRID_I16)
		scale = 2000;
	tf.threshold = (float)(base + 0.3 * scale);
	tf.lo = (float)(base + 0.25 * scale);
	tf.hi = (float)(base + 0.9 * scale);
	return tf;
}

/* Lookup tables: a few colours, dark at the start, one black entry inside
 * (dark too). */
static const uint8_t lut5[5 * 3] = { 0, 0, 0, 40, 200, 90, 0, 0, 0, 255, 128, 0, 255, 255, 255 };

static void upright(float m[16], double a, const struct scene_grid *g)
{
	/* Scaled to about 1.2 across, turned by a about y, centred near the axis. */
	double c = cos(a), s = sin(a), sc = 1.2 / (g->n[0] * g->spacing[0]);
	double half[3] = { g->n[0] * g->spacing[0] / 2 * sc, g->n[1] * g->spacing[1] / 2 * sc * 0.7,
			   g->n[2] * g->spacing[2] / 2 * sc };
	double t[3] = { 0.07, -0.04, -0.05 };
	/* p' = R (S p) + t - R half */
	float r[16] = { (float)(c * sc),
			0,
			(float)(s * sc),
			0,
			0,
			(float)(sc * 0.7),
			0,
			0,
			(float)(-s * sc),
			0,
			(float)(c * sc),
			0,
			0,
			0,
			0,
			1 };
	r[12] = (float)(t[0] - (c * half[0] - s * half[2]));
	r[13] = (float)(t[1] - half[1]);
	r[14] = (float)(t[2] - (s * half[0] + c * half[2]));
	memcpy(m, r, sizeof(r));
}

static void tilted(float m[16], double a, const struct scene_grid *g)
{
	double c = cos(a), s = sin(a), sc = 1.1 / (g->n[0] * g->spacing[0]);
	double l[9] = { c * sc, 0.12 * sc, s * sc, 0.06 * sc, 0.8 * sc, -0.1 * sc, -s * sc, 0.09 * sc, c * sc };
	float r[16] = { (float)l[0], (float)l[1], (float)l[2], 0, (float)l[3], (float)l[4], (float)l[5], 0,
			(float)l[6], (float)l[7], (float)l[8], 0, 0,           0,           0,           1 };
	double half[3] = { g->n[0] * g->spacing[0] / 2, g->n[1] * g->spacing[1] / 2, g->n[2] * g->spacing[2] / 2 };
	for (int row = 0; row < 3; row++)
		r[12 + row] = (float)(-0.03 * row - (r[row] * half[0] + r[4 + row] * half[1] + r[8 + row] * half[2]));
	memcpy(m, r, sizeof(r));
}

static struct scene_draw grid_draw(const struct tgrid *tg, const float m[16], struct scene_transfer tf,
				   const uint8_t rgb[3])
{
	struct scene_draw d = { .prim = SCENE_GRID, .grid = &tg->grid, .transfer = tf, .grid_id = tg->id };
	memcpy(d.rgb, rgb, 3);
	memcpy(d.transform, m, sizeof(d.transform));
	return d;
}

static struct volume *render_with(struct renderer *r, const struct scene_draw *d, uint32_t n)
{
	struct scene sc = { .draw_count = n, .draws = d };
	struct volume *vol = volume_create(&r->geom);
	CHECK(vol);
	int e = render_volume(r, &sc, vol);
	CHECK_MSG(e == 0, "%s: render failed: %s", r->impl->name, strerror(-e));
	return vol;
}

/* What a channel of draw d may show at the pixel: whether a point within
 * one voxel of the pixel centre f gives it lit (any), dark (any), with
 * thr the pixel's threshold and m the brightness map. */
struct reach {
	bool lit[3], dark[3];
};

static void reach_of(const struct scene_draw *d, const struct brightness_map *m, uint32_t u, const double f[3],
		     uint8_t thr, struct reach *out)
{
	const struct scene_grid *g = d->grid;
	memset(out, 0, sizeof(*out));
	for (int dz = -1; dz <= 1; dz++)
		for (int dy = -1; dy <= 1; dy++)
			for (int dx = -1; dx <= 1; dx++) {
				double p[3] = { f[0] + dx, f[1] + dy, f[2] + dz };
				uint8_t rgb[3] = { 0, 0, 0 };
				bool inside = true;
				for (int a = 0; a < 3; a++)
					inside &= p[a] >= -0.5 && p[a] < g->n[a] - 0.5;
				if (inside && grid_sample(d, p, rgb) && brightness_active(m)) {
					struct brightness_weight w = { m->rate, m->wall, 1.0f };
					for (int c = 0; c < 3; c++)
						rgb[c] = brightness_apply(m, &w, u, rgb[c]);
				}
				for (int c = 0; c < 3; c++) {
					out->lit[c] |= rgb[c] > thr;
					out->dark[c] |= !(rgb[c] > thr);
				}
			}
}

/* Compares gl with the CPU's cpu for the draws d (each a grid): returns
 * the differing bits; a bit that no point within one voxel explains fails
 * the test. lit: the CPU's lit bits. */
static uint64_t compare(const char *what, const struct geometry *g, const struct scene_draw *d, uint32_t n,
			const struct volume *cpu, const struct volume *gl, uint64_t *lit)
{
	struct brightness_map m;
	CHECK(brightness_map_init(&m, g) == 0);
	struct grid_job jobs[4];
	bool ok[4];
	CHECK(n <= 4);
	for (uint32_t i = 0; i < n; i++)
		ok[i] = grid_prepare(&jobs[i], &d[i]);
	uint64_t differ = 0;
	*lit = 0;
	double h = g->half_height;
	for (uint32_t k = 0; k < cpu->image_count; k++) {
		double th = geometry_image_angle(g, k), cx = cos(th), cz = sin(th);
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				bool a[3], b[3], any = false;
				for (int c = 0; c < 3; c++) {
					a[c] = rtest_lit(cpu, k, u, v, c);
					b[c] = rtest_lit(gl, k, u, v, c);
					*lit += a[c];
					any |= a[c] != b[c];
				}
				if (!any)
					continue;
				/* Per channel: GL lit is explained when some draw reaches
				 * lit, GL dark when every draw reaches dark (MAX). */
				double s = (u + 0.5) * 2.0 / g->width - 1.0, y = h - (v + 0.5) * 2.0 * h / g->height;
				double p[3] = { s * cx, y, s * cz };
				uint8_t thr = brightness_threshold(&m, k, u, v);
				bool can_lit[3] = { false, false, false }, can_dark[3] = { true, true, true };
				for (uint32_t i = 0; i < n; i++) {
					struct reach r = { { false }, { true, true, true } };
					if (ok[i]) {
						double f[3];
						for (int ax = 0; ax < 3; ax++)
							f[ax] = jobs[i].off[ax] + jobs[i].lin[ax][0] * p[0] +
								jobs[i].lin[ax][1] * p[1] + jobs[i].lin[ax][2] * p[2];
						reach_of(&d[i], &m, u, f, thr, &r);
					}
					for (int c = 0; c < 3; c++) {
						can_lit[c] |= r.lit[c];
						can_dark[c] &= r.dark[c];
					}
				}
				for (int c = 0; c < 3; c++) {
					if (a[c] == b[c])
						continue;
					differ++;
					CHECK_MSG(b[c] ? can_lit[c] : can_dark[c],
						  "%s: image %u pixel (%u, %u) channel %d: GL %s, the CPU %s, and no "
						  "point "
						  "within a voxel gives GL's",
						  what, k, u, v, c, b[c] ? "lit" : "dark", a[c] ? "lit" : "dark");
				}
			}
	}
	brightness_map_finish(&m);
	return differ;
}

/* Renders draws d on gl and the CPU and compares (1.); returns the share
 * of differing bits, printed. */
static void check_draws(const char *what, struct renderer *gl, struct renderer *cpu, const struct scene_draw *d,
			uint32_t n)
{
	struct volume *want = render_with(cpu, d, n), *got = render_with(gl, d, n);
	CHECK_MSG(gl->stats.engine == RENDER_ENGINE_GL, "%s: not drawn on GL", what);
	CHECK_MSG(rtest_padding_clear(got), "%s: padding bits set", what);
	uint64_t lit, differ = compare(what, &gl->geom, d, n, want, got, &lit);
	CHECK_MSG(lit > 1000, "%s: the CPU lights only %llu bits", what, (unsigned long long)lit);
	double share = (double)differ / (double)lit;
	printf("  %-44s %8llu bits lit, %5llu differ (%.3f%%), all within a voxel of a boundary\n", what,
	       (unsigned long long)lit, (unsigned long long)differ, 100 * share);
	CHECK_MSG(share <= MAX_DIFFER, "%s: %.3f%% of the bits differ (at most %.3f%%)", what, 100 * share,
		  100 * MAX_DIFFER);
	volume_destroy(want);
	volume_destroy(got);
}

static struct renderer *gl_create(const struct geometry *g, const char *backend, bool naive, uint64_t budget,
				  bool no_fallback)
{
	struct render_gl_options o = { .backend = backend,
				       .threads = 2,
				       .naive = naive,
				       .no_fallback = no_fallback,
				       .max_grid_bytes = budget };
	struct renderer *r = render_gl_create(g, &o);
	CHECK_MSG(r, "%s: render_gl_create failed: %s", backend, strerror(errno));
	return r;
}

static const uint32_t sizes[3] = { 13, 17, 11 };
static const float spacing[3] = { 0.1f, 0.09f, 0.12f };

/* 1. Every type, sampling, placement, with and without a table. */
static void check_types(const char *gname, const struct geometry *g, const char *backend, bool all)
{
	struct renderer *gl = gl_create(g, backend, false, 0, true), *cpu = render_cpu_create(g, 2);
	CHECK(cpu);
	static const uint8_t white[3] = { 255, 255, 255 }, tint[3] = { 200, 120, 255 };
	for (uint32_t type = SCENE_GRID_U8; type <= SCENE_GRID_RGBA8; type++) {
		struct tgrid tg;
		make_grid(&tg, type, sizes, spacing);
		for (int place = 0; place < 2; place++)
			for (int tri = 0; tri < 2; tri++)
				for (int lut = 0; lut < (type == SCENE_GRID_RGBA8 ? 1 : 2); lut++) {
					/* The brightness models: one case each is enough. */
					if (!all && (lut || place))
						continue;
					float m[16];
					if (place)
						tilted(m, 0.6 + type, &tg.grid);
					else
						upright(m, 0.4 * type, &tg.grid);
					struct scene_transfer tf = transfer_for(type, tri);
					if (lut) {
						tf.lut = lut5;
						tf.lut_count = 5;
					}
					struct scene_draw d = grid_draw(&tg, m, tf, lut || place ? white : tint);
					char what[96];
					snprintf(what, sizeof(what), "%s %s %s %s%s", gname, type_name(type),
						 place ? "tilted" : "upright", tri ? "trilinear" : "nearest",
						 lut ? " lut" : "");
					check_draws(what, gl, cpu, &d, 1);
				}
		free(tg.data);
	}
	render_destroy(gl);
	render_destroy(cpu);
}

/* 2. Two grids overlapping (MAX), a lookup table on one; the naive
 * pipeline. */
static void check_two(const char *gname, const struct geometry *g, const char *backend)
{
	struct renderer *cpu = render_cpu_create(g, 2);
	CHECK(cpu);
	struct tgrid a, b;
	static const uint32_t nb[3] = { 9, 12, 10 };
	static const float sb[3] = { 0.07f, 0.1f, 0.08f };
	make_grid(&a, SCENE_GRID_I16, sizes, spacing);
	make_grid(&b, SCENE_GRID_F32, nb, sb);
	float ma[16], mb[16];
	upright(ma, 0.3, &a.grid);
	tilted(mb, 1.9, &b.grid);
	struct scene_transfer ta = transfer_for(SCENE_GRID_I16, true), tb = transfer_for(SCENE_GRID_F32, false);
	tb.lut = lut5;
	tb.lut_count = 5;
	static const uint8_t rgb[3] = { 90, 255, 160 };
	struct scene_draw d[2] = { grid_draw(&a, ma, ta, rgb), grid_draw(&b, mb, tb, rgb) };
	for (int naive = 0; naive < 2; naive++) {
		struct renderer *gl = gl_create(g, backend, naive, 0, true);
		char what[96];
		snprintf(what, sizeof(what), "%s two grids (MAX)%s", gname, naive ? ", naive" : "");
		check_draws(what, gl, cpu, d, 2);
		render_destroy(gl);
	}
	free(a.data);
	free(b.data);
	render_destroy(cpu);
}

static bool same_as_cpu(struct renderer *gl, struct renderer *cpu, const struct scene_draw *d, uint32_t n,
			const char *what)
{
	struct volume *want = render_with(cpu, d, n), *got = render_with(gl, d, n);
	uint64_t lit, differ = compare(what, &gl->geom, d, n, want, got, &lit);
	bool ok = (double)differ <= MAX_DIFFER * (double)lit && lit > 1000;
	volume_destroy(want);
	volume_destroy(got);
	return ok;
}

/* 3. Textures kept, and drawn anew when the grid changes. */
static void check_reuse(const struct geometry *g, const char *backend)
{
	struct renderer *gl = gl_create(g, backend, false, 0, true), *cpu = render_cpu_create(g, 2);
	CHECK(cpu);
	struct tgrid tg, other;
	make_grid(&tg, SCENE_GRID_U8, sizes, spacing);
	make_grid(&other, SCENE_GRID_U8, sizes, spacing);
	float m[16];
	upright(m, 0.2, &tg.grid);
	static const uint8_t white[3] = { 255, 255, 255 };
	struct scene_draw d = grid_draw(&tg, m, transfer_for(SCENE_GRID_U8, false), white);
	struct volume *first = render_with(gl, &d, 1), *again = render_with(gl, &d, 1);
	CHECK_MSG(rtest_same(first, again), "%s: the same scene twice differs", backend);
	/* Known by address (id 0): new data at a new address. */
	uint8_t *v = other.data;
	for (size_t i = 0; i < (size_t)sizes[0] * sizes[1] * sizes[2]; i++)
		v[i] = (uint8_t)(255 - v[i]);
	d.grid_id = 0;
	struct volume *by_address = render_with(gl, &d, 1);
	CHECK(rtest_same(first, by_address));
	tg.grid.data = other.data;
	CHECK_MSG(same_as_cpu(gl, cpu, &d, 1, "reuse"), "%s: new data at a new address not drawn", backend);
	/* Known by id: new samples in place under a new id. */
	tg.grid.data = tg.data;
	memcpy(tg.data, other.data, (size_t)sizes[0] * sizes[1] * sizes[2]);
	d.grid_id = ++next_id;
	CHECK_MSG(same_as_cpu(gl, cpu, &d, 1, "reuse"), "%s: new samples under a new id not drawn", backend);
	/* Gone from one scene, back in the next. */
	struct volume *none = render_with(gl, NULL, 0);
	CHECK(rtest_count(none, 0) == 0);
	CHECK_MSG(same_as_cpu(gl, cpu, &d, 1, "reuse"), "%s: a grid back in the scene not drawn", backend);
	printf("  textures kept for the same scene; a new address, new samples under a new id, a grid that comes "
	       "back: drawn anew\n");
	volume_destroy(first);
	volume_destroy(again);
	volume_destroy(by_address);
	volume_destroy(none);
	free(tg.data);
	free(other.data);
	render_destroy(gl);
	render_destroy(cpu);
}

/* 4. The budget, and 5. grids that light nothing. */
static void check_limits(const struct geometry *g, const char *backend)
{
	struct renderer *cpu = render_cpu_create(g, 2);
	CHECK(cpu);
	struct tgrid tg;
	make_grid(&tg, SCENE_GRID_I16, sizes, spacing);
	uint64_t bytes = (uint64_t)sizes[0] * sizes[1] * sizes[2] * 2;
	float m[16];
	upright(m, 0.9, &tg.grid);
	static const uint8_t white[3] = { 255, 255, 255 };
	struct scene_draw d = grid_draw(&tg, m, transfer_for(SCENE_GRID_I16, true), white);
	struct scene sc = { .draw_count = 1, .draws = &d };
	struct renderer *strict = gl_create(g, backend, false, bytes - 1, true);
	struct volume *vol = volume_create(g);
	CHECK(vol);
	CHECK_EQ(render_volume(strict, &sc, vol), -EFBIG);
	render_destroy(strict);
	struct renderer *gl = gl_create(g, backend, false, bytes - 1, false);
	struct volume *want = render_with(cpu, &d, 1), *got = render_with(gl, &d, 1);
	CHECK_MSG(gl->stats.engine == RENDER_ENGINE_CPU, "%s: a grid over the budget not on the CPU", backend);
	CHECK_MSG(rtest_same(want, got), "%s: over the budget, not the CPU renderer's volume", backend);
	/* Half the grid fits: the next scene is drawn on GL again. */
	static const uint32_t half[3] = { 13, 8, 11 };
	struct tgrid small;
	make_grid(&small, SCENE_GRID_I16, half, spacing);
	d.grid = &small.grid;
	d.grid_id = small.id;
	CHECK(same_as_cpu(gl, cpu, &d, 1, "budget"));
	CHECK_MSG(gl->stats.engine == RENDER_ENGINE_GL, "%s: a grid within the budget not on GL", backend);
	render_destroy(gl);
	printf("  over max_grid_bytes: -EFBIG without fallback, else that volume on the CPU, the next on GL\n");

	/* 5. */
	gl = gl_create(g, backend, false, 0, true);
	struct scene_draw none[4] = { d, d, d, d };
	none[0].grid = NULL;
	struct scene_grid empty = small.grid;
	empty.data = NULL;
	none[1].grid = &empty;
	none[1].grid_id = ++next_id;
	memset(none[2].transform, 0, 12 * sizeof(float)); /* singular */
	none[3].transform[5] = NAN;
	struct volume *dark = render_with(gl, none, 4);
	CHECK_MSG(rtest_count(dark, 0) + rtest_count(dark, 1) + rtest_count(dark, 2) == 0,
		  "%s: a grid that lights nothing lit something", backend);
	printf("  no grid, no samples, a singular or NaN transform: nothing lit\n");
	volume_destroy(dark);
	volume_destroy(vol);
	volume_destroy(want);
	volume_destroy(got);
	free(tg.data);
	free(small.data);
	render_destroy(gl);
	render_destroy(cpu);
}

int main(void)
{
	setvbuf(stdout, NULL, _IOLBF, 0);
	static const char *const backends[] = { "egl", "osmesa" };
	struct geometry small = rtest_small(), odd = rtest_odd();
	struct geometry even = small, uniform = odd, odd_even = odd;
	even.brightness = odd_even.brightness = GEOMETRY_BRIGHTNESS_EVEN;
	uniform.brightness = GEOMETRY_BRIGHTNESS_UNIFORM;
	for (int i = 0; i < 2; i++) {
		const char *b = backends[i];
		if (!rtest_have_gl(&small, b))
			continue;
		printf("%s:\n", b);
		check_types("small", &small, b, true);
		check_types("odd", &odd, b, true);
		check_types("small even", &even, b, false);
		check_types("odd uniform", &uniform, b, false);
		check_two("small", &small, b);
		check_two("odd even", &odd_even, b);
		check_reuse(&small, b);
		check_limits(&small, b);
	}
	return check_done();
}
