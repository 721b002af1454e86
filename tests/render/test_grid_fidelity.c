/* Volume fidelity (issue 22, item 7): a 3-D Shepp-Logan head phantom
 * drawn as a grid (scene.h, SCENE_GRID) by the CPU renderer, against the
 * analytic ellipsoids it was sampled from, in the display's voxels.
 *
 * The phantom is Kak and Slaney's table as scripts/make-phantom has it
 * (docs/volumes.md, "The phantom"): ten ellipsoids, each adding its value
 * over a base of -1000, so int16 Hounsfield-like units (air -1000, skull
 * 1000, brain 20, ventricles 0, "tumours" 30 to 60). Its ellipsoid
 * coordinates span the grid's box, [-1, 1] on each axis: x along i, the
 * superior z along the grid's up axis j, the anterior y along k, as the
 * display's convention (docs/volumes.md) places a head. Samples are point
 * samples at voxel centres: each is exactly the table's value there.
 *
 * Expectations come from the table evaluated here and the formulas of
 * docs/design.md section 3 (common/geometry.h), with the draw transform
 * inverted here (Gauss-Jordan), never from grid.c. Pixel (u, v) of volume
 * image k shows the display point s d_k + y e_y with s and y its centre's
 * coordinates; the inverse transform takes that to the model, where the
 * grid's box is [0, n sx) x [0, n sy) x [0, n sz).
 *
 * 1-3. The window shows the ventricles' value range, -10 <= v < 10: the
 *    two ventricles and ellipsoid j (all 0 HU; the one ventricle's corner
 *    that ellipsoid e overlaps is 20 HU, dark), each a solid ellipsoid
 *    among the brain's 20 and the skull's 1000. Placed upright (scaled,
 *    turned about the display's axis, moved, so that the left ventricle
 *    holds the axis: the grids' upright path) and tilted (turned, tilted
 *    25 degrees, scaled unevenly: the reference loop), nearest sampling,
 *    on the small profile (mirrored) and rtest_odd() (unmirrored):
 *
 *    Holes and fat, as the mesh tests define them, translated to a solid.
 *    For meshes (test_brightness.c, the protocol suite) a hole is a place
 *    on the shape with no lit voxel where the shape is, and fat a lit
 *    voxel the shape does not reach; a surface has no thickness, so "where
 *    it is" is the voxel it passes through, give or take the one voxel
 *    that docs/design.md section 3 allows either way. A solid from a grid
 *    is decided pixel by pixel instead: the renderer lights a pixel with
 *    the sample at its centre (docs/rendering.md, "Grids"), so
 *
 *    - should be lit: the pixel centre's point falls in a grid voxel whose
 *      centre lies in the analytic region (the table's value there is in
 *      the window): the analytic ellipsoid as the grid's nearest sampling
 *      sees it, which is all a renderer of the grid can know. A hole is
 *      such a pixel left dark. Holes / should-be-lit <= 0.1%, the mesh
 *      tests' bound (test_brightness.c, MAX_HOLE_FRACTION); the only ones
 *      allowed for are pixel centres within rounding of a voxel face,
 *      where the renderer's float transform and this test's double one
 *      may pick neighbouring voxels.
 *    - fat: a lit pixel whose centre lies outside the analytic region
 *      itself. Nearest sampling draws the grid's staircase, which reaches
 *      up to half a voxel (diagonal) beyond the surface: the thickening by
 *      at most a neighbouring voxel that docs/design.md allows. Fat / lit
 *      <= 5%. Lit pixels outside the sampled region (the converse of a
 *      hole) are held to 0.1% too, and the staircase's inner half
 *      (analytic region, dark) is printed.
 *
 * 4. Trilinear: every pixel where trilinear and nearest sampling disagree
 *    on lit/dark lies within one voxel (grid spacing, in the grid's voxel
 *    coordinates, by the exact distance to the ellipsoid's surface) of the
 *    surface of one of the shown ellipsoids, or, lit by trilinear only,
 *    within one voxel of the skull's outer surface, where the mix of air
 *    (-1000) and skull (1000) passes through the window (a partial volume
 *    ramp any interpolation has). Counts per surface are printed.
 *
 * 5. Brightness (docs/rendering.md, "Brightness" and "Grids"): a solid
 *    fills every slice, so in the even and uniform models each of its
 *    pixels is weighted as a surface crossing the slices at right angles
 *    is, min(wall, rate[u]). The whole head, white, centred on the axis;
 *    the cells (u, v) that exact lights in all M images of the volume are
 *    where a solid crosses every slice. Even must light n[u] = min(M,
 *    max(1, round(M r_u D))) of the M images there (r_u the column's
 *    centre radius in pixels, D = 2 pi / N): per band of radii (0-1, 1-2,
 *    2-4, ... px up to r0) the lit share is the model's ratio sum n[u] /
 *    (M cells) within 2%, and how many cells light exactly n[u] (the
 *    Bresenham pattern's "in exactly n[u] of any M consecutive images")
 *    is printed; beyond r0 + 1 even changes nothing. Uniform weighs
 *    w = min(d, d r_u D) (d = r0 / R) and halftones it with the pattern
 *    of n = max(1, round(M d r_u D)) images: every cell must light as many
 *    images as that pattern gives w, for some phase (pattern_count()).
 *    Near the axis both light fewer than exact, as test_brightness.c
 *    checks of meshes. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "grid.h"
#include "rtest.h"

/* ------------------------------------------------------------------ */
/* The phantom. */

struct ellipsoid {
	const char *name;
	double c[3], r[3]; /* centre and semi-axes, ellipsoid coordinates */
	double phi;        /* turned about z, degrees (x towards y) */
	double value;      /* added inside */
};

#define BASE (-1000)
static const struct ellipsoid table[] = {
	{ "skull", { 0.00, 0.000, 0.000 }, { 0.6900, 0.920, 0.900 }, 0, 2000 },
	{ "brain", { 0.00, 0.000, 0.000 }, { 0.6624, 0.874, 0.880 }, 0, -980 },
	{ "ventricle-r", { -0.22, 0.000, -0.250 }, { 0.4100, 0.160, 0.210 }, 108, -20 },
	{ "ventricle-l", { 0.22, 0.000, -0.250 }, { 0.3100, 0.110, 0.220 }, 72, -20 },
	{ "e", { 0.00, 0.350, -0.250 }, { 0.2100, 0.250, 0.500 }, 0, 20 },
	{ "f", { 0.00, 0.100, -0.250 }, { 0.0460, 0.046, 0.046 }, 0, 20 },
	{ "g", { -0.08, -0.650, -0.250 }, { 0.0460, 0.023, 0.020 }, 0, 10 },
	{ "h", { 0.06, -0.650, -0.250 }, { 0.0460, 0.023, 0.020 }, 90, 10 },
	{ "i", { 0.06, -0.105, 0.625 }, { 0.0560, 0.040, 0.100 }, 90, 20 },
	{ "j", { 0.00, 0.100, 0.625 }, { 0.0560, 0.056, 0.100 }, 0, -20 },
};
enum { ELLIPSOIDS = sizeof(table) / sizeof(table[0]), SKULL = 0 };

/* The surfaces that bound the window's region: the ventricles and j
 * (0 HU), and e where it overlaps the right ventricle (20 HU). */
static bool bounds_window(int e)
{
	const char *n = table[e].name;
	return !strcmp(n, "ventricle-r") || !strcmp(n, "ventricle-l") || !strcmp(n, "j") || !strcmp(n, "e");
}

/* Samples along i, j (up), k; i and k alike, so that a turn about z is a
 * turn in voxel coordinates too. The model box is the unit cube. */
enum { NH = 112, NV = 128 };

/* p in ellipsoid coordinates, turned into e's own frame. */
static void local(const struct ellipsoid *e, const double p[3], double out[3])
{
	double a = e->phi * M_PI / 180, cs = cos(a), sn = sin(a);
	double dx = p[0] - e->c[0], dy = p[1] - e->c[1];
	out[0] = dx * cs + dy * sn;
	out[1] = -dx * sn + dy * cs;
	out[2] = p[2] - e->c[2];
}

static bool inside(const struct ellipsoid *e, const double p[3])
{
	double q[3];
	local(e, p, q);
	double f = 0;
	for (int a = 0; a < 3; a++)
		f += q[a] / e->r[a] * (q[a] / e->r[a]);
	return f <= 1.0;
}

/* The phantom's value at ellipsoid coordinates p. */
static double phantom(const double p[3])
{
	double v = BASE;
	for (int e = 0; e < ELLIPSOIDS; e++)
		if (inside(&table[e], p))
			v += table[e].value;
	return v;
}

/* Ellipsoid coordinates of a point of the model's unit cube (x, y up, z):
 * x along i, y (anterior) along k, z (superior) along j. */
static void model_to_ellipsoid(const double m[3], double p[3])
{
	p[0] = 2 * m[0] - 1;
	p[1] = 2 * m[2] - 1;
	p[2] = 2 * m[1] - 1;
}

/* Sample (i, j, k) at (k NH + i) NV + j: the value at its centre. */
static int16_t *make_phantom(void)
{
	int16_t *d = malloc((size_t)NH * NV * NH * sizeof(*d));
	CHECK(d);
	for (uint32_t k = 0; k < NH; k++)
		for (uint32_t i = 0; i < NH; i++)
			for (uint32_t j = 0; j < NV; j++) {
				double m[3] = { (i + 0.5) / NH, (j + 0.5) / NV, (k + 0.5) / NH }, p[3];
				model_to_ellipsoid(m, p);
				d[((size_t)k * NH + i) * NV + j] = (int16_t)phantom(p);
			}
	return d;
}

/* The window of checks 1-4: lit iff -10 <= v < 10. The threshold cuts
 * below; over the window -15 .. 25, lut entry round(4 g) is 3 or 4 from
 * v = 10 on: black. */
static const uint8_t ventricle_lut[5 * 3] = { 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 0, 0, 0 };

static bool in_window(double v)
{
	return v >= -10 && v < 10;
}

/* ------------------------------------------------------------------ */
/* Distance from a point to an ellipsoid's surface. */

/* The distance from y (in the frame of an ellipsoid of semi-axes e, any
 * octant, inside or outside) to its surface. The closest point x has
 * x_i = e_i^2 y_i / (t + e_i^2) for the one root t > -min e_i^2 of
 * sum (e_i y_i / (t + e_i^2))^2 = 1, which decreases in t; found by
 * bisection. A coordinate of 0 is moved by 1e-12, which moves the
 * distance by as little and keeps the root in that interval. */
static double surface_distance(const double e[3], const double y_in[3])
{
	double y[3], norm = 0, emin2 = INFINITY, emax = 0;
	for (int a = 0; a < 3; a++) {
		y[a] = fmax(fabs(y_in[a]), 1e-12);
		norm += y[a] * y[a];
		emin2 = fmin(emin2, e[a] * e[a]);
		emax = fmax(emax, e[a]);
	}
	double lo = -emin2, hi = emax * sqrt(norm);
	for (int it = 0; it < 300; it++) {
		double mid = 0.5 * (lo + hi), f = -1;
		if (mid <= lo || mid >= hi)
			break;
		for (int a = 0; a < 3; a++) {
			double t = e[a] * y[a] / (mid + e[a] * e[a]);
			f += t * t;
		}
		if (f > 0)
			lo = mid;
		else
			hi = mid;
	}
	double d2 = 0;
	for (int a = 0; a < 3; a++) {
		double x = e[a] * e[a] * y[a] / (hi + e[a] * e[a]);
		d2 += (x - y[a]) * (x - y[a]);
	}
	return sqrt(d2);
}

/* The distance, in voxels (the grid's voxel coordinates, centres at
 * integers), from grid point q to ellipsoid e's surface. In voxel
 * coordinates e is turned about the up axis j only (i and k have the same
 * count), with semi-axes a NH / 2, b NH / 2, c NV / 2. */
static double voxel_distance(const struct ellipsoid *e, const double q[3])
{
	const double n[3] = { NH, NV, NH };
	double m[3], p[3], l[3];
	for (int a = 0; a < 3; a++)
		m[a] = (q[a] + 0.5) / n[a];
	model_to_ellipsoid(m, p);
	local(e, p, l);
	/* Ellipsoid coordinates to voxels: x and y by NH / 2, z by NV / 2. */
	const double scale[3] = { NH / 2.0, NH / 2.0, NV / 2.0 };
	double y[3], semi[3];
	for (int a = 0; a < 3; a++) {
		y[a] = l[a] * scale[a];
		semi[a] = e->r[a] * scale[a];
	}
	return surface_distance(semi, y);
}

/* ------------------------------------------------------------------ */
/* Placement and pixels. */

/* 3x3 row-major products. */
static void mul3(double a[3][3], double b[3][3], double out[3][3])
{
	for (int r = 0; r < 3; r++)
		for (int c = 0; c < 3; c++)
			out[r][c] = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
}

enum placement { UPRIGHT, TILTED, CENTRED };
static const char *const placement_name[] = { "upright", "tilted", "centred" };

/* The draw transform of the unit cube: its centre to the origin, scaled,
 * (TILTED: tilted about x by 25 degrees and scaled unevenly,) turned about
 * y by 0.6 rad (x' = x cos a - z sin a, z' = x sin a + z cos a), moved:
 * UPRIGHT and TILTED put the left ventricle's centre at x = 0.011,
 * z = 0.017, beside the axis; CENTRED puts the cube's centre on it. */
static void placement(enum placement pl, float out[16])
{
	double turn = 0.6, tilt = pl == TILTED ? 25 * M_PI / 180 : 0;
	double sc[3] = { 1.4, 1.4, 1.4 };
	if (pl == TILTED)
		sc[0] = 1.45, sc[2] = 1.35;
	double S[3][3] = { { sc[0], 0, 0 }, { 0, sc[1], 0 }, { 0, 0, sc[2] } };
	double X[3][3] = { { 1, 0, 0 }, { 0, cos(tilt), -sin(tilt) }, { 0, sin(tilt), cos(tilt) } };
	double Y[3][3] = { { cos(turn), 0, -sin(turn) }, { 0, 1, 0 }, { sin(turn), 0, cos(turn) } };
	double xs[3][3], lin[3][3];
	mul3(X, S, xs);
	mul3(Y, xs, lin);
	/* The point to put near the axis, model coordinates. */
	double at[3] = { 0.5, 0.5, 0.5 };
	if (pl != CENTRED) {
		const struct ellipsoid *v = &table[3]; /* ventricle-l */
		at[0] = (v->c[0] + 1) / 2, at[1] = (v->c[2] + 1) / 2, at[2] = (v->c[1] + 1) / 2;
	}
	double t[3];
	for (int r = 0; r < 3; r++) {
		t[r] = 0;
		for (int c = 0; c < 3; c++)
			t[r] -= lin[r][c] * 0.5;
	}
	/* Where the point lands without the move's horizontal part. */
	double land[3];
	for (int r = 0; r < 3; r++) {
		land[r] = t[r];
		for (int c = 0; c < 3; c++)
			land[r] += lin[r][c] * at[c];
	}
	if (pl != CENTRED) {
		t[0] += 0.011 - land[0];
		t[2] += 0.017 - land[2];
	}
	memset(out, 0, 16 * sizeof(float));
	for (int r = 0; r < 3; r++) {
		for (int c = 0; c < 3; c++)
			out[c * 4 + r] = (float)lin[r][c];
		out[12 + r] = (float)t[r];
	}
	out[15] = 1;
}

static uint32_t images_of(const struct geometry *g)
{
	return geometry_images_per_volume(g);
}

/* The model point that pixel (u, v) of volume image k shows. */
static void pixel_model(const struct geometry *g, const double inv[16], uint32_t k, uint32_t u, uint32_t v,
			double out[3])
{
	double th = geometry_image_angle(g, k);
	double s = (u + 0.5) * 2.0 / g->width - 1.0, y = g->half_height - (v + 0.5) * 2.0 * g->half_height / g->height;
	double p[3] = { s * cos(th), y, s * sin(th) };
	for (int r = 0; r < 3; r++)
		out[r] = inv[12 + r] + inv[r] * p[0] + inv[4 + r] * p[1] + inv[8 + r] * p[2];
}

/* The phantom grid, and a draw of it. */
struct phantom_grid {
	int16_t *data;
	float *brick_max;
	struct scene_grid grid;
	double extent[3]; /* the box, n times the spacing as the renderer has it */
};

static void phantom_grid_init(struct phantom_grid *pg)
{
	pg->data = make_phantom();
	pg->grid = (struct scene_grid){ .type = SCENE_GRID_I16,
					.n = { NH, NV, NH },
					.spacing = { 1.0f / NH, 1.0f / NV, 1.0f / NH },
					.data = pg->data };
	/* As the daemon makes a volume: with its bricks' maxima, so that the
	 * upright path skips what stays below the threshold. */
	pg->brick_max = malloc(grid_brick_count(&pg->grid) * sizeof(float));
	CHECK(pg->brick_max);
	grid_brick_max(&pg->grid, pg->brick_max);
	pg->grid.brick_max = pg->brick_max;
	for (int a = 0; a < 3; a++)
		pg->extent[a] = pg->grid.n[a] * (double)pg->grid.spacing[a];
}

static void phantom_grid_finish(struct phantom_grid *pg)
{
	free(pg->data);
	free(pg->brick_max);
}

static struct scene_draw phantom_draw(const struct phantom_grid *pg, const float m[16], uint32_t sampling)
{
	struct scene_draw d = {
		.prim = SCENE_GRID,
		.rgb = { 255, 255, 255 },
		.grid = &pg->grid,
		.transfer = { .threshold = -10,
			      .lo = -15,
			      .hi = 25,
			      .sampling = sampling,
			      .lut = ventricle_lut,
			      .lut_count = 5 },
	};
	memcpy(d.transform, m, sizeof(d.transform));
	return d;
}

/* Where model point m lies: in the box, its nearest voxel (i, j, k). */
static bool nearest_voxel(const struct phantom_grid *pg, const double m[3], uint32_t idx[3])
{
	for (int a = 0; a < 3; a++) {
		if (!(m[a] >= 0 && m[a] < pg->extent[a]))
			return false;
		double f = floor(m[a] / (double)pg->grid.spacing[a]);
		idx[a] = f >= pg->grid.n[a] ? pg->grid.n[a] - 1 : (uint32_t)f;
	}
	return true;
}

/* ------------------------------------------------------------------ */
/* 1-4. */

struct figures {
	uint64_t pixels, should, holes, stray, analytic, inner, lit, fat;
	uint64_t differ, tri_only, near_only, at[ELLIPSOIDS];
	double worst; /* the largest distance of a disagreement from its surface, voxels */
};

static void check_fidelity(const char *gname, const struct geometry *g, const struct phantom_grid *pg,
			   enum placement pl, struct figures *f)
{
	float m[16];
	placement(pl, m);
	struct scene_draw d = phantom_draw(pg, m, SCENE_NEAREST);
	/* Each placement takes the path it is meant to test. */
	struct grid_job job;
	CHECK(grid_prepare(&job, &d));
	CHECK_MSG(job.upright == (pl == UPRIGHT), "%s: upright %d", placement_name[pl], job.upright);
	grid_job_finish(&job);
	struct volume *nearest = rtest_render(g, &d, 1, 2);
	d.transfer.sampling = SCENE_TRILINEAR;
	struct volume *tri = rtest_render(g, &d, 1, 2);
	double inv[16];
	rtest_invert(m, inv);
	memset(f, 0, sizeof(*f));
	const int16_t *data = pg->data;
	for (uint32_t k = 0; k < images_of(g); k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++) {
				double mp[3], p[3];
				uint32_t idx[3];
				pixel_model(g, inv, k, u, v, mp);
				bool in_box = nearest_voxel(pg, mp, idx);
				/* The nearest voxel's centre, through the samples made
				 * from the table there; the pixel centre itself. */
				bool should = in_box && in_window(data[((size_t)idx[2] * NH + idx[0]) * NV + idx[1]]);
				model_to_ellipsoid(mp, p);
				bool analytic = in_window(phantom(p));
				bool a = rtest_lit(nearest, k, u, v, 0), b = rtest_lit(tri, k, u, v, 0);
				f->pixels++;
				f->should += should;
				f->holes += should && !a;
				f->stray += a && !should;
				f->analytic += analytic;
				f->inner += analytic && !a;
				f->lit += a;
				f->fat += a && !analytic;
				if (a == b)
					continue;
				/* 4: the nearest surface, in voxels. */
				f->differ++;
				f->tri_only += b;
				f->near_only += a;
				double q[3], best = INFINITY;
				int at = -1;
				for (int c = 0; c < 3; c++)
					q[c] = mp[c] / (double)pg->grid.spacing[c] - 0.5;
				for (int e = 0; e < ELLIPSOIDS; e++) {
					if (!bounds_window(e) && !(e == SKULL && b))
						continue;
					double dist = voxel_distance(&table[e], q);
					if (dist < best)
						best = dist, at = e;
				}
				CHECK_MSG(at >= 0 && best <= 1.0,
					  "%s %s: image %u pixel (%u, %u): trilinear %s, nearest %s, %.3f voxels from "
					  "the surface of %s",
					  gname, placement_name[pl], k, u, v, b ? "lit" : "dark", a ? "lit" : "dark",
					  best, at >= 0 ? table[at].name : "any");
				f->at[at]++;
				f->worst = fmax(f->worst, best);
			}
	double holes = (double)f->holes / (double)f->should, fat = (double)f->fat / (double)f->lit;
	printf("%s %s: nearest: %llu lit; should be lit %llu, holes %llu (%.4f%%); fat %llu (%.3f%% of lit); lit "
	       "outside the sampled region %llu; analytic %llu, dark inside it %llu (%.3f%%)\n",
	       gname, placement_name[pl], (unsigned long long)f->lit, (unsigned long long)f->should,
	       (unsigned long long)f->holes, 100 * holes, (unsigned long long)f->fat, 100 * fat,
	       (unsigned long long)f->stray, (unsigned long long)f->analytic, (unsigned long long)f->inner,
	       100.0 * (double)f->inner / (double)f->analytic);
	printf("%s %s: trilinear differs at %llu pixels (%llu lit by trilinear only), all within %.3f voxels of a "
	       "surface:",
	       gname, placement_name[pl], (unsigned long long)f->differ, (unsigned long long)f->tri_only, f->worst);
	for (int e = 0; e < ELLIPSOIDS; e++)
		if (f->at[e])
			printf(" %s %llu", table[e].name, (unsigned long long)f->at[e]);
	printf("\n");
	CHECK_MSG(f->should > 5000, "%s %s: only %llu pixels to light", gname, placement_name[pl],
		  (unsigned long long)f->should);
	CHECK_MSG(holes <= 0.001, "%s %s: %llu holes in %llu", gname, placement_name[pl], (unsigned long long)f->holes,
		  (unsigned long long)f->should);
	CHECK_MSG(f->stray <= 0.001 * (double)f->lit, "%s %s: %llu lit outside the sampled region", gname,
		  placement_name[pl], (unsigned long long)f->stray);
	CHECK_MSG(fat <= 0.05, "%s %s: fat %llu of %llu lit", gname, placement_name[pl], (unsigned long long)f->fat,
		  (unsigned long long)f->lit);
	CHECK(f->differ > 0);
	volume_destroy(nearest);
	volume_destroy(tri);
}

/* ------------------------------------------------------------------ */
/* 5. */

/* Lit images of each pixel (u, v) of the volume, counted over its M images. */
static uint16_t *lit_counts(const struct volume *vol)
{
	const struct geometry *g = &vol->geom;
	uint16_t *n = calloc((size_t)g->width * g->height, sizeof(*n));
	CHECK(n);
	for (uint32_t k = 0; k < vol->image_count; k++)
		for (uint32_t v = 0; v < g->height; v++)
			for (uint32_t u = 0; u < g->width; u++)
				n[(size_t)v * g->width + u] += rtest_lit(vol, k, u, v, 0);
	return n;
}

/* How many of the M images light a cell of weight w (docs/rendering.md,
 * "Brightness"): the value c = floor(255 w) is lit iff c > 255 x / M, with
 * x = (k n + phase) mod M over the images k. x runs through the residues
 * phase mod g (g = gcd(n, M)) g times each; the phase is the map's own,
 * so *lo and *hi bound the count over every residue, and over c within
 * 0.01 of 255 w (the map weighs in float). */
static void pattern_count(uint32_t M, uint32_t n, double w, uint32_t *lo, uint32_t *hi)
{
	uint32_t g = M, b = n;
	while (b) {
		uint32_t t = g % b;
		g = b;
		b = t;
	}
	int c_lo = (int)floor(255 * w - 0.01), c_hi = (int)floor(255 * w + 0.01);
	*lo = M;
	*hi = 0;
	for (uint32_t r = 0; r < g; r++) {
		uint32_t a = 0, z = 0;
		for (uint32_t x = r; x < M; x += g) {
			int t = (int)(255 * x / M);
			a += c_lo > t;
			z += c_hi > t;
		}
		*lo = a * g < *lo ? a * g : *lo;
		*hi = z * g > *hi ? z * g : *hi;
	}
}

static void check_brightness(const char *gname, const struct geometry *g, const struct phantom_grid *pg)
{
	float m[16];
	placement(CENTRED, m);
	/* The whole head, white: every value from -500 on saturates. */
	struct scene_draw d = phantom_draw(pg, m, SCENE_NEAREST);
	d.transfer = (struct scene_transfer){ .threshold = -500, .lo = -1000, .hi = -500 };
	struct geometry ge = *g, gu = *g;
	ge.brightness = GEOMETRY_BRIGHTNESS_EVEN;
	gu.brightness = GEOMETRY_BRIGHTNESS_UNIFORM;
	struct volume *exact = rtest_render(g, &d, 1, 2), *even = rtest_render(&ge, &d, 1, 2);
	struct volume *uniform = rtest_render(&gu, &d, 1, 2);
	uint16_t *ne = lit_counts(exact), *nv = lit_counts(even), *nu = lit_counts(uniform);
	const uint32_t M = images_of(g);
	const double r0 = geometry_r0_px(g), D = 2 * M_PI / g->images_per_rev, dens = r0 / (g->width / 2.0);
	/* Bands of the column's centre radius, pixels: 0, 1, 2, 4, ... to r0,
	 * and the last from r0 to the rim. */
	enum { BANDS_MAX = 16 };
	double edge[BANDS_MAX + 1] = { 0 };
	int bands = 0;
	for (double e = 1; e < r0; e *= 2)
		edge[++bands] = e;
	edge[++bands] = r0;
	edge[++bands] = g->width / 2.0;
	CHECK(bands <= BANDS_MAX);
	uint64_t cells[BANDS_MAX] = { 0 }, got_even[BANDS_MAX] = { 0 }, got_uniform[BANDS_MAX] = { 0 };
	uint64_t want_even[BANDS_MAX] = { 0 }, uniform_lo[BANDS_MAX] = { 0 }, uniform_hi[BANDS_MAX] = { 0 };
	uint64_t even_cells = 0, even_exact = 0, uniform_cells = 0, uniform_out = 0, beyond = 0, beyond_lit = 0;
	for (uint32_t v = 0; v < g->height; v++)
		for (uint32_t u = 0; u < g->width; u++) {
			size_t i = (size_t)v * g->width + u;
			double r = fabs(u + 0.5 - g->width / 2.0);
			if (r > r0 + 1) {
				for (uint32_t k = 0; k < M; k++)
					beyond += rtest_lit(exact, k, u, v, 0) != rtest_lit(even, k, u, v, 0);
				beyond_lit += ne[i];
			}
			if (ne[i] != M) /* not a solid crossing every slice here */
				continue;
			/* even: n[u] images; uniform: weight min(d, d r D), its
			 * pattern's n rounded from d r D. */
			double ue = fmin(M, fmax(1, floor(M * r * D + 0.5)));
			double rate = fmin(1.0, dens * r * D), w = fmin(dens, rate);
			uint32_t un = (uint32_t)fmin(M, fmax(1, floor(M * rate + 0.5))), lo, hi;
			pattern_count(M, un, w, &lo, &hi);
			uniform_cells++;
			uniform_out += nu[i] < lo || nu[i] > hi;
			int b = 0;
			while (b < bands - 1 && r >= edge[b + 1])
				b++;
			cells[b]++;
			got_uniform[b] += nu[i];
			uniform_lo[b] += lo;
			uniform_hi[b] += hi;
			if (r > r0 + 1)
				continue;
			even_cells++;
			even_exact += nv[i] == (uint32_t)ue;
			got_even[b] += nv[i];
			want_even[b] += (uint64_t)ue;
		}
	printf("%s brightness (M %u, r0 %.1f px): a solid head, white, centred on the axis; per band of radii, the "
	       "share of images lit in the cells (u, v) that exact lights in all M:\n",
	       gname, M, r0);
	printf("  %-12s %6s %8s %8s %8s %17s\n", "band (px)", "cells", "even", "model", "uniform", "model");
	for (int b = 0; b < bands; b++) {
		double c = (double)cells[b] * M;
		if (!cells[b])
			continue;
		printf("  %5.1f-%-6.1f %6llu", edge[b], edge[b + 1], (unsigned long long)cells[b]);
		if (b < bands - 1)
			printf(" %8.4f %8.4f", (double)got_even[b] / c, (double)want_even[b] / c);
		else
			printf(" %8s %8s", "-", "-");
		printf(" %8.4f  %7.4f-%.4f\n", (double)got_uniform[b] / c, (double)uniform_lo[b] / c,
		       (double)uniform_hi[b] / c);
	}
	printf("  even: %llu of %llu cells within r0 + 1 lit in exactly n[u] images; uniform: %llu of %llu cells "
	       "outside their pattern's count; beyond r0 + 1, %llu of %llu lit voxels differ between even and "
	       "exact\n",
	       (unsigned long long)even_exact, (unsigned long long)even_cells, (unsigned long long)uniform_out,
	       (unsigned long long)uniform_cells, (unsigned long long)beyond, (unsigned long long)beyond_lit);
	for (int b = 0; b < bands - 1; b++) {
		CHECK_MSG(cells[b] >= 4, "%s: band %g-%g px holds %llu cells", gname, edge[b], edge[b + 1],
			  (unsigned long long)cells[b]);
		/* The model's ratio, within 2% (it is exact by construction). */
		CHECK_MSG(fabs((double)got_even[b] / (double)want_even[b] - 1) <= 0.02,
			  "%s even, band %g-%g px: %llu lit, the model %llu", gname, edge[b], edge[b + 1],
			  (unsigned long long)got_even[b], (unsigned long long)want_even[b]);
		CHECK(got_even[b] < cells[b] * M && got_uniform[b] < got_even[b]);
	}
	CHECK_MSG(uniform_out == 0, "%s uniform: %llu cells outside their pattern's count", gname,
		  (unsigned long long)uniform_out);
	CHECK_MSG(beyond == 0, "%s: even differs from exact in %llu voxels beyond r0 + 1", gname,
		  (unsigned long long)beyond);
	CHECK(beyond_lit > 1000 && cells[bands - 1] > 100);
	free(ne);
	free(nv);
	free(nu);
	volume_destroy(exact);
	volume_destroy(even);
	volume_destroy(uniform);
}

int main(void)
{
	setvbuf(stdout, NULL, _IOLBF, 0);
	struct phantom_grid pg;
	phantom_grid_init(&pg);
	struct geometry small = rtest_small(), odd = rtest_odd();
	const struct {
		const char *name;
		const struct geometry *g;
	} geoms[] = { { "small", &small }, { "odd", &odd } };
	printf("phantom: %ux%ux%u int16 (i, j up, k), the Kak-Slaney table; window -10 <= v < 10 (the ventricles "
	       "and j); holes: of the pixels whose nearest voxel's centre is in the window, those dark; fat: of the "
	       "lit pixels, those whose centre is not\n",
	       NH, NV, NH);
	for (int i = 0; i < 2; i++)
		for (int pl = UPRIGHT; pl <= TILTED; pl++) {
			struct figures f;
			check_fidelity(geoms[i].name, geoms[i].g, &pg, (enum placement)pl, &f);
		}
	for (int i = 0; i < 2; i++)
		check_brightness(geoms[i].name, geoms[i].g, &pg);
	phantom_grid_finish(&pg);
	return check_done();
}
