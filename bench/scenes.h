/* The benchmark scenes of docs/design.md section 7 (bench/README.md): fixed,
 * deterministic scene snapshots for a geometry, some animated per volume. */
#ifndef SPINDLE_BENCH_SCENES_H
#define SPINDLE_BENCH_SCENES_H

#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "scene.h"

/* Model files the mesh scenes load; a scene whose file is NULL is not
 * available (bench_scene_build() returns -ENODATA). */
struct bench_files {
	const char *bunny;       /* tests/data/bunny.ply */
	const char *dragon;      /* dragon_vrip.ply */
	const char *dragon_res2; /* dragon_vrip_res2.ply */
};

struct bench_scene_impl;

struct bench_scene_info {
	const char *name; /* e.g. "S1-points-1M"; the group is the part before '-' */
	const char *what; /* one line */
	/* What the scene claims to hold; bench_scene_build() checks it. */
	uint64_t points, segments, triangles, draws;
	/* Private. */
	const struct bench_scene_impl *impl;
	uint32_t param;
};

/* All scenes, in benchmark order, ending with a NULL name. */
const struct bench_scene_info *bench_scene_list(void);

struct bench_scene {
	const struct bench_scene_info *info;
	struct scene scene; /* what gets rendered, valid until freed */
	/* Counted from the draws: */
	uint64_t points, segments, triangles;
	/* Private. */
	struct scene_draw *draws;
	void *data;
};

/* Builds the scene called name for geometry g. Returns 0, -ENOENT (no such
 * scene), -ENODATA (its model file is not given), or another negative errno
 * with a one-line reason in err. */
int bench_scene_build(const char *name, const struct geometry *g, const struct bench_files *files,
		      struct bench_scene *out, char *err, size_t err_size);

/* Sets the draws to what the scene shows in volume number frame (only the
 * animated scenes change). Part of each measured volume. */
void bench_scene_animate(struct bench_scene *s, uint64_t frame);

/* Accepts a zeroed scene. */
void bench_scene_free(struct bench_scene *s);

/* S4's motion: an object orbiting the axis at its own radius, height,
 * speed and spin (speeds in rad/s). */
struct bench_orbit {
	double radius, y, phase, speed, spin, tilt;
};
struct rng;
/* A random orbit inside a display of half height h. */
void bench_orbit_random(struct bench_orbit *o, struct rng *rng, double h);
/* Its model -> volume transform at t seconds. */
void bench_orbit_pose(const struct bench_orbit *o, double t, float out[16]);

#endif
