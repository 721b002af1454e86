/* spindle-bench-cache: the object cache and compositor (daemon/cache.h)
 * through the code the daemon runs (cache_plan, cache_render, cache_done
 * around the CPU renderer), at perspecta, against full renders of the
 * same scenes in the same run. See bench/README.md.
 *
 *   build/bench/spindle-bench-cache [--volumes N] [--seconds S] [--profile P] [--round R] [--gap US]
 *                                   [--only dragon|beside|s4] [--bunny BUNNY.ply] DRAGON.ply */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cache.h"
#include "draw.h"
#include "log.h"
#include "pool.h"
#include "render.h"
#include "rng.h"
#include "scenes.h"
#include "shapes.h"
#include "snapshot.h"
#include "turn.h"

#define MAX_OBJECTS 1024

/* A scene of objects, one draw each, as the daemon's snapshot carries it. */
struct bscene {
	struct snapshot snap;
	struct scene_draw draws[MAX_OBJECTS];
	struct scene_object objects[MAX_OBJECTS];
	struct vdata *data[MAX_OBJECTS];
	uint32_t n;
};

static struct vdata *token(void)
{
	struct vdata *v = calloc(1, sizeof(*v)); /* only counted: identity is the xyz pointer */
	if (!v)
		abort();
	v->refs = 1;
	return v;
}

static void bscene_add(struct bscene *b, const struct scene_draw *d)
{
	uint32_t i = b->n++;
	b->draws[i] = *d;
	b->objects[i] = (struct scene_object){ .key = i + 1, .first_draw = i, .draw_count = 1 };
	b->data[i] = token();
	b->snap.draws = b->draws;
	b->snap.data = b->data;
	b->snap.objects = b->objects;
	b->snap.scene =
		(struct scene){ .draw_count = b->n, .draws = b->draws, .object_count = b->n, .objects = b->objects };
}

static void bscene_free(struct bscene *b)
{
	for (uint32_t i = 0; i < b->n; i++)
		vdata_unref(b->data[i]);
}

/* Volumes a series renders into in turn (--round; the default as the
 * daemon's pipeline passes its own round: with the simulated perspecta
 * device's three buffers each comes back to be rendered into three
 * volumes after it was handed out, counted in spindled beside the dragon
 * under bench/beside). The cache then patches a volume where the last R
 * compositions changed (cache.h). 1: one volume, patched where the last
 * composition changed. */
#define ROUND_DEFAULT 3
#define ROUND_MAX 8

/* The series of a small object beside the dragon measure at least this
 * many volumes (within --seconds): their volumes take well under a
 * millisecond, and --volumes' 100 would be over before the state the
 * dragon's full renders leave the machine in has passed. */
#define BESIDE_MIN_VOLUMES 2000

/* A pause after each volume (--gap), in microseconds: the daemon renders a
 * volume a display period, so its workers are asleep when each starts
 * (pool.h), and a volume measured right after another one would find them
 * awake or not as the other left them. */
#define GAP_DEFAULT_US 1000

struct opts {
	unsigned volumes, round, gap_us;
	double seconds;
	const char *profile, *dragon, *bunny;
	const char *only; /* NULL, "dragon", "beside" (its objects beside it) or "s4": the rows to run */
};

struct result {
	unsigned n;
	double median_ms, p99_ms, vol_s;
	double render_ms, compose_ms; /* medians of the cache's split */
	double tiles;                 /* and of the tiles it composed */
	struct cache_stats st;
};

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

typedef void (*animate_fn)(struct bscene *b, uint64_t frame, void *arg);

/* One scene's volumes: rendered with its cache (or whole, cache NULL),
 * animated by fn before each; per measured volume its ms and the cache's
 * split. */
struct series {
	struct cache *cache;
	struct bscene *b;
	animate_fn fn;
	void *arg;
	struct volume *out[ROUND_MAX]; /* its own, passed round (volume n into out[n % round]) */
	unsigned round;
	double *ms, *rms, *cms, *tiles, sum_ms;
};

/* Volume number frame of s into its out[frame % round]; recorded as the
 * nth when warm. */
static void one_volume(struct renderer *r, struct series *s, uint64_t frame, unsigned n, bool warm)
{
	int64_t t0 = now_ns();
	if (s->fn)
		s->fn(s->b, frame, s->arg);
	int err;
	if (s->cache) {
		if (cache_plan(s->cache, &s->b->snap) < 0)
			abort();
		err = cache_render(s->cache, r, &s->b->snap.scene, s->out[frame % s->round]);
		cache_done(s->cache, err);
	} else {
		err = render_volume(r, &s->b->snap.scene, s->out[frame % s->round]);
	}
	if (err < 0) {
		fprintf(stderr, "render failed: %s\n", strerror(-err));
		exit(1);
	}
	if (!warm)
		return;
	s->ms[n] = (double)(now_ns() - t0) / 1e6;
	s->sum_ms += s->ms[n];
	if (s->cache) {
		struct cache_stats st;
		cache_get_stats(s->cache, &st);
		s->rms[n] = st.last_render_us / 1e3;
		s->cms[n] = st.last_compose_us / 1e3;
		s->tiles[n] = (double)st.last_composed;
	}
}

/* The medians of s's n volumes; vol/s from the time they took. */
static void summarise(struct series *s, unsigned n, struct result *res)
{
	qsort(s->ms, n, sizeof(double), cmp_double);
	qsort(s->rms, n, sizeof(double), cmp_double);
	qsort(s->cms, n, sizeof(double), cmp_double);
	qsort(s->tiles, n, sizeof(double), cmp_double);
	*res = (struct result){
		.n = n,
		.median_ms = s->ms[n / 2],
		.p99_ms = s->ms[(unsigned)ceil(0.99 * n) - 1],
		.vol_s = n / (s->sum_ms / 1e3),
		.render_ms = s->rms[n / 2],
		.compose_ms = s->cms[n / 2],
		.tiles = s->tiles[n / 2],
	};
	if (s->cache)
		cache_get_stats(s->cache, &res->st);
}

/* The count series measured a volume each in turn, so that the drift of
 * a shared machine falls on each alike: 3 warm-up volumes each, then until
 * opts' count or time; res[i] is series i's. */
static void measure_series(struct renderer *r, struct series *s, unsigned count, const struct opts *o,
			   struct result *res)
{
	for (unsigned i = 0; i < count; i++) {
		s[i].round = o->round;
		for (unsigned v = 0; v < o->round; v++)
			if (!(s[i].out[v] = volume_create(&r->geom)))
				abort();
		s[i].ms = calloc(o->volumes, sizeof(double));
		s[i].rms = calloc(o->volumes, sizeof(double));
		s[i].cms = calloc(o->volumes, sizeof(double));
		s[i].tiles = calloc(o->volumes, sizeof(double));
		s[i].sum_ms = 0;
		if (!s[i].ms || !s[i].rms || !s[i].cms || !s[i].tiles)
			abort();
	}
	unsigned n = 0;
	int64_t start = 0;
	for (uint64_t frame = 0;; frame++) {
		bool warm = frame >= 3;
		if (warm && !start)
			start = now_ns();
		if (warm && (n == o->volumes || (double)(now_ns() - start) / 1e9 > o->seconds))
			break;
		for (unsigned i = 0; i < count; i++) {
			one_volume(r, &s[i], frame, n, warm);
			if (o->gap_us)
				usleep(o->gap_us);
		}
		n += warm;
	}
	for (unsigned i = 0; i < count; i++) {
		summarise(&s[i], n, &res[i]);
		free(s[i].ms);
		free(s[i].rms);
		free(s[i].cms);
		free(s[i].tiles);
		for (unsigned v = 0; v < s[i].round; v++)
			volume_destroy(s[i].out[v]);
	}
}

/* Volumes of b (animated by fn before each) with the cache (or whole,
 * cache NULL), alone. */
static void measure(struct renderer *r, struct cache *cache, struct bscene *b, animate_fn fn, void *arg,
		    const struct opts *o, struct result *res)
{
	struct series s = { .cache = cache, .b = b, .fn = fn, .arg = arg };
	measure_series(r, &s, 1, o, res);
}

static void row(const char *scene, const char *how, const struct result *r, const char *note)
{
	printf("| %s | %s | %u | %.1f | %.2f | %.2f | ", scene, how, r->n, r->vol_s, r->median_ms, r->p99_ms);
	if (r->st.budget)
		printf("%.2f | %.2f | %llu / %llu | %.1f | %s |\n", r->render_ms, r->compose_ms,
		       (unsigned long long)r->st.hits, (unsigned long long)r->st.misses, r->st.bytes / 1048576.0, note);
	else
		printf(" |  |  |  | %s |\n", note);
	fflush(stdout);
}

/* ---- the scenes ---- */

struct orbiter {
	struct bench_orbit o[MAX_OBJECTS];
	double volume_s;
	uint32_t first;  /* objects before first never move */
	double fraction; /* of the moving ones that move each volume (1: all) */
	struct rng rng;
};

static void pose(struct bscene *b, const struct orbiter *orb, uint32_t i, uint64_t frame)
{
	bench_orbit_pose(&orb->o[i], (double)frame * orb->volume_s, b->draws[i].transform);
}

static void animate_orbits(struct bscene *b, uint64_t frame, void *arg)
{
	struct orbiter *orb = arg;
	for (uint32_t i = orb->first; i < b->n; i++)
		if (orb->fraction >= 1 || rng_unit(&orb->rng) < orb->fraction)
			pose(b, orb, i, frame);
}

/* Object 0 alone moved, on the first orbit (the others stay). */
static void animate_first(struct bscene *b, uint64_t frame, void *arg)
{
	pose(b, arg, 0, frame);
}

/* The dragon turned about the axis by one image step per volume, as the
 * daemon draws a layer whose transform is its base turned by whole images
 * (turn.h: the base stays, the turn is an image shift). */
static void animate_turntable(struct bscene *b, uint64_t frame, void *arg)
{
	const struct geometry *g = arg;
	double a = 2 * M_PI * (double)frame / g->images_per_rev;
	float t[16] = { 0 }, base[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
	t[0] = (float)cos(a);
	t[2] = (float)sin(a);
	t[5] = 1;
	t[8] = (float)-sin(a);
	t[10] = (float)cos(a);
	t[15] = 1;
	uint32_t m = 0;
	if (!turn_find(base, t, g->images_per_rev, &m))
		abort();
	memcpy(b->draws[0].transform, base, sizeof(base));
	b->draws[0].turn = (uint16_t)m;
}

/* The dragon moved up and down the axis a row per volume (8 rows either
 * way), as the daemon draws a layer whose transform is its base moved by
 * whole rows (turn.h: the base stays, the lift is a row shift). */
static void animate_bob(struct bscene *b, uint64_t frame, void *arg)
{
	(void)arg;
	b->draws[0].lift = (int16_t)(abs((int)(frame % 32) - 16) - 8);
}

static const uint8_t orange[3] = { 255, 128, 0 };

/* A draw of v's triangles in one colour, identity transform. */
static struct scene_draw object_draw(const struct vbuf *v, const uint8_t rgb[3])
{
	struct scene_draw d = { .prim = SCENE_TRIANGLES, .count = v->count, .xyz = v->xyz };
	for (int i = 0; i < 16; i++)
		d.transform[i] = i % 5 == 0;
	memcpy(d.rgb, rgb, 3);
	return d;
}

static long rss_kb(void)
{
	FILE *f = fopen("/proc/self/status", "r");
	char line[256];
	long kb = 0;
	while (f && fgets(line, sizeof(line), f))
		if (sscanf(line, "VmRSS: %ld", &kb) == 1)
			break;
	if (f)
		fclose(f);
	return kb;
}

/* What every scene runs on: the renderer, a fresh cache per scene (on the
 * pool, as the daemon's pipeline composes), the orbits, the icosahedron. */
struct bench {
	struct opts o;
	struct geometry g;
	struct renderer *r;
	struct pool *pool;
	struct orbiter *orb;
	struct vbuf ico;
	struct bscene b;
	struct cache *cache;
};

/* The scene in be->b measured whole and, with a new cache, composed. */
static void measure_cached(struct bench *be, animate_fn fn, void *arg, struct result *res)
{
	cache_destroy(be->cache);
	be->cache = cache_create(&be->g, 256ull << 20, be->pool, true);
	if (!be->cache)
		abort();
	measure(be->r, be->cache, &be->b, fn, arg, &be->o, res);
}

static void reset_scene(struct bench *be)
{
	bscene_free(&be->b);
	memset(&be->b, 0, sizeof(be->b));
}

/* o for the series of a small object beside the dragon. */
static struct opts beside_opts(const struct opts *o)
{
	struct opts many = *o;
	if (many.volumes < BESIDE_MIN_VOLUMES)
		many.volumes = BESIDE_MIN_VOLUMES;
	return many;
}

/* The axis offset of the calibrated rows: the projector's image of the
 * axis 3 columns right and 2 rows up of its centre. */
#define AXIS_DU 3
#define AXIS_DV -2

/* An object moving on the first orbit (be->b) and the same beside the
 * dragon (with), each through a cache of its own, a volume each in turn;
 * with an axis offset (du, dv), as the pipeline gives the cache the
 * calibration's (cache_set_offset()). full: the
 * object's rate rendered whole, for the note (0: none). */
static void cached_pair(struct bench *be, const char *what, struct bscene *with, int32_t du, int32_t dv, double full)
{
	struct result cached[2];
	char alone[96], beside[96], note[192], how[64];
	snprintf(alone, sizeof(alone), "%s alone", what);
	snprintf(beside, sizeof(beside), "dragon (static) + %s", what);
	snprintf(how, sizeof(how), du || dv ? "cache, axis offset (%d, %d)" : "cache", du, dv);
	struct series s[2] = {
		{ .cache = cache_create(&be->g, 256ull << 20, be->pool, true),
		  .b = &be->b,
		  .fn = animate_first,
		  .arg = be->orb },
		{ .cache = cache_create(&be->g, 256ull << 20, be->pool, true),
		  .b = with,
		  .fn = animate_first,
		  .arg = be->orb },
	};
	if (!s[0].cache || !s[1].cache)
		abort();
	cache_set_offset(s[0].cache, du, dv);
	cache_set_offset(s[1].cache, du, dv);
	struct opts many = beside_opts(&be->o);
	measure_series(be->r, s, 2, &many, cached);
	row(alone, how, &cached[0], "the daemon's path; a volume each in turn with the next row");
	int at = snprintf(note, sizeof(note), "%.0f%% of the %s's solo rate through the cache",
			  100 * cached[1].vol_s / cached[0].vol_s, what);
	if (full > 0)
		at += snprintf(note + at, sizeof(note) - (size_t)at, ", %.0f%% of its full render",
			       100 * cached[1].vol_s / full);
	snprintf(note + at, sizeof(note) - (size_t)at, "; %.0f tiles composed a volume", cached[1].tiles);
	row(beside, how, &cached[1], note);
	cache_destroy(s[0].cache);
	cache_destroy(s[1].cache);
}

/* An object moving on the first orbit, alone and beside the static dragon
 * (the scene's object 0, the dragon its object 1), each rendered whole
 * and then through a cache of its own, the two cached ones a volume each
 * in turn; the rate beside the dragon as a share of its own. */
static void beside_dragon(struct bench *be, const char *what, const struct scene_draw *d,
			  const struct scene_draw *dragon)
{
	struct result whole[2];
	char alone[96], beside[96];
	struct bscene *with = calloc(1, sizeof(*with));
	if (!with)
		abort();
	bscene_add(&be->b, d);
	bscene_add(with, d);
	bscene_add(with, dragon);
	snprintf(alone, sizeof(alone), "%s alone", what);
	snprintf(beside, sizeof(beside), "dragon (static) + %s", what);
	measure(be->r, NULL, &be->b, animate_first, be->orb, &be->o, &whole[0]);
	row(alone, "full render", &whole[0], "");
	measure(be->r, NULL, with, animate_first, be->orb, &be->o, &whole[1]);
	row(beside, "full render", &whole[1], "");
	cached_pair(be, what, with, 0, 0, whole[0].vol_s);
	cached_pair(be, what, with, AXIS_DU, AXIS_DV, 0);
	bscene_free(with);
	free(with);
	reset_scene(be);
}

/* The bunny (tests/data/bunny.ply, 69,451 triangles) as a small object of
 * radius about r: its fit to the volume and r baked into its vertices, so
 * that an orbit's pose moves it as it moves the icosahedron. 0 or -1. */
static int small_bunny(struct bench *be, double r, struct vbuf *out)
{
	char err[256];
	struct bench_scene bunny = { 0 };
	struct bench_files files = { .bunny = be->o.bunny };
	if (!be->o.bunny || bench_scene_build("S3-bunny", &be->g, &files, &bunny, err, sizeof(err)) < 0) {
		printf("\n(no bunny: %s)\n", be->o.bunny ? err : "give --bunny bunny.ply");
		return -1;
	}
	const struct scene_draw *d = &bunny.draws[0];
	const float *m = d->transform;
	for (uint32_t i = 0; i < d->count; i++) {
		const float *v = d->xyz + 3 * (size_t)i;
		double p[3];
		for (int a = 0; a < 3; a++)
			p[a] = r *
			       ((double)m[a] * v[0] + (double)m[4 + a] * v[1] + (double)m[8 + a] * v[2] + m[12 + a]);
		vbuf_add(out, p[0], p[1], p[2]);
	}
	bench_scene_free(&bunny);
	return out->oom ? -1 : 0;
}

/* An animated icosahedron and a small animated bunny, each alone and
 * beside the static dragon; the dragon turning one image a volume, and
 * moving a row a volume along the axis. */
static void bench_dragon(struct bench *be)
{
	struct result res;
	char err[256];
	struct scene_draw ico = object_draw(&be->ico, orange);
	struct bench_scene dragon = { 0 };
	struct bench_files files = { .dragon = be->o.dragon };
	if (!be->o.dragon || bench_scene_build("S3-dragon", &be->g, &files, &dragon, err, sizeof(err)) < 0) {
		printf("\n(no dragon: %s)\n", be->o.dragon ? err : "give dragon_vrip.ply");
		return;
	}
	beside_dragon(be, "icosahedron", &ico, &dragon.draws[0]);
	struct vbuf bunny = { 0 };
	if (small_bunny(be, 0.15, &bunny) == 0) {
		struct scene_draw d = object_draw(&bunny, orange);
		beside_dragon(be, "bunny", &d, &dragon.draws[0]);
	}
	vbuf_free(&bunny);
	if (be->o.only && !strcmp(be->o.only, "beside")) {
		bench_scene_free(&dragon);
		return;
	}
	bscene_add(&be->b, &dragon.draws[0]); /* turning one image step per volume */
	measure(be->r, NULL, &be->b, animate_turntable, &be->g, &be->o, &res);
	row("dragon turning one image a volume", "full render", &res, "");
	measure_cached(be, animate_turntable, &be->g, &res);
	row("dragon turning one image a volume", "cache", &res, "");
	reset_scene(be);
	bscene_add(&be->b, &dragon.draws[0]); /* moving a row per volume */
	measure(be->r, NULL, &be->b, animate_bob, NULL, &be->o, &res);
	row("dragon moving a row a volume along the axis", "full render", &res, "");
	measure_cached(be, animate_bob, NULL, &res);
	row("dragon moving a row a volume along the axis", "cache", &res, "");
	reset_scene(be);
	bench_scene_free(&dragon);
}

/* S4: 1,000 icosahedra; all move each volume, or a random 10%. */
static void bench_s4(struct bench *be)
{
	static const uint8_t six[6][3] = { { 255, 0, 0 },   { 0, 255, 0 },   { 0, 0, 255 },
					   { 255, 255, 0 }, { 255, 0, 255 }, { 0, 255, 255 } };
	struct result all, res;
	for (uint32_t i = 0; i < 1000; i++) {
		struct scene_draw di = object_draw(&be->ico, six[i % 6]);
		bscene_add(&be->b, &di);
		pose(&be->b, be->orb, i, 0);
	}
	be->orb->first = 0;
	be->orb->fraction = 1;
	measure(be->r, NULL, &be->b, animate_orbits, be->orb, &be->o, &all);
	row("S4: 1,000 objects, all move", "full render", &all, "");
	be->orb->fraction = 0.1;
	measure(be->r, NULL, &be->b, animate_orbits, be->orb, &be->o, &res);
	row("S4: 1,000 objects, 10% move", "full render", &res, "");
	measure_cached(be, animate_orbits, be->orb, &res);
	char note[128];
	snprintf(note, sizeof(note), "%.2fx the full render of all moving", res.vol_s / all.vol_s);
	row("S4: 1,000 objects, 10% move", "cache", &res, note);
	printf("\nRSS at the end: %.0f MB; cache working volumes %.1f MB.\n", rss_kb() / 1024.0,
	       res.st.working_bytes / 1048576.0);
	reset_scene(be);
}

static int usage(const char *argv0)
{
	fprintf(stderr,
		"usage: %s [--volumes N] [--seconds S] [--profile P] [--round R] [--gap US] [--only dragon|beside|s4] "
		"[--bunny PLY] [DRAGON.ply]\n",
		argv0);
	return 2;
}

/* 0, or the exit status for a bad command line. */
static int parse(int argc, char **argv, struct opts *o)
{
	*o = (struct opts){ .volumes = 100,
			    .round = ROUND_DEFAULT,
			    .gap_us = GAP_DEFAULT_US,
			    .seconds = 4,
			    .profile = "perspecta" };
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--volumes") && i + 1 < argc)
			o->volumes = (unsigned)atoi(argv[++i]);
		else if (!strcmp(argv[i], "--round") && i + 1 < argc)
			o->round = (unsigned)atoi(argv[++i]);
		else if (!strcmp(argv[i], "--gap") && i + 1 < argc)
			o->gap_us = (unsigned)atoi(argv[++i]);
		else if (!strcmp(argv[i], "--seconds") && i + 1 < argc)
			o->seconds = atof(argv[++i]);
		else if (!strcmp(argv[i], "--profile") && i + 1 < argc)
			o->profile = argv[++i];
		else if (!strcmp(argv[i], "--bunny") && i + 1 < argc)
			o->bunny = argv[++i];
		else if (!strcmp(argv[i], "--only") && i + 1 < argc &&
			 (!strcmp(argv[i + 1], "dragon") || !strcmp(argv[i + 1], "beside") ||
			  !strcmp(argv[i + 1], "s4")))
			o->only = argv[++i];
		else if (argv[i][0] != '-')
			o->dragon = argv[i];
		else
			return usage(argv[0]);
	}
	if (o->round < 1 || o->round > ROUND_MAX)
		return usage(argv[0]);
	if (o->volumes < 1)
		o->volumes = 1;
	return 0;
}

static void header(const struct bench *be)
{
	printf("Object cache, %s (%ux%u, N = %u%s), CPU renderer on %u threads; cache budget 256 MiB. Each row: 3 "
	       "warm-up volumes, then up to %u volumes (%u beside the dragon) or %.0f s, into %u volumes in turn (as "
	       "the daemon's pipeline passes them round), %u us apart; ms per volume (plan + render + compose, "
	       "animation "
	       "included), median and p99; vol/s: the volumes over the time they took; render / compose: the cache's "
	       "split, medians; hits / misses: objects, "
	       "summed over the measured volumes; MB: what the cache holds at the end.\n\n",
	       be->o.profile, be->g.width, be->g.height, be->g.images_per_rev, be->g.mirrored ? ", mirrored" : "",
	       be->r->stats.threads, be->o.volumes, beside_opts(&be->o).volumes, be->o.seconds, be->o.round,
	       be->o.gap_us);
	printf("| scene | how | volumes | vol/s | median ms | p99 ms | render ms | compose ms | hits / misses | cache "
	       "MB | |\n|---|---|--:|--:|--:|--:|--:|--:|--:|--:|---|\n");
}

int main(int argc, char **argv)
{
	static struct bench be; /* large: the scenes' arrays */
	int status = parse(argc, argv, &be.o);
	if (status)
		return status;
	if (geometry_from_profile(be.o.profile, &be.g) < 0) {
		fprintf(stderr, "unknown profile %s\n", be.o.profile);
		return 2;
	}
	log_set_level(LOG_LEVEL_WARN);
	be.r = render_cpu_create(&be.g, 0);
	be.pool = be.r ? pool_create(be.r->stats.threads) : NULL;
	be.orb = calloc(1, sizeof(*be.orb));
	if (!be.r || !be.pool || !be.orb)
		return 1;
	header(&be);
	shape_icosahedron(&be.ico, 0.03);
	be.orb->volume_s = 1.0 / (be.g.rpm / 60.0 * (be.g.mirrored ? 2 : 1));
	be.orb->rng = rng_seed(0x5350494e444c4534u);
	for (uint32_t i = 0; i < MAX_OBJECTS; i++)
		bench_orbit_random(&be.orb->o[i], &be.orb->rng, be.g.half_height);
	if (!be.o.only || strcmp(be.o.only, "s4"))
		bench_dragon(&be);
	if (!be.o.only || !strcmp(be.o.only, "s4"))
		bench_s4(&be);
	free(be.orb);
	cache_destroy(be.cache);
	pool_destroy(be.pool);
	render_destroy(be.r);
	vbuf_free(&be.ico);
	return 0;
}
