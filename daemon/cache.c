/* The object cache and compositor (cache.h). */
#include "cache.h"
#include "cache_priv.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "compose.h"
#include "draw.h"
#include "log.h"
#include "pool.h"
#include "renderer.h"
#include "snapshot.h"
#include "volume.h"

/* Volumes in a row an object must come unchanged before it is cached,
 * shifted left by its back-off. */
#define CREATE_AFTER 1
#define MAX_BACKOFF 6 /* waits of up to 64 volumes */
/* Hits a cached volume must have had when its object changes for the
 * caching to have paid: rendering the object alone once costs about what
 * rendering it among the others does (S4 in bench/README.md: 1 gave 1.57x
 * the full render, 2 1.44x, 4 1.30x). Fewer, and the object backs off; as
 * many, and the back-off wears off by one. */
#define PAYOFF_HITS 1
/* Volumes an object may be missing from the scene (a hidden layer) before
 * its entry goes. */
#define IDLE_VOLUMES 24

struct cache *cache_create(const struct geometry *geom, uint64_t budget, struct pool *pool, bool turns)
{
	struct cache *c = calloc(1, sizeof(*c));
	if (!c)
		return NULL;
	c->geom = *geom;
	c->budget = budget;
	c->compose = compose_create(geom, pool);
	c->pool = pool;
	c->turns = turns && c->compose && compose_can_turn(c->compose);
	c->turned_vol = volume_create(geom);
	c->rest_vol = volume_create(geom);
	c->tmp = volume_create(geom);
	uint32_t tiles = c->tmp ? volume_tiles_per_image(c->tmp) : 0, images = c->tmp ? c->tmp->image_count : 0;
	bool marks = c->tmp && tile_set_init(&c->dirty, images, tiles) == 0 &&
		     tile_set_init(&c->since, images, tiles) == 0;
	for (unsigned g = 0; marks && g < CHANGED_HISTORY; g++)
		marks = tile_set_init(&c->changed[g], images, tiles) == 0 &&
			tile_set_init(&c->lit[g], images, tiles) == 0;
	c->stamps = calloc(images ? images : 1, sizeof(*c->stamps));
	if (!c->compose || !c->tmp || !marks || !c->stamps || !c->rest_vol || !c->turned_vol) {
		cache_destroy(c);
		errno = ENOMEM;
		return NULL;
	}
	return c;
}

void cache_add_footprint(struct cache *c, const struct compose_source *src)
{
	compose_add_footprint(&c->dirty, src);
}

/* An entry whose volume is in the last composition leaves it: its tiles
 * there are composed anew next time. */
static void leave_composition(struct cache *c, struct entry *e)
{
	if (!e->in_prev)
		return;
	cache_add_footprint(c, &(struct compose_source){ .rle = e->vol });
	e->in_prev = false;
}

static void drop_volume(struct cache *c, struct entry *e)
{
	if (!e->vol)
		return;
	leave_composition(c, e);
	rle_volume_free(e->vol);
	e->vol = NULL;
}

static void drop_canvas(struct entry *e)
{
	rle_volume_free(e->canvas);
	e->canvas = NULL;
}

static void release_draws(struct entry *e)
{
	for (uint32_t i = 0; i < e->draw_count; i++)
		vdata_unref(e->refs[i]);
	free(e->draws);
	free(e->refs);
	e->draws = NULL;
	e->refs = NULL;
	e->draw_count = 0;
}

static void free_entry(struct cache *c, struct entry *e)
{
	drop_volume(c, e);
	drop_canvas(e);
	release_draws(e);
	free(e);
}

void cache_destroy(struct cache *c)
{
	if (!c)
		return;
	for (uint32_t i = 0; i < c->count; i++)
		free_entry(c, c->entries[i]);
	for (uint32_t i = 0; c->created && i < c->create_count; i++)
		rle_volume_free(c->created[i]);
	for (uint32_t i = 0; c->made_canvas && i < c->canvas_count; i++)
		rle_volume_free(c->made_canvas[i]);
	free(c->turneds);
	free(c->canvases);
	free(c->made_canvas);
	free(c->turned_src);
	free(c->unturned);
	volume_destroy(c->turned_vol);
	free(c->entries);
	free(c->uses);
	free(c->creates);
	free(c->created);
	free(c->created_by);
	free(c->batched);
	batch_destroy(c->batch);
	free(c->rest);
	free(c->sources);
	tile_set_finish(&c->dirty);
	for (unsigned g = 0; g < CHANGED_HISTORY; g++) {
		tile_set_finish(&c->changed[g]);
		tile_set_finish(&c->lit[g]);
	}
	tile_set_finish(&c->since);
	free(c->stamps);
	volume_destroy(c->rest_vol);
	volume_destroy(c->moved);
	volume_destroy(c->tmp);
	compose_destroy(c->compose);
	free(c);
}

/* ---- entries ---- */

/* The index of key, or where it would go. */
static uint32_t find(const struct cache *c, uint64_t key)
{
	uint32_t lo = 0, hi = c->count;
	while (lo < hi) {
		uint32_t mid = lo + (hi - lo) / 2;
		if (c->entries[mid]->key < key)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo;
}

static struct entry *lookup_or_add(struct cache *c, uint64_t key)
{
	uint32_t i = find(c, key);
	if (i < c->count && c->entries[i]->key == key)
		return c->entries[i];
	if (c->count == c->cap) {
		uint32_t cap = c->cap ? c->cap * 2 : 64;
		struct entry **a = realloc(c->entries, cap * sizeof(*a));
		if (!a)
			return NULL;
		c->entries = a;
		c->cap = cap;
	}
	struct entry *e = calloc(1, sizeof(*e));
	if (!e)
		return NULL;
	e->key = key;
	memmove(c->entries + i + 1, c->entries + i, (c->count - i) * sizeof(*c->entries));
	c->entries[i] = e;
	c->count++;
	return e;
}

enum change {
	CHANGED,
	SAME,   /* draw for draw the same */
	TURNED, /* the same but for one turn and lift, common to all its draws, that changed */
};

static enum change compare(const struct entry *e, const struct scene_draw *draws, uint32_t n)
{
	if (e->draw_count != n || n == 0)
		return CHANGED;
	bool same_turn = true;
	for (uint32_t i = 0; i < n; i++) {
		if (!scene_draw_alike(&e->draws[i], &draws[i]) || draws[i].turn != draws[0].turn ||
		    draws[i].lift != draws[0].lift)
			return CHANGED;
		same_turn &= e->draws[i].turn == draws[i].turn && e->draws[i].lift == draws[i].lift;
	}
	return same_turn ? SAME : TURNED;
}

/* The entry now follows these draws (with references to their data). */
static int follow(struct entry *e, const struct scene_draw *draws, struct vdata *const *data, uint32_t n)
{
	struct scene_draw *d = malloc((n ? n : 1) * sizeof(*d)); /* an object may draw nothing */
	struct vdata **refs = malloc((n ? n : 1) * sizeof(*refs));
	if (!d || !refs) {
		free(d);
		free(refs);
		return -ENOMEM;
	}
	if (n)
		memcpy(d, draws, n * sizeof(*d));
	for (uint32_t i = 0; i < n; i++)
		refs[i] = vdata_ref(data[i]);
	release_draws(e);
	e->draws = d;
	e->refs = refs;
	e->draw_count = n;
	return 0;
}

static uint8_t sat_inc(uint8_t v, uint8_t max)
{
	return v < max ? (uint8_t)(v + 1) : max;
}

/* Tile storage a volume has allocated. */
/* Bytes held now against the budget: the coded volumes and the
 * bookkeeping. (The volumes it renders and composes into, the last
 * composition among them, are working storage the size of a volume or
 * two, as the pipeline's own volumes are: counted apart.) */
static uint64_t held(const struct cache *c)
{
	uint64_t b = (uint64_t)c->cap * sizeof(*c->entries) + (uint64_t)c->count * sizeof(struct entry);
	for (uint32_t i = 0; i < c->count; i++) {
		const struct entry *e = c->entries[i];
		b += (uint64_t)e->draw_count * (sizeof(*e->draws) + sizeof(*e->refs));
		if (e->vol)
			b += e->vol->bytes;
		if (e->canvas)
			b += e->canvas->bytes;
	}
	return b;
}

/* Drops the volumes of the least recently used entries not used by the
 * plan being made until the cache holds at most target bytes. An entry
 * evicted backs off as a changed one does: it waits longer before it is
 * cached again, so a budget too small for the scene does not make the
 * cache render objects alone only to throw them away. */
static void evict_to(struct cache *c, uint64_t target)
{
	uint64_t now = held(c);
	while (now > target) {
		struct entry *lru = NULL;
		for (uint32_t i = 0; i < c->count; i++) {
			struct entry *e = c->entries[i];
			bool in_plan = c->planned && (e->role == ROLE_USE || e->role == ROLE_TURNED);
			if ((e->vol || e->canvas) && !in_plan && (!lru || e->last_used < lru->last_used))
				lru = e;
		}
		if (!lru)
			break;
		now -= (lru->vol ? lru->vol->bytes : 0) + (lru->canvas ? lru->canvas->bytes : 0);
		drop_volume(c, lru);
		drop_canvas(lru);
		lru->reuse = 0;
		lru->hits = 0;
		lru->backoff = sat_inc(lru->backoff, MAX_BACKOFF);
		c->stats.evictions++;
	}
}

/* *pp (a pointer to an array) resized to n elements of size bytes; false
 * when out of memory, *pp untouched. */
bool cache_resize(void *pp, size_t n, size_t size)
{
	void **p = pp;
	void *q = realloc(*p, n * size);
	if (!q)
		return false;
	*p = q;
	return true;
}

static int grow_plan(struct cache *c, uint32_t objects)
{
	if (objects <= c->array_cap)
		return 0;
	uint32_t cap = c->array_cap ? c->array_cap : 64;
	while (cap < objects)
		cap *= 2;
	/* The sources: every object's volume, the rest's and the turned. */
	if (!cache_resize(&c->uses, cap, sizeof(*c->uses)) || !cache_resize(&c->creates, cap, sizeof(*c->creates)) ||
	    !cache_resize(&c->created, cap, sizeof(*c->created)) ||
	    !cache_resize(&c->created_by, cap, sizeof(*c->created_by)) ||
	    !cache_resize(&c->batched, cap, sizeof(*c->batched)) ||
	    !cache_resize(&c->turneds, cap, sizeof(*c->turneds)) ||
	    !cache_resize(&c->canvases, cap, sizeof(*c->canvases)) ||
	    !cache_resize(&c->made_canvas, cap, sizeof(*c->made_canvas)) ||
	    !cache_resize(&c->turned_src, cap, sizeof(*c->turned_src)) ||
	    !cache_resize(&c->sources, cap + 2, sizeof(*c->sources)))
		return -ENOMEM;
	c->source_cap = cap + 2;
	c->array_cap = cap;
	return 0;
}

static int add_rest(struct cache *c, const struct scene_draw *draws, uint32_t n)
{
	if (c->rest_count + n > c->rest_cap) {
		uint32_t cap = c->rest_cap ? c->rest_cap : 64;
		while (cap < c->rest_count + n)
			cap *= 2;
		if (!cache_resize(&c->rest, cap, sizeof(*c->rest)))
			return -ENOMEM;
		c->rest_cap = cap;
	}
	if (n)
		memcpy(c->rest + c->rest_count, draws, n * sizeof(*draws));
	c->rest_count += n;
	c->rest_objects++;
	return 0;
}

/* The role of object e, which changed, this volume: its cached result
 * dropped, the back-off moved by whether it paid, the counters restarted.
 * room: the budget has room for new entries. */
static enum role invalidate(struct cache *c, struct entry *e, bool room)
{
	bool paid = false;
	if (e->vol || e->canvas) {
		drop_volume(c, e);
		drop_canvas(e);
		paid = e->hits >= PAYOFF_HITS;
		if (!paid)
			e->backoff = sat_inc(e->backoff, MAX_BACKOFF);
		else if (e->backoff)
			e->backoff--;
		c->stats.invalidations++;
	}
	e->reuse = 0;
	e->hits = 0;
	/* An object whose cached volume paid and that does not back off is
	 * cached again at once, in its new state: it changes now and then,
	 * and rendering it with the rest now and alone next time would
	 * render it twice. */
	return paid && !e->backoff && room ? ROLE_CREATE : ROLE_REST;
}

/* The role of object e this volume, and its state moved on. room: the
 * budget has room for new entries. */
static enum role decide(struct cache *c, struct entry *e, enum change change, bool room)
{
	if (change == CHANGED || (change == TURNED && !c->turns))
		return invalidate(c, e, room);
	/* Unchanged, or only turned: reusable. */
	e->reuse = sat_inc(e->reuse, UINT8_MAX);
	uint32_t wait = (uint32_t)CREATE_AFTER << e->backoff;
	bool ripe = e->reuse >= (wait < UINT8_MAX ? wait : UINT8_MAX) && room;
	if (change == TURNED) {
		drop_volume(c, e); /* rendered at another turn */
		if (e->canvas) {
			e->hits = sat_inc(e->hits, PAYOFF_HITS);
			return ROLE_TURNED;
		}
		return ripe ? ROLE_CANVAS : ROLE_REST;
	}
	if (e->vol) {
		e->hits = sat_inc(e->hits, PAYOFF_HITS);
		return ROLE_USE;
	}
	/* Stopped turning: composed from its canvas until its volume at
	 * this turn is made. */
	if (ripe)
		return ROLE_CREATE;
	return e->canvas ? ROLE_TURNED : ROLE_REST;
}

/* Puts e, in its role, into the plan. */
static int place(struct cache *c, struct entry *e, const struct scene_draw *draws, uint32_t n)
{
	bool hit = e->role == ROLE_USE || e->role == ROLE_TURNED;
	c->stats.hits += hit;
	c->stats.misses += !hit;
	if (e->role != ROLE_REST)
		e->last_used = c->plan_seq;
	switch (e->role) {
	case ROLE_TURNED:
		c->turneds[c->turned_count++] = e;
		c->stats.turned++;
		return 0;
	case ROLE_CANVAS:
		c->canvases[c->canvas_count++] = e;
		return 0;
	case ROLE_USE:
		c->uses[c->use_count++] = e;
		if (!e->in_prev) /* back in the scene */
			cache_add_footprint(c, &(struct compose_source){ .rle = e->vol });
		return 0;
	case ROLE_CREATE:
		c->creates[c->create_count++] = e;
		return 0;
	case ROLE_REST:
		break;
	}
	return add_rest(c, draws, n);
}

/* Objects missing from the scene: kept a while (a layer hidden and shown
 * again), then forgotten. They leave the composition. */
static void sweep_absent(struct cache *c)
{
	for (uint32_t i = 0; i < c->count;) {
		struct entry *e = c->entries[i];
		if (!e->seen) {
			e->role = ROLE_REST;
			leave_composition(c, e);
			e->absent = sat_inc(e->absent, UINT8_MAX);
			if (e->absent > IDLE_VOLUMES) {
				free_entry(c, e);
				memmove(c->entries + i, c->entries + i + 1, (c->count - i - 1) * sizeof(*c->entries));
				c->count--;
				c->stats.expired++;
				continue;
			}
		}
		i++;
	}
}

int cache_plan(struct cache *c, const struct snapshot *snap)
{
	const struct scene *s = &snap->scene;
	c->planned = false;
	c->plan_seq++;
	c->use_count = c->create_count = c->rest_count = c->rest_objects = 0;
	c->turned_count = c->canvas_count = 0;
	if (grow_plan(c, s->object_count) < 0)
		return -ENOMEM;
	for (uint32_t i = 0; i < c->count; i++)
		c->entries[i]->seen = false;
	bool room = held(c) < c->budget;
	for (uint32_t o = 0; o < s->object_count; o++) {
		const struct scene_object *obj = &s->objects[o];
		const struct scene_draw *draws = s->draws + obj->first_draw;
		struct entry *e = lookup_or_add(c, obj->key);
		if (!e)
			return -ENOMEM;
		bool fresh = e->draw_count == 0 && !e->draws;
		enum change change = fresh ? CHANGED : compare(e, draws, obj->draw_count);
		if (change != SAME && follow(e, draws, snap->data + obj->first_draw, obj->draw_count) < 0)
			return -ENOMEM;
		e->seen = true;
		e->absent = 0;
		e->first_draw = obj->first_draw;
		e->turn = obj->draw_count ? draws[0].turn : 0;
		e->lift = obj->draw_count ? draws[0].lift : 0;
		e->role = decide(c, e, change, room);
		if (place(c, e, draws, obj->draw_count) < 0)
			return -ENOMEM;
	}
	sweep_absent(c);
	c->planned = true;
	evict_to(c, c->budget);
	/* (An empty scene has allocated neither: memset() may not take NULL.) */
	if (c->create_count)
		memset(c->created, 0, c->create_count * sizeof(*c->created));
	if (c->canvas_count)
		memset(c->made_canvas, 0, c->canvas_count * sizeof(*c->made_canvas));
	return 0;
}

/* ---- after ---- */

/* The volumes and canvases the render made for new entries: kept, unless
 * the volume was rendered whole by another engine than made them (or
 * discard). */
static void keep_made(struct cache *c, bool discard)
{
	for (uint32_t i = 0; i < c->create_count; i++) {
		if (discard || (c->whole && c->created_by[i] != c->engine)) {
			rle_volume_free(c->created[i]);
		} else {
			c->creates[i]->vol = c->created[i];
			c->creates[i]->engine = c->created_by[i];
			c->stats.creates++;
		}
		c->created[i] = NULL;
	}
	for (uint32_t i = 0; i < c->canvas_count; i++) {
		if (discard || (c->whole && c->engine != RENDER_ENGINE_CPU)) {
			rle_volume_free(c->made_canvas[i]);
		} else {
			c->canvases[i]->canvas = c->made_canvas[i];
			c->stats.creates++;
		}
		c->made_canvas[i] = NULL;
	}
}

/* What the new composition holds (where the rest and the turned lit in it
 * is remembered with it: c->lit). */
static void mark_composition(struct cache *c)
{
	for (uint32_t i = 0; i < c->use_count; i++)
		c->uses[i]->in_prev = true;
	for (uint32_t i = 0; i < c->create_count; i++)
		c->creates[i]->in_prev = true;
}

void cache_done(struct cache *c, int result)
{
	if (!c->planned)
		return;
	c->planned = false;
	for (uint32_t i = 0; i < c->count; i++)
		c->entries[i]->in_prev = false;
	tile_set_clear(&c->dirty);
	c->prev_valid = result == 0 && c->composed;
	/* A failed render: nothing of it is trusted, the next composition
	 * is made whole. */
	keep_made(c, result < 0);
	if (result < 0)
		return;
	if (c->whole) {
		/* Nothing came from the cache after all, and only what the
		 * renderer's engine now gives may be composed. */
		c->stats.hits -= c->use_count + c->turned_count;
		c->stats.turned -= c->turned_count;
		c->stats.misses += c->use_count + c->turned_count;
		for (uint32_t i = 0; i < c->count; i++)
			if (c->entries[i]->vol && c->entries[i]->engine != c->engine)
				drop_volume(c, c->entries[i]);
	}
	if (c->prev_valid)
		mark_composition(c);
	c->stats.last_rendered = c->rest_objects + c->create_count + c->canvas_count;
	c->stats.last_reused = c->use_count + c->turned_count;
	c->stats.last_render_us = c->render_us;
	c->stats.last_compose_us = c->compose_us;
	c->stats.last_composed = c->composed_tiles;
	c->stats.composed += c->composed_tiles;
	evict_to(c, c->budget);
}

void cache_forget_orphans(struct cache *c)
{
	if (c->planned)
		return;
	for (uint32_t i = 0; i < c->count;) {
		struct entry *e = c->entries[i];
		bool orphan = false;
		for (uint32_t d = 0; !e->seen && d < e->draw_count; d++)
			orphan |= e->refs[d]->refs == 1;
		if (!orphan) {
			i++;
			continue;
		}
		free_entry(c, e);
		memmove(c->entries + i, c->entries + i + 1, (c->count - i - 1) * sizeof(*c->entries));
		c->count--;
		c->stats.expired++;
	}
}

void cache_set_offset(struct cache *c, int32_t du, int32_t dv)
{
	if (du == c->du && dv == c->dv)
		return;
	c->du = du;
	c->dv = dv;
	for (uint32_t i = 0; i < c->count; i++)
		drop_volume(c, c->entries[i]); /* composed anew where it was */
}

void cache_set_budget(struct cache *c, uint64_t bytes)
{
	c->budget = bytes;
}

void cache_get_stats(const struct cache *c, struct cache_stats *out)
{
	*out = c->stats;
	out->objects = c->count;
	out->cached = 0;
	for (uint32_t i = 0; i < c->count; i++)
		out->cached += c->entries[i]->vol || c->entries[i]->canvas;
	out->bytes = held(c);
	out->budget = c->budget;
	out->working_bytes =
		volume_held_bytes(c->rest_vol) + volume_held_bytes(c->tmp) + volume_held_bytes(c->turned_vol) +
		batch_held(c->batch) + (c->moved ? volume_held_bytes(c->moved) : 0);
}
