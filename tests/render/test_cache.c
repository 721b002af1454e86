/* The object cache and compositor (daemon/cache.h) against full renders:
 * random sequences of objects created, left unchanged, moved (by arbitrary
 * transforms and by rotations about the axis of whole slice steps),
 * recoloured, given new vertex data, hidden and shown again, deleted, and
 * deleted several at once (a client disconnecting), with budgets from
 * roomy to tiny (evictions) and none; every composed volume must be bit for
 * bit the renderer's full render of the same scene, and the cache follows
 * no deleted object once it is done (cache_forget_orphans()). One draw in
 * eight is a grid (scene.h, SCENE_GRID). The CPU renderer at two geometries; the GL
 * renderers, each against its own full render, when they run here (grids
 * drawn from their 3-D textures, objects composed as any others). And
 * with a calibration's axis offset that changes now and then
 * (cache_set_offset()): every volume against the full render moved. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cache.h"
#include "check.h"
#include "compose.h"
#include "draw.h"
#include "pool.h"
#include "render.h"
#include "rtest.h"
#include "snapshot.h"
#include "volume_diff.h"

#define MAX_OBJECTS 24
#define MAX_DRAWS 2

static uint64_t rng_state;

static uint32_t rnd(void)
{
	/* splitmix64 */
	uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
	return (uint32_t)((z ^ (z >> 31)) >> 32);
}

static double unit(void)
{
	return rnd() / 4294967296.0;
}

static double range(double a, double b)
{
	return a + (b - a) * unit();
}

struct tobj {
	bool alive, visible;
	uint64_t key;
	uint32_t ndraws;
	struct vdata *data[MAX_DRAWS];
	float transform[16];
	uint8_t rgb[MAX_DRAWS][3];
	uint8_t point_size;
	uint16_t turn; /* scene_draw.turn of its draws */
	int16_t lift;  /* and .lift */
};

struct world {
	const struct geometry *geom;
	bool turns; /* the renderer draws turns (the daemon gives only those turned layers) */
	struct tobj obj[MAX_OBJECTS];
	uint64_t next_key;
	/* The scene as the daemon's snapshot would carry it. */
	struct snapshot snap;
	struct scene_draw draws[MAX_OBJECTS * MAX_DRAWS];
	struct vdata *data[MAX_OBJECTS * MAX_DRAWS];
	struct scene_object objects[MAX_OBJECTS];
};

/* The grid that grid draws show (scene.h, SCENE_GRID): random values, a
 * window that leaves most of them between dark and full. */
static uint8_t grid_values[6 * 5 * 4];
static const struct scene_grid test_grid = { SCENE_GRID_U8, { 6, 5, 4 }, { 0.1f, 0.12f, 0.09f }, grid_values, NULL };
static const struct scene_transfer test_transfer = { .threshold = 40, .lo = 0, .hi = 255 };

static struct vdata *make_data(void)
{
	if (rnd() % 8 == 0) { /* a grid draw: its vdata carries no vertices */
		struct vdata *v = calloc(1, sizeof(*v));
		CHECK(v != NULL);
		*v = (struct vdata){ .refs = 1, .prim = SCENE_GRID };
		return v;
	}
	enum scene_prim prim = (enum scene_prim)(rnd() % 3);
	uint32_t per = prim == SCENE_POINTS ? 1 : prim == SCENE_LINES ? 2 : 3;
	uint32_t prims = 1 + rnd() % 12;
	uint32_t count = prims * per;
	/* One block, as draw.c makes it: vdata_unref() frees it whole, prim_rgb
	 * included, whoever holds the last reference (the cache, often). */
	struct vdata *v = calloc(1, sizeof(*v) + count * 3 * sizeof(float) + prims * 3);
	CHECK(v != NULL);
	v->refs = 1;
	v->prim = prim;
	v->count = count;
	v->prims = prims;
	/* Small shapes around a point of the volume. */
	double cx = range(-0.6, 0.6), cy = range(-0.6, 0.6), cz = range(-0.6, 0.6);
	for (uint32_t i = 0; i < count; i++) {
		v->xyz[3 * i] = (float)(cx + range(-0.3, 0.3));
		v->xyz[3 * i + 1] = (float)(cy + range(-0.3, 0.3));
		v->xyz[3 * i + 2] = (float)(cz + range(-0.3, 0.3));
	}
	if (rnd() % 4 == 0) {
		v->prim_rgb = (uint8_t *)(v->xyz + 3 * count);
		for (uint32_t i = 0; i < prims * 3; i++)
			v->prim_rgb[i] = (uint8_t)rnd();
	}
	return v;
}

static void free_data(struct vdata *v)
{
	vdata_unref(v);
}

static void random_transform(float t[16])
{
	double a = range(0, 2 * M_PI), s = range(0.5, 1.3);
	memset(t, 0, 16 * sizeof(float));
	t[0] = (float)(s * cos(a));
	t[2] = (float)(-s * sin(a));
	t[5] = (float)s;
	t[8] = (float)(s * sin(a));
	t[10] = (float)(s * cos(a));
	t[12] = (float)range(-0.2, 0.2);
	t[13] = (float)range(-0.2, 0.2);
	t[14] = (float)range(-0.2, 0.2);
	t[15] = 1;
}

/* t = R_y(steps slices) * t: a turn about the axis by whole images. */
static void turn(const struct geometry *g, float t[16], int steps)
{
	double a = 2 * M_PI * steps / g->images_per_rev;
	double c = cos(a), s = sin(a);
	for (int col = 0; col < 4; col++) {
		double x = t[col * 4], z = t[col * 4 + 2];
		t[col * 4] = (float)(c * x - s * z);
		t[col * 4 + 2] = (float)(s * x + c * z);
	}
}

static void random_colour(uint8_t rgb[3])
{
	for (int c = 0; c < 3; c++) {
		uint32_t r = rnd() % 4;
		rgb[c] = r == 0 ? 0 : r == 1 ? 255 : (uint8_t)rnd();
	}
}

static void create(struct world *w, struct tobj *o)
{
	*o = (struct tobj){ .alive = true, .visible = true, .key = ++w->next_key };
	o->ndraws = 1 + rnd() % MAX_DRAWS;
	for (uint32_t d = 0; d < o->ndraws; d++) {
		o->data[d] = make_data();
		random_colour(o->rgb[d]);
	}
	random_transform(o->transform);
	o->point_size = (uint8_t)(1 + rnd() % 3);
}

static void destroy(struct tobj *o)
{
	for (uint32_t d = 0; d < o->ndraws; d++)
		free_data(o->data[d]);
	*o = (struct tobj){ 0 };
}

/* One random change; returns its name. */
static const char *mutate(struct world *w)
{
	struct tobj *o = &w->obj[rnd() % MAX_OBJECTS];
	if (!o->alive) {
		create(w, o);
		return "create";
	}
	switch (rnd() % 10) {
	case 8: /* turned by whole images, as a layer's turn (turn.h) */
		if (!w->turns)
			return "unchanged";
		o->turn = (uint16_t)((o->turn + 1 + rnd() % 7) % w->geom->images_per_rev);
		return "spin";
	case 9: /* moved along the axis by whole rows, as a layer's lift */
		if (!w->turns)
			return "unchanged";
		o->lift = (int16_t)((int)(rnd() % 41) - 20);
		return "bob";
	case 0:
		random_transform(o->transform);
		return "move";
	case 1:
	case 2:
		turn(w->geom, o->transform, 1 + (int)(rnd() % 5));
		return "turn";
	case 3:
		random_colour(o->rgb[rnd() % o->ndraws]);
		return "colour";
	case 4: {
		uint32_t d = rnd() % o->ndraws;
		free_data(o->data[d]);
		o->data[d] = make_data();
		return "data";
	}
	case 5:
		o->visible = !o->visible;
		return "hide/show";
	case 6:
		destroy(o);
		return "delete";
	default: /* a client with several objects goes */
		for (int i = 0; i < 3; i++)
			destroy(&w->obj[rnd() % MAX_OBJECTS]);
		return "disconnect";
	}
}

static void build(struct world *w)
{
	uint32_t nd = 0, no = 0;
	for (int i = 0; i < MAX_OBJECTS; i++) {
		const struct tobj *o = &w->obj[i];
		if (!o->alive || !o->visible)
			continue;
		w->objects[no++] = (struct scene_object){ .key = o->key, .first_draw = nd, .draw_count = o->ndraws };
		for (uint32_t d = 0; d < o->ndraws; d++) {
			struct scene_draw *sd = &w->draws[nd];
			*sd = (struct scene_draw){
				.prim = o->data[d]->prim,
				.count = o->data[d]->count,
				.xyz = o->data[d]->xyz,
				.point_size = o->point_size,
				.turn = o->turn,
				.lift = o->lift,
				.prim_rgb = o->data[d]->prim_rgb,
			};
			if (sd->prim == SCENE_GRID) {
				sd->grid = &test_grid;
				sd->transfer = test_transfer;
			}
			memcpy(sd->transform, o->transform, sizeof(sd->transform));
			memcpy(sd->rgb, o->rgb[d], 3);
			w->data[nd++] = o->data[d];
		}
	}
	w->snap.draws = w->draws;
	w->snap.data = w->data;
	w->snap.objects = w->objects;
	w->snap.scene =
		(struct scene){ .draw_count = nd, .draws = w->draws, .object_count = no, .objects = w->objects };
}

struct run_totals {
	unsigned volumes;
	struct cache_stats st;
	unsigned stamped; /* images an upload would skip comparing (volume.h) */
	unsigned hinted;  /* uploads told which tiles may differ (cache_may_differ()) */
};

/* Images of a and b that carry the same stamp (not 0) and differ: an
 * upload of a against b would skip them, and lose the difference. */
static unsigned stamp_lies(const struct volume *a, const struct volume *b, unsigned *same)
{
	unsigned n = 0;
	for (uint32_t k = 0; k < a->image_count; k++) {
		const struct volume_image *x = &a->images[k], *y = &b->images[k];
		if (!x->stamp || x->stamp != y->stamp)
			continue;
		*same += 1;
		n += x->tile_count != y->tile_count || memcmp(x->mask, y->mask, a->mask_bytes) ||
		     (x->tile_count && memcmp(x->tiles, y->tiles, (size_t)x->tile_count * VOLUME_TILE_BYTES));
	}
	return n;
}

static void print_totals(const struct renderer *r, uint64_t budget, const struct run_totals *t)
{
	const struct geometry *g = &r->geom;
	printf("%s %ux%u N=%u budget %llu: %u volumes, %u objects followed, %u cached (%llu bytes); hits %llu, "
	       "turned %llu, misses %llu, creates %llu (batched %llu), invalidations %llu, evictions %llu, expired "
	       "%llu; %u images an upload would skip comparing, %u uploads told where tiles may differ\n",
	       r->impl->name, g->width, g->height, g->images_per_rev, (unsigned long long)budget, t->volumes,
	       t->st.objects, t->st.cached, (unsigned long long)t->st.bytes, (unsigned long long)t->st.hits,
	       (unsigned long long)t->st.turned, (unsigned long long)t->st.misses, (unsigned long long)t->st.creates,
	       (unsigned long long)t->st.batched, (unsigned long long)t->st.invalidations,
	       (unsigned long long)t->st.evictions, (unsigned long long)t->st.expired, t->stamped, t->hinted);
}

/* The axis offsets run() gives the cache in turn when axis_moves (a new
 * one every AXIS_STEPS volumes): parts of a tile, none, past a tile, a
 * whole tile across. */
static bool axis_moves;
#define AXIS_STEPS 23
static const int32_t axis_offsets[][2] = { { 3, -2 }, { 0, 0 }, { -17, 33 }, { 32, -5 } };

/* The volumes a run passes round: handed out in turn, as the pipeline
 * passes its own (the cache patches into one only what changed since it
 * last had it), now and then one swapped with the full render's, whose
 * contents the cache did not make; the full render (moved through raw
 * when there is an axis offset); and what the projector's buffers hold,
 * copies of the last volumes handed out (stamps and all), the bases of
 * the pipeline's uploads. */
struct run_vols {
	struct volume *outs[3], *full, *raw, *sent[4];
	struct tile_set differ; /* cache_may_differ()'s marks */
};

static void vols_create(struct run_vols *v, const struct geometry *g)
{
	struct volume **all[] = { &v->outs[0], &v->outs[1], &v->outs[2], &v->full,   &v->raw,
				  &v->sent[0], &v->sent[1], &v->sent[2], &v->sent[3] };
	for (size_t i = 0; i < sizeof(all) / sizeof(all[0]); i++)
		CHECK((*all[i] = volume_create(g)) != NULL);
	CHECK_EQ(tile_set_init(&v->differ, v->full->image_count, volume_tiles_per_image(v->full)), 0);
}

static void vols_destroy(struct run_vols *v)
{
	for (int i = 0; i < 3; i++)
		volume_destroy(v->outs[i]);
	for (int i = 0; i < 4; i++)
		volume_destroy(v->sent[i]);
	volume_destroy(v->full);
	volume_destroy(v->raw);
	tile_set_finish(&v->differ);
}

/* stamp_lies() of composed against the other volumes handed out (outs)
 * and the copies of those sent before (sent, with their origin marks),
 * and, against the sent ones the cache says it knows (counted in
 * *hinted), the tiles that differ where it says they do not: an upload
 * told so would skip them, and lose the difference. */
static unsigned upload_lies(const struct cache *c, const struct volume *composed, struct run_vols *v, unsigned *same,
			    unsigned *hinted)
{
	unsigned lies = 0;
	for (int i = 0; i < 4; i++) {
		lies += stamp_lies(composed, v->sent[i], same);
		if (!cache_may_differ(c, v->sent[i], composed, &v->differ))
			continue;
		*hinted += 1;
		lies += (unsigned)volume_differences(composed, v->sent[i], v->differ.mask, NULL, NULL);
		tile_set_clear(&v->differ);
	}
	for (int i = 0; i < 3; i++)
		lies += v->outs[i] != composed ? stamp_lies(composed, v->outs[i], same) : 0;
	return lies;
}

/* Volume s's changes to w: often none (that is what gets cached),
 * sometimes several; a turntable (the first object turns a step every
 * volume) and a bobber (the second moves up and down a row at a time).
 * What changed last, for messages. */
static const char *change(struct world *w, unsigned s)
{
	unsigned changes = rnd() % 3 == 0 ? 1 + rnd() % 3 : 0;
	const char *what = "unchanged";
	for (unsigned i = 0; i < changes; i++)
		what = mutate(w);
	if (w->turns && w->obj[0].alive)
		w->obj[0].turn = (uint16_t)((w->obj[0].turn + 1) % w->geom->images_per_rev);
	if (w->turns && w->obj[1].alive)
		w->obj[1].lift = (int16_t)(abs((int)(s % 24) - 12) - 6);
	build(w);
	return what;
}

/* The cache follows no more objects than w has: the world's scene holds
 * no references, so a deleted object's data is the cache's alone, and its
 * entry goes now. */
static void check_followed(struct cache *c, const struct world *w, unsigned s, const char *what)
{
	cache_forget_orphans(c);
	struct cache_stats now;
	cache_get_stats(c, &now);
	unsigned alive = 0;
	for (int i = 0; i < MAX_OBJECTS; i++)
		alive += w->obj[i].alive;
	CHECK_MSG(now.objects <= alive, "step %u (%s): %u objects followed, %u alive", s, what, now.objects, alive);
}

/* steps volumes of random changes through a cache of budget bytes on r,
 * composing on pool (or on this thread: NULL), as the daemon's pipeline
 * does; each composed volume against r's full render. */
static void run(struct renderer *r, struct pool *pool, uint64_t budget, unsigned steps, uint64_t seed,
		struct run_totals *out)
{
	static const int32_t none[2] = { 0, 0 };
	const struct geometry *g = &r->geom;
	rng_state = seed;
	struct world w = { .geom = g, .turns = r->impl->render_canvas != NULL };
	struct cache *c = cache_create(g, budget, pool, r->impl->render_canvas != NULL);
	CHECK(c != NULL);
	struct run_vols v;
	vols_create(&v, g);
	unsigned lies = 0, same = 0, bad = 0, hinted = 0;
	for (int i = 0; i < MAX_OBJECTS / 2; i++)
		create(&w, &w.obj[i]);
	for (unsigned s = 0; s < steps; s++) {
		const char *what = change(&w, s);
		const int32_t *off = axis_moves ? axis_offsets[s / AXIS_STEPS % 4] : none;
		cache_set_offset(c, off[0], off[1]);
		CHECK_EQ(cache_plan(c, &w.snap), 0);
		struct volume *composed = v.outs[s % 3];
		int err = cache_render(c, r, &w.snap.scene, composed);
		cache_done(c, err);
		CHECK_EQ(err, 0);
		check_followed(c, &w, s, what);
		lies += upload_lies(c, composed, &v, &same, &hinted);
		CHECK_EQ(volume_copy(v.sent[s % 4], composed), 0);
		v.sent[s % 4]->origin = composed->origin; /* as the buffer holds it */
		CHECK_EQ(render_volume_moved(r, &w.snap.scene, v.raw, v.full, off[0], off[1]), 0);
		if (!rtest_same(composed, v.full) && bad++ < 5)
			printf("  %s: step %u (%s): composed volume differs from the full render\n", r->impl->name, s,
			       what);
		if (s % 7 == 3) {
			struct volume *next = v.outs[(s + 1) % 3];
			v.outs[(s + 1) % 3] = v.full;
			v.full = next;
		}
	}
	CHECK_EQ(bad, 0);
	CHECK_MSG(lies == 0, "%u images or tiles an upload would take for unchanged and are not", lies);
	cache_get_stats(c, &out->st);
	out->volumes = steps;
	out->stamped = same;
	out->hinted = hinted;
	print_totals(r, budget, out);
	CHECK(out->st.bytes <= budget || out->st.cached == 0);
	cache_destroy(c);
	for (int i = 0; i < MAX_OBJECTS; i++)
		if (w.obj[i].alive)
			destroy(&w.obj[i]);
	vols_destroy(&v);
}

/* The tiles any of the n volumes has, image by image. */
static uint64_t tiles_in(struct volume *const *v, unsigned n)
{
	uint64_t count = 0;
	for (uint32_t k = 0; k < v[0]->image_count; k++)
		for (uint32_t i = 0; i < v[0]->mask_bytes; i++) {
			unsigned any = 0;
			for (unsigned j = 0; j < n; j++)
				any |= v[j]->images[k].mask[i];
			count += (uint64_t)__builtin_popcount(any);
		}
	return count;
}

/* Object 1 of w, small, at x and rendered alone into out. */
static void small_at(struct renderer *r, struct world *w, double x, struct volume *out)
{
	float *t = w->obj[1].transform;
	memset(t, 0, 16 * sizeof(float));
	t[0] = t[5] = t[10] = 0.2f;
	t[12] = (float)x;
	t[15] = 1;
	build(w);
	const struct scene_object *o = &w->snap.scene.objects[1];
	struct scene alone = { .draw_count = o->draw_count, .draws = w->snap.scene.draws + o->first_draw };
	CHECK_EQ(render_volume(r, &alone, out), 0);
}

/* Volume s of w through c into v's outs[s % 3], against the full render;
 * c's counts after. */
static struct cache_stats hand_out(struct renderer *r, struct cache *c, struct world *w, struct run_vols *v, unsigned s)
{
	struct cache_stats st;
	CHECK_EQ(cache_plan(c, &w->snap), 0);
	int err = cache_render(c, r, &w->snap.scene, v->outs[s % 3]);
	cache_done(c, err);
	CHECK_EQ(err, 0);
	CHECK_EQ(render_volume(r, &w->snap.scene, v->full), 0);
	CHECK(rtest_same(v->outs[s % 3], v->full));
	cache_get_stats(c, &st);
	return st;
}

/* A small object moving every volume beside a static one, the volumes
 * handed out in turn as the pipeline passes them: each is patched where
 * the small one lit in the composition it holds and where it lights now,
 * not where it passed in between (cache_render.c, patch_since()), and
 * the composition stays exact. */
static void test_patch_places(struct renderer *r, struct pool *pool)
{
	const struct geometry *g = &r->geom;
	rng_state = 21;
	struct world w = { .geom = g };
	struct cache *c = cache_create(g, 64u << 20, pool, false);
	struct volume *lit[4];
	struct run_vols v;
	CHECK(c != NULL);
	vols_create(&v, g);
	for (int i = 0; i < 4; i++)
		CHECK((lit[i] = volume_create(g)) != NULL);
	create(&w, &w.obj[0]);
	create(&w, &w.obj[1]);
	struct cache_stats st = { 0 };
	unsigned created = 0, checked = 0, fewer = 0;
	for (unsigned s = 0; s < 48; s++) {
		small_at(r, &w, -0.75 + 0.3 * (s % 6), lit[s % 4]);
		uint64_t creates = st.creates;
		st = hand_out(r, c, &w, &v, s);
		created = st.creates != creates ? s : created;
		if (s < created + 3 || st.last_reused != 1 || st.last_rendered != 1)
			continue; /* the held composition from before the static one was cached */
		/* Where it lit volumes s - 3 (held) and s (now); and also
		 * s - 2 and s - 1, which the patch need not touch. */
		struct volume *ends[2] = { lit[(s + 1) % 4], lit[s % 4] };
		CHECK_EQ(st.last_composed, tiles_in(ends, 2));
		fewer += tiles_in(lit, 4) > st.last_composed;
		checked++;
	}
	CHECK(checked >= 30);
	CHECK(fewer > 0);
	printf("patch places: %u volumes checked, %u fewer tiles than where it lit since, %llu composed in all\n",
	       checked, fewer, (unsigned long long)st.composed);
	for (int i = 0; i < 4; i++)
		volume_destroy(lit[i]);
	vols_destroy(&v);
	cache_destroy(c);
	destroy(&w.obj[0]);
	destroy(&w.obj[1]);
}

/* Patches on a pool's workers (every one, however few its tiles): the
 * composition of sources 0-2 patched where sources 3-5 light is the render
 * of all six, all, and patched back where they light without them, the
 * composition of 0-2 again. */
static void patch_on_pool(const struct geometry *g, const struct volume *all, const struct compose_source src[6])
{
	struct pool *pool = pool_create(2);
	struct compose *par = compose_create(g, pool), *ser = compose_create(g, NULL);
	struct volume *out = volume_create(g), *three = volume_create(g);
	struct tile_set dirty;
	CHECK(pool && par && ser && out && three);
	CHECK_EQ(tile_set_init(&dirty, out->image_count, volume_tiles_per_image(out)), 0);
	compose_set_few_tiles(par, 0, 0);
	CHECK_EQ(compose_volumes(par, out, src, 6), 0);
	CHECK(rtest_same(all, out));
	CHECK_EQ(compose_volumes(ser, three, src, 3), 0);
	CHECK_EQ(compose_volumes(par, out, src, 3), 0);
	CHECK(rtest_same(three, out));
	for (int i = 3; i < 6; i++)
		compose_add_footprint(&dirty, &src[i]);
	CHECK(dirty.listed > 0);
	CHECK_EQ(compose_patch(par, out, &dirty, src, 6), 0);
	CHECK(rtest_same(all, out));
	CHECK_EQ(compose_patch(par, out, &dirty, src, 3), 0);
	CHECK(rtest_same(three, out));
	tile_set_finish(&dirty);
	volume_destroy(three);
	volume_destroy(out);
	compose_destroy(ser);
	compose_destroy(par);
	pool_destroy(pool);
}

/* The run-length code round trip, and composing volumes by OR. */
static void test_codec(void)
{
	struct geometry g = rtest_small();
	rng_state = 7;
	struct world w = { .geom = &g };
	for (int i = 0; i < 6; i++)
		create(&w, &w.obj[i]);
	build(&w);
	struct volume *v = rtest_render(&g, w.draws, w.snap.scene.draw_count, 2);
	struct rle_volume *r = rle_volume_encode(v);
	CHECK(r != NULL);
	struct volume *back = volume_create(&g);
	CHECK_EQ(rle_volume_decode(r, back), 0);
	CHECK(rtest_same(v, back));
	printf("codec: %llu tiles, %llu bytes packed, %llu coded (%.1f%%)\n", (unsigned long long)r->tiles,
	       (unsigned long long)r->packed_bytes, (unsigned long long)r->bytes,
	       100.0 * (double)r->bytes / (double)(r->packed_bytes ? r->packed_bytes : 1));
	CHECK(r->bytes < r->packed_bytes);
	/* The OR of each object rendered alone is the render of all. */
	struct compose *cmp = compose_create(&g, NULL);
	struct volume *parts[6];
	struct compose_source src[7];
	for (int i = 0; i < 6; i++) {
		const struct scene_object *o = &w.objects[i];
		parts[i] = rtest_render(&g, w.draws + o->first_draw, o->draw_count, 1);
		src[i] = i % 2 ? (struct compose_source){ .vol = parts[i] } : (struct compose_source){ .rle = NULL };
		if (i % 2 == 0) {
			struct rle_volume *pr = rle_volume_encode(parts[i]);
			CHECK(pr != NULL);
			src[i] = (struct compose_source){ .rle = pr };
		}
	}
	CHECK_EQ(compose_volumes(cmp, back, src, 6), 0);
	CHECK(rtest_same(v, back));
	src[6] = (struct compose_source){ .vol = back };
	CHECK(compose_volumes(cmp, back, src, 7) < 0); /* out among the sources */
	patch_on_pool(&g, v, src);
	for (int i = 0; i < 6; i++) {
		if (i % 2 == 0)
			rle_volume_free((struct rle_volume *)src[i].rle);
		volume_destroy(parts[i]);
	}
	compose_destroy(cmp);
	rle_volume_free(r);
	volume_destroy(back);
	volume_destroy(v);
	for (int i = 0; i < MAX_OBJECTS; i++)
		if (w.obj[i].alive)
			destroy(&w.obj[i]);
}

/* Whether s lists exactly its flagged images, each once, and has no
 * mark outside them. */
static bool tile_set_sound(const struct tile_set *s)
{
	uint32_t flagged = 0;
	uint8_t *seen = calloc(s->image_count, 1);
	bool ok = seen != NULL;
	for (uint32_t p = 0; ok && p < s->listed; p++) {
		uint32_t k = s->list[p];
		ok = k < s->image_count && s->images[k] && !seen[k];
		if (ok)
			seen[k] = 1;
	}
	for (uint32_t k = 0; ok && k < s->image_count; k++) {
		flagged += s->images[k] != 0;
		ok = s->images[k] || volume_all_zero(s->mask + (size_t)k * s->mask_bytes, s->mask_bytes);
	}
	free(seen);
	return ok && flagged == s->listed;
}

/* Tile sets keep the list of their flagged images through flag, or,
 * copy, clear and fill, and or/copy give the masks' OR and copy. */
static void test_tile_sets(void)
{
	struct tile_set a, b, c;
	const uint32_t images = 40, tiles = 100; /* 13 mask bytes: a partial word */
	CHECK(tile_set_init(&a, images, tiles) == 0 && tile_set_init(&b, images, tiles) == 0 &&
	      tile_set_init(&c, images, tiles) == 0);
	uint8_t *want = calloc(images, a.mask_bytes);
	rng_state = 11;
	for (int round = 0; round < 20; round++) {
		tile_set_clear(&a);
		CHECK(a.listed == 0 && tile_set_sound(&a));
		tile_set_copy(&b, &a);
		memset(want, 0, (size_t)images * a.mask_bytes);
		for (int i = 0; i < 30; i++) { /* some into a, some into b */
			struct tile_set *s = i % 3 ? &a : &b;
			uint32_t k = rnd() % images, t = rnd() % tiles;
			uint8_t *m = tile_set_flag(s, k);
			if (rnd() % 4) { /* else flagged with no mark */
				m[t / 8] |= (uint8_t)(1u << (t % 8));
				want[(size_t)k * a.mask_bytes + t / 8] |= (uint8_t)(1u << (t % 8));
			}
		}
		CHECK(tile_set_sound(&a) && tile_set_sound(&b));
		tile_set_copy(&c, &a); /* c had the last round's marks */
		CHECK(tile_set_sound(&c) && c.listed == a.listed);
		CHECK(!memcmp(c.mask, a.mask, (size_t)images * a.mask_bytes));
		tile_set_or(&c, &b);
		CHECK(tile_set_sound(&c));
		CHECK(!memcmp(c.mask, want, (size_t)images * a.mask_bytes));
		for (uint32_t k = 0; k < images; k++)
			CHECK_EQ(tile_set_image_any(&c, k),
				 !volume_all_zero(want + (size_t)k * a.mask_bytes, a.mask_bytes));
	}
	tile_set_fill(&c);
	CHECK(c.listed == images && tile_set_sound(&c));
	tile_set_clear(&c);
	CHECK(c.listed == 0 && tile_set_sound(&c) && volume_all_zero(c.mask, (size_t)images * c.mask_bytes));
	free(want);
	tile_set_finish(&a);
	tile_set_finish(&b);
	tile_set_finish(&c);
}

/* The CPU renderer's runs: on two workers, new entries rendered side by
 * side (batch.h), as in the daemon; then on this thread alone; a tight
 * budget, none; the axis offset; an odd geometry. */
static void runs_cpu(struct pool *pool)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	struct run_totals t;
	struct renderer *cpu = render_cpu_create(&small, 2);
	CHECK(cpu != NULL);
	test_patch_places(cpu, pool);
	run(cpu, pool, 64u << 20, 160, 1, &t);
	CHECK(t.st.hits > 0 && t.st.creates > 0 && t.st.invalidations > 0 && t.st.expired > 0);
	CHECK(t.st.turned > 0); /* turned objects composed from their canvases */
	CHECK(t.st.batched > 0);
	CHECK(t.stamped > 0 && t.hinted > 0);  /* uploads skip what did not change */
	run(cpu, NULL, 40u << 10, 120, 2, &t); /* a few entries at a time */
	CHECK(t.st.evictions > 0);
	run(cpu, NULL, 0, 40, 3, &t); /* nothing may be cached */
	CHECK_EQ(t.st.batched, 0);
	CHECK_EQ(t.st.creates, 0);
	axis_moves = true; /* composed moved, entries dropped when it changes */
	run(cpu, pool, 64u << 20, 120, 13, &t);
	CHECK(t.st.hits > 0 && t.st.turned > 0 && t.st.batched > 0);
	axis_moves = false;
	render_destroy(cpu);
	cpu = render_cpu_create(&odd, 1);
	CHECK(cpu != NULL);
	run(cpu, pool, 64u << 20, 100, 4, &t);
	render_destroy(cpu);
}

/* The brightness models weight and thin what primitives light
 * (brightness.h): composing stays exact, turned canvases included. */
static void runs_brightness(struct pool *pool)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	struct run_totals t;
	small.brightness = GEOMETRY_BRIGHTNESS_EVEN;
	odd.brightness = GEOMETRY_BRIGHTNESS_UNIFORM;
	const struct geometry *bright[] = { &small, &odd };
	for (int i = 0; i < 2; i++) {
		struct renderer *cpu = render_cpu_create(bright[i], 2);
		CHECK(cpu != NULL);
		run(cpu, pool, 64u << 20, 100, 9 + (uint64_t)i, &t);
		CHECK(t.st.hits > 0 && t.st.turned > 0);
		render_destroy(cpu);
	}
}

/* Each GL renderer that is here against its own full render: exact, in
 * the even model too, with the axis offset (GL renders, the cache moves
 * on the CPU), and over its CPU fallback. */
static void runs_gl(struct pool *pool)
{
	struct geometry small = rtest_small();
	struct run_totals t;
	const char *gl[] = { "egl", "osmesa" };
	for (int i = 0; i < 2; i++) {
		struct render_gl_options o = { .backend = gl[i], .threads = 2, .no_fallback = true };
		struct renderer *r = render_gl_create(&small, &o);
		if (!r) {
			printf("%s: not here, skipped\n", gl[i]);
			continue;
		}
		run(r, pool, 64u << 20, 60, 5 + (uint64_t)i, &t);
		CHECK(t.st.hits > 0);
		if (i == 0) {
			axis_moves = true;
			run(r, pool, 64u << 20, 50, 15, &t);
			CHECK(t.st.hits > 0);
			axis_moves = false;
		}
		render_destroy(r);
		/* GL weights and thresholds depend on the primitive and the
		 * image only, so composing stays exact. */
		struct geometry even = small;
		even.brightness = GEOMETRY_BRIGHTNESS_EVEN;
		r = render_gl_create(&even, &o);
		CHECK(r != NULL);
		run(r, pool, 64u << 20, 60, 11 + (uint64_t)i, &t);
		CHECK(t.st.hits > 0);
		render_destroy(r);
		/* Scenes over max_prims go to the CPU fallback, single objects
		 * stay on GL: parts of two engines are never composed. */
		o.no_fallback = false;
		o.max_prims = 64;
		r = render_gl_create(&small, &o);
		CHECK(r != NULL);
		run(r, NULL, 64u << 20, 40, 7 + (uint64_t)i, &t);
		render_destroy(r);
	}
}

int main(void)
{
	test_tile_sets();
	test_codec();
	for (size_t i = 0; i < sizeof(grid_values); i++)
		grid_values[i] = (uint8_t)rnd();
	struct pool *pool = pool_create(2);
	CHECK(pool != NULL);
	runs_cpu(pool);
	runs_brightness(pool);
	runs_gl(pool);
	pool_destroy(pool);
	return check_done();
}
