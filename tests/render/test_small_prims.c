/* section.c's shortcuts (lobes the clip cannot reach, planes every vertex
 * is inside, rows by a product, spans by half rows), and section_lanes()'s
 * eight lanes (section_batch.c) on the unmirrored segments and triangles, eight cases
 * at a time, against the general
 * path (section_canvas.general: both lobes, both planes, geometry_row(),
 * spans byte by byte), pixel for pixel: many random small triangles and
 * segments about each image's wedge planes, near and across the axis, with
 * vertices on column and row boundaries and on the wedge planes, degenerate
 * ones, drawn as they are and mirrored, on three geometries (2h a power of two
 * and not), in the exact, even and uniform brightness models; a third in
 * the colour the fast canvases keep as bits (section_canvas_plain()). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "check.h"
#include "rtest.h"
#include "section.h"

/* splitmix64: the same cases on every machine. */
static uint64_t rng_state = 17;

static double unit(void)
{
	uint64_t z = (rng_state += 0x9e3779b97f4a7c15u);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
	z ^= z >> 31;
	return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static double range(double lo, double hi)
{
	return lo + (hi - lo) * unit();
}

/* Whether the two canvases hold the same bytes and row masks; clears both. */
static bool same_and_clear(struct section_canvas *a, struct section_canvas *b)
{
	bool same = true;
	uint32_t tiles = a->tiles_x * a->tiles_y;
	for (uint32_t t = 0; t < tiles; t++) {
		section_canvas_fold_tile(a, t);
		section_canvas_fold_tile(b, t);
		if (!a->rows[t] && !b->rows[t])
			continue;
		if (a->rows[t] != b->rows[t] || memcmp(a->rgb + (size_t)t * HALFTONE_TILE_BYTES,
						       b->rgb + (size_t)t * HALFTONE_TILE_BYTES, HALFTONE_TILE_BYTES))
			same = false;
		/* Both masks: a row one canvas lit and the other did not. */
		uint32_t rows = a->rows[t] | b->rows[t];
		a->rows[t] = b->rows[t] = rows;
		section_canvas_clear_tile(a, t);
		section_canvas_clear_tile(b, t);
	}
	return same;
}

/* A vertex near (r, y) at azimuth phi, or moved onto something exact. */
static void vertex(const struct geometry *g, const struct section_wedge *w, double cx, double cy, double cz,
		   double size, double out[3])
{
	double row_h = 2.0 * g->half_height / g->height, col_w = 2.0 / g->width;
	out[0] = cx + range(-size, size);
	out[1] = cy + range(-size, size);
	out[2] = cz + range(-size, size);
	double pick = unit();
	if (pick < 0.1) { /* y on a row boundary */
		out[1] = g->half_height - round((g->half_height - out[1]) / row_h) * row_h;
	} else if (pick < 0.2) { /* s on a column boundary, on the image's plane */
		double s = out[0] * w->dx + out[2] * w->dz;
		s = round((s + 1.0) / col_w) * col_w - 1.0;
		out[0] = s * w->dx;
		out[2] = s * w->dz;
	} else if (pick < 0.3) { /* on a wedge plane: azimuth theta_k +- D/2 */
		double r = hypot(out[0], out[2]), a = atan2(w->dz, w->dx);
		a += (unit() < 0.5 ? -0.5 : 0.5) * 2.0 * M_PI / g->images_per_rev;
		out[0] = r * cos(a);
		out[2] = r * sin(a);
	}
	for (int j = 0; j < 3; j++)
		out[j] = F(out[j]);
}

/* Eight segments or triangles (verts vertices) at a time through
 * section_lanes() (lanes of all kinds side by side) against the general
 * path. */
struct batch {
	int verts;
	struct section_canvas lanes, general;
	float v[SECTION_BATCH][9];
	uint8_t rgb[SECTION_BATCH][3];
	struct section_lane t[SECTION_BATCH];
	unsigned n;
	struct section_wedge w;
};

static void batch_flush(struct batch *b)
{
	if (!b->n)
		return;
	section_lanes(&b->lanes, &b->w, b->t, b->n, b->verts);
	CHECK_MSG(same_and_clear(&b->lanes, &b->general), "%ux%u N %u: a batch of %u in image %u", b->lanes.geom.width,
		  b->lanes.geom.height, b->lanes.geom.images_per_rev, b->n, b->w.image);
	b->n = 0;
}

/* Adds segment or triangle v of image w (the batch's image, or a new
 * batch). */
static void batch_add(struct batch *b, const struct section_wedge *w, const double (*v)[3], const uint8_t rgb[3])
{
	if (b->n && b->w.image != w->image)
		batch_flush(b);
	b->w = *w;
	double f[3][3]; /* binned vertices are floats */
	for (int a = 0; a < 3 * b->verts; a++) {
		b->v[b->n][a] = (float)v[a / 3][a % 3];
		f[a / 3][a % 3] = b->v[b->n][a];
	}
	memcpy(b->rgb[b->n], rgb, 3);
	b->t[b->n] = (struct section_lane){ b->v[b->n], b->rgb[b->n] };
	section_prim(&b->general, w, (const double(*)[3])f, b->verts, rgb);
	if (++b->n == SECTION_BATCH)
		batch_flush(b);
}

/* Case i in w's image: a segment or triangle (the count returned) into v,
 * mostly about the planes of the wedge, some across the axis; runs of
 * cases wholly inside it (i % 64 >= 40: whole batches the clip leaves be);
 * some degenerate. */
static int random_case(const struct geometry *g, const struct section_wedge *w, uint32_t i, double v[3][3])
{
	double col_w = 2.0 / g->width;
	double r = unit() < 0.15 ? range(0.0, 3.0 * col_w) : range(0.0, 1.1);
	double phi = atan2(w->dz, w->dx) + range(-1.5, 1.5) * 2.0 * M_PI / g->images_per_rev;
	if (unit() < 0.3)
		phi += M_PI; /* the s < 0 lobe */
	double cx = r * cos(phi), cz = r * sin(phi), cy = range(-1.05, 1.05) * g->half_height;
	double size = col_w * exp(range(log(1e-4), log(3.0)));
	if (i % 64 >= 40) { /* runs wholly inside the wedge: batches the clip leaves be */
		r = range(0.3, 1.0);
		phi = atan2(w->dz, w->dx) + (unit() < 0.3 ? M_PI : 0) + range(-0.2, 0.2) * M_PI / g->images_per_rev;
		cx = r * cos(phi), cz = r * sin(phi);
		size = r * M_PI / g->images_per_rev * range(0.01, 0.2);
	}
	int n = unit() < 0.8 ? 3 : 2;
	for (int a = 0; a < n; a++) {
		vertex(g, w, cx, cy, cz, size, v[a]);
		if (i % 64 >= 40) /* not moved onto a plane */
			for (int j = 0; j < 3; j++)
				v[a][j] = F((j == 0 ? cx : j == 1 ? cy : cz) + range(-size, size));
	}
	double pick = unit();
	if (pick < 0.05) { /* two vertices the same */
		memcpy(v[1], v[0], sizeof(v[0]));
	} else if (pick < 0.08) { /* all the same: a point */
		memcpy(v[1], v[0], sizeof(v[0]));
		memcpy(v[2], v[0], sizeof(v[0]));
	} else if (pick < 0.12 && n == 3) { /* collinear */
		for (int j = 0; j < 3; j++)
			v[2][j] = F(v[0][j] + 0.5 * (v[1][j] - v[0][j]));
	}
	return n;
}

static void check_geometry(const struct geometry *g, uint32_t cases)
{
	struct batch bt = { .verts = 3 }, bs = { .verts = 2 }; /* triangles, segments */
	struct batch *both[2] = { &bs, &bt };
	for (int q = 0; q < 2; q++) {
		CHECK(section_canvas_init(&both[q]->lanes, g) == 0);
		CHECK(section_canvas_init(&both[q]->general, g) == 0);
	}
	struct section_canvas fast, slow;
	struct brightness_map bright;
	CHECK(section_canvas_init(&fast, g) == 0);
	CHECK(section_canvas_init(&slow, g) == 0);
	CHECK(brightness_map_init(&bright, g) == 0);
	fast.bright = slow.bright = &bright; /* weighted near the axis unless EXACT */
	for (int q = 0; q < 2; q++) {
		both[q]->lanes.bright = both[q]->general.bright = &bright;
		both[q]->general.general = true;
	}
	slow.general = true;
	/* A third of the cases in the plain colour (section_canvas_plain()),
	 * kept as bits where the canvas is not general. */
	static const uint8_t plain[3] = { 90, 0, 255 };
	struct section_canvas *all[] = { &fast, &slow, &bs.lanes, &bs.general, &bt.lanes, &bt.general };
	for (int q = 0; q < 6; q++)
		section_canvas_plain(all[q], plain);
	uint32_t images = geometry_images_per_volume(g);
	for (uint32_t i = 0; i < cases; i++) {
		/* Runs of cases in one image, so that batches fill. */
		uint32_t k = i % 64 ? bt.w.image : (uint32_t)(unit() * images);
		struct section_wedge w;
		section_wedge_init(&w, g, k);
		double v[3][3] = { { 0 } };
		int n = random_case(g, &w, i, v);
		uint8_t rgb[3] = { (uint8_t)(1 + i % 255), (uint8_t)(i * 7 % 256), 255 };
		if (i % 3 == 0)
			memcpy(rgb, plain, 3);
		bool mirror = unit() < 0.3;
		section_prim_mirror(&fast, &w, (const double(*)[3])v, n, rgb, mirror);
		section_prim_mirror(&slow, &w, (const double(*)[3])v, n, rgb, mirror);
		if (!mirror)
			batch_add(both[n == 3], &w, (const double(*)[3])v, rgb);
		CHECK_MSG(same_and_clear(&fast, &slow),
			  "%ux%u N %u: case %u, image %u, %d vertices (%.17g %.17g %.17g) (%.17g %.17g %.17g) "
			  "(%.17g %.17g %.17g), mirror %d",
			  g->width, g->height, g->images_per_rev, i, k, n, v[0][0], v[0][1], v[0][2], v[1][0], v[1][1],
			  v[1][2], v[2][0], v[2][1], v[2][2], mirror);
	}
	for (int q = 0; q < 2; q++) {
		batch_flush(both[q]);
		section_canvas_finish(&both[q]->lanes);
		section_canvas_finish(&both[q]->general);
	}
	section_canvas_finish(&fast);
	section_canvas_finish(&slow);
	brightness_map_finish(&bright);
}

int main(void)
{
	struct geometry perspecta, small = rtest_small(), odd = rtest_odd();
	CHECK(geometry_from_profile("perspecta", &perspecta) == 0);
	check_geometry(&perspecta, 200000);
	check_geometry(&small, 100000);
	check_geometry(&odd, 100000);
	perspecta.brightness = GEOMETRY_BRIGHTNESS_EVEN;
	odd.brightness = GEOMETRY_BRIGHTNESS_UNIFORM;
	check_geometry(&perspecta, 100000);
	check_geometry(&odd, 50000);
	return check_done();
}
