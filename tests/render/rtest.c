#include "rtest.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render_gl.h"

struct geometry rtest_small(void)
{
	struct geometry g;
	if (geometry_from_profile("small", &g) < 0)
		abort();
	return g;
}

struct geometry rtest_odd(void)
{
	struct geometry g = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	return g;
}

void rtest_mesh_add(struct rtest_mesh *m, double x, double y, double z)
{
	if (m->count == m->cap) {
		m->cap = m->cap ? 2 * m->cap : 64;
		m->xyz = realloc(m->xyz, (size_t)m->cap * 3 * sizeof(float));
		if (!m->xyz)
			abort();
	}
	float *p = m->xyz + (size_t)m->count * 3;
	p[0] = (float)x;
	p[1] = (float)y;
	p[2] = (float)z;
	m->count++;
}

void rtest_mesh_free(struct rtest_mesh *m)
{
	free(m->xyz);
	memset(m, 0, sizeof(*m));
}

static void sphere_point(double out[3], double r, int i, int j, int slices, int stacks)
{
	double lat = M_PI / 2 - M_PI * j / stacks, lon = 2 * M_PI * i / slices;
	out[0] = r * cos(lat) * cos(lon);
	out[1] = r * sin(lat);
	out[2] = r * cos(lat) * sin(lon);
}

static void add3(struct rtest_mesh *m, const double a[3], const double b[3], const double c[3])
{
	rtest_mesh_add(m, a[0], a[1], a[2]);
	rtest_mesh_add(m, b[0], b[1], b[2]);
	rtest_mesh_add(m, c[0], c[1], c[2]);
}

void rtest_sphere(struct rtest_mesh *m, double r, int slices, int stacks)
{
	for (int j = 0; j < stacks; j++) {
		for (int i = 0; i < slices; i++) {
			double a[3], b[3], c[3], d[3];
			sphere_point(a, r, i, j, slices, stacks);
			sphere_point(b, r, i + 1, j, slices, stacks);
			sphere_point(c, r, i, j + 1, slices, stacks);
			sphere_point(d, r, i + 1, j + 1, slices, stacks);
			if (j > 0)
				add3(m, a, b, d);
			if (j < stacks - 1)
				add3(m, a, d, c);
		}
	}
}

void rtest_disk(struct rtest_mesh *m, double r, double y, int segments)
{
	for (int i = 0; i < segments; i++) {
		double a0 = 2 * M_PI * i / segments, a1 = 2 * M_PI * (i + 1) / segments;
		rtest_mesh_add(m, 0, y, 0);
		rtest_mesh_add(m, r * cos(a0), y, r * sin(a0));
		rtest_mesh_add(m, r * cos(a1), y, r * sin(a1));
	}
}

void rtest_wall(struct rtest_mesh *m, double a, double b)
{
	rtest_mesh_add(m, -a, -b, 0);
	rtest_mesh_add(m, a, -b, 0);
	rtest_mesh_add(m, a, b, 0);
	rtest_mesh_add(m, -a, -b, 0);
	rtest_mesh_add(m, a, b, 0);
	rtest_mesh_add(m, -a, b, 0);
}

/* Pixel targets of rtest_edge_points(): n >= 0 is pixel n from the low
 * edge, -n pixel W - n (or H - n), OUT_LO and OUT_HI lie beyond the image,
 * MID the middle pixel. */
enum { OUT_LO = -1000, OUT_HI = 1000, MID = 2000 };

static double target_s(const struct geometry *g, int u)
{
	uint32_t w = g->width;
	if (u == OUT_LO || u == OUT_HI)
		return u == OUT_LO ? -1.3 : 1.3;
	uint32_t px = u == MID ? w / 2 : u < 0 ? w - (uint32_t)-u : (uint32_t)u;
	return (px + 0.5) * 2.0 / w - 1.0;
}

static double target_y(const struct geometry *g, int v)
{
	uint32_t h = g->height;
	double hh = g->half_height;
	if (v == OUT_LO || v == OUT_HI)
		return v == OUT_LO ? 1.3 * hh : -1.3 * hh;
	uint32_t px = v == MID ? h / 2 : v < 0 ? h - (uint32_t)-v : (uint32_t)v;
	return hh - (px + 0.5) * 2.0 * hh / h;
}

uint32_t rtest_edge_points(const struct geometry *g, struct rtest_mesh *m)
{
	static const int at[][2] = {
		{ 0, 0 },           { -1, 0 },          { 0, -1 },          { -1, -1 }, /* the corners */
		{ OUT_LO, OUT_LO }, { OUT_HI, OUT_HI }, { OUT_LO, OUT_HI }, { OUT_HI, OUT_LO }, { 1, 1 },
		{ 2, -2 },          { -2, 2 },          { 3, -3 },          { -3, 3 },          { 6, 7 },
		{ 7, -8 },          { -7, 8 },          { -8, -7 },         { 8, -9 },          { -9, 6 },
		{ MID, MID },       { MID, 0 },         { 0, MID },         { -1, MID },        { MID, -1 },
	};
	uint32_t n = sizeof(at) / sizeof(at[0]);
	if (n > g->images_per_rev / 2)
		n = g->images_per_rev / 2;
	for (uint32_t j = 0; j < n; j++) {
		double th = geometry_image_angle(g, j), s = target_s(g, at[j][0]);
		rtest_mesh_add(m, s * cos(th), target_y(g, at[j][1]), s * sin(th));
	}
	/* On the axis: azimuth 0 (image 0, and N/2 unmirrored), column W/2. */
	rtest_mesh_add(m, 0, target_y(g, 5), 0);
	return n + 1;
}

/* floor(f) clamped to 0 .. n - 1 (docs/design.md: "both clamped"). */
static uint32_t design_index(double f, uint32_t n)
{
	double i = floor(f);
	return i < 0 ? 0 : i > n - 1 ? n - 1 : (uint32_t)i;
}

/* round(phi / D) mod N, rounding ties away from zero as geometry.c does. */
static uint32_t design_image(const struct geometry *g, double phi)
{
	long n = (long)g->images_per_rev, k = lround(phi / (2 * M_PI / n)) % n;
	return (uint32_t)(k < 0 ? k + n : k);
}

void rtest_point_voxels(const struct geometry *g, const float p[3], struct rtest_voxel out[2])
{
	double phi = atan2(p[2], p[0]), h = g->half_height;
	uint32_t lobes[2] = { design_image(g, phi), design_image(g, phi - M_PI) };
	for (int i = 0; i < 2; i++) {
		uint32_t k = lobes[i] % geometry_images_per_volume(g);
		double th = 2 * M_PI * k / g->images_per_rev;
		double s = p[0] * cos(th) + p[2] * sin(th);
		out[i] = (struct rtest_voxel){ k, design_index((s + 1) / 2 * g->width, g->width),
					       design_index((h - p[1]) / (2 * h) * g->height, g->height) };
	}
}

void rtest_colour(uint32_t i, uint8_t out[3])
{
	out[0] = (uint8_t)(i * 73 + 11);
	out[1] = (uint8_t)(i * 151 + 97);
	out[2] = (uint8_t)(i * 29 + 200);
}

void rtest_saturated(uint32_t i, uint8_t out[3])
{
	for (int c = 0; c < 3; c++)
		out[c] = ((i % 7 + 1) >> c) & 1 ? 255 : 0;
}

void rtest_identity(float t[16])
{
	memset(t, 0, 16 * sizeof(float));
	t[0] = t[5] = t[10] = t[15] = 1.0f;
}

struct scene_draw rtest_draw(enum scene_prim prim, const struct rtest_mesh *m, uint8_t r, uint8_t g, uint8_t b)
{
	struct scene_draw d = { .prim = prim, .count = m->count, .xyz = m->xyz };
	rtest_identity(d.transform);
	d.rgb[0] = r;
	d.rgb[1] = g;
	d.rgb[2] = b;
	return d;
}

struct volume *rtest_render(const struct geometry *g, const struct scene_draw *draws, uint32_t n, unsigned threads)
{
	struct scene s = { .draw_count = n, .draws = draws };
	struct renderer *r = render_cpu_create(g, threads);
	struct volume *vol = volume_create(g);
	if (!r || !vol || render_volume(r, &s, vol) < 0) {
		fprintf(stderr, "rtest_render failed\n");
		abort();
	}
	render_destroy(r);
	return vol;
}

bool rtest_lit(const struct volume *vol, uint32_t k, uint32_t u, uint32_t v, int c)
{
	return volume_pixel(vol, k, u, v, c) != 0;
}

uint64_t rtest_count_image(const struct volume *vol, uint32_t k, int c)
{
	const struct volume_image *img = &vol->images[k];
	uint64_t n = 0;
	for (uint32_t i = 0; i < img->tile_count; i++) {
		const uint8_t *p = img->tiles + (size_t)i * VOLUME_TILE_BYTES + c * VOLUME_TILE_PLANE_BYTES;
		for (int b = 0; b < VOLUME_TILE_PLANE_BYTES; b++)
			n += (uint64_t)__builtin_popcount(p[b]);
	}
	return n;
}

uint64_t rtest_count(const struct volume *vol, int c)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < vol->image_count; k++)
		n += rtest_count_image(vol, k, c);
	return n;
}

bool rtest_same(const struct volume *a, const struct volume *b)
{
	if (a->image_count != b->image_count || a->mask_bytes != b->mask_bytes)
		return false;
	for (uint32_t k = 0; k < a->image_count; k++) {
		const struct volume_image *x = &a->images[k], *y = &b->images[k];
		if (x->tile_count != y->tile_count || x->next_tile != y->next_tile ||
		    memcmp(x->mask, y->mask, a->mask_bytes) != 0)
			return false;
		if (x->tile_count && memcmp(x->tiles, y->tiles, (size_t)x->tile_count * VOLUME_TILE_BYTES) != 0)
			return false;
	}
	return true;
}

bool rtest_padding_clear(const struct volume *vol)
{
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const uint8_t *tile = vol->images[k].tiles;
		for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
			if (!volume_tile_present(&vol->images[k], t))
				continue;
			uint32_t x0 = (t % vol->tiles_x) * 32, y0 = (t / vol->tiles_x) * 32;
			for (uint32_t i = 0; i < 3 * 32 * 32; i++) {
				uint32_t x = i % 32, y = (i / 32) % 32;
				bool bit = (tile[i / 8] >> (7 - i % 8)) & 1;
				if (bit && (x0 + x >= vol->geom.width || y0 + y >= vol->geom.height))
					return false;
			}
			tile += VOLUME_TILE_BYTES;
		}
	}
	return true;
}

double rtest_col_s0(const struct geometry *g, uint32_t u)
{
	return 2.0 * u / g->width - 1.0;
}

double rtest_col_s1(const struct geometry *g, uint32_t u)
{
	return 2.0 * (u + 1) / g->width - 1.0;
}

double rtest_row_y0(const struct geometry *g, uint32_t v)
{
	return g->half_height - 2.0 * g->half_height * v / g->height;
}

double rtest_row_y1(const struct geometry *g, uint32_t v)
{
	return g->half_height - 2.0 * g->half_height * (v + 1) / g->height;
}

double rtest_row_mid(const struct geometry *g, uint32_t v)
{
	return 0.5 * (rtest_row_y0(g, v) + rtest_row_y1(g, v));
}

void rtest_invert(const float m[16], double inv[16])
{
	double a[4][8];
	for (int r = 0; r < 4; r++)
		for (int c = 0; c < 4; c++) {
			a[r][c] = m[c * 4 + r];
			a[r][4 + c] = r == c;
		}
	for (int c = 0; c < 4; c++) {
		int p = c;
		for (int r = c + 1; r < 4; r++)
			if (fabs(a[r][c]) > fabs(a[p][c]))
				p = r;
		for (int k = 0; k < 8; k++) {
			double t = a[c][k];
			a[c][k] = a[p][k];
			a[p][k] = t;
		}
		double d = a[c][c];
		if (!(fabs(d) > 1e-12)) {
			fprintf(stderr, "rtest_invert: a singular transform\n");
			abort();
		}
		for (int k = 0; k < 8; k++)
			a[c][k] /= d;
		for (int r = 0; r < 4; r++)
			if (r != c) {
				double f = a[r][c];
				for (int k = 0; k < 8; k++)
					a[r][k] -= f * a[c][k];
			}
	}
	for (int r = 0; r < 4; r++)
		for (int c = 0; c < 4; c++)
			inv[c * 4 + r] = a[r][4 + c];
}

bool rtest_have_gl(const struct geometry *g, const char *backend)
{
	struct render_gl_options o = { .backend = backend, .threads = 2 };
	struct renderer *r = render_gl_create(g, &o);
	if (!r && errno == ENOENT && !strcmp(backend, "osmesa")) {
		printf("%s: not in this build (no OSMesa), skipped\n", backend);
		return false;
	}
	if (!r) {
		fprintf(stderr, "%s: render_gl_create failed: %s\n", backend, strerror(errno));
		exit(1);
	}
	render_destroy(r);
	return true;
}

double rtest_rnd(uint64_t *state)
{
	*state ^= *state << 13;
	*state ^= *state >> 7;
	*state ^= *state << 17;
	return (double)(*state >> 11) / 9007199254740992.0;
}

double rtest_range(uint64_t *state, double a, double b)
{
	return a + (b - a) * rtest_rnd(state);
}
