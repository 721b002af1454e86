/* The object cache's render thread (cache.h: cache_render()): the new
 * entries, the rest and the turned objects rendered, the last composition
 * patched, and handed out. */
#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "cache.h"
#include "cache_priv.h"
#include "compose.h"
#include "log.h"
#include "pool.h"
#include "renderer.h"
#include "volume.h"

/* New entries of at most this many segments and triangles are rendered
 * side by side, one per worker (batch.h); larger ones one at a time with
 * every worker on each. */
#define BATCH_MAX_PRIMS 16384

static struct scene sub_scene(const struct scene_draw *draws, uint32_t n)
{
	return (struct scene){ .draw_count = n, .draws = draws };
}

/* Whether what the cache renders is moved (cache_set_offset()). */
static bool moving(const struct cache *c)
{
	return c->du || c->dv;
}

/* *v (one of the cache's volumes) moved by the axis offset, when there
 * is one: shifted into c->moved, which it then exchanges with. */
static int move_part(struct cache *c, struct volume **v)
{
	if (!moving(c))
		return 0;
	if (!c->moved && !(c->moved = volume_create(&c->geom)))
		return -ENOMEM;
	int err = volume_shift(c->moved, *v, c->du, c->dv);
	if (err < 0)
		return err;
	struct volume *t = *v;
	*v = c->moved;
	c->moved = t;
	return 0;
}

/* The scene rendered into out, moved by the axis offset. */
static int render_moved(struct cache *c, struct renderer *r, const struct scene *scene, struct volume *out)
{
	return render_volume_moved(r, scene, c->tmp, out, c->du, c->dv);
}

/* New entry i's volume (rendered side by side, coded) moved by the axis
 * offset, when there is one. */
static int move_created(struct cache *c, uint32_t i)
{
	if (!moving(c))
		return 0;
	int err = rle_volume_decode(c->created[i], c->tmp);
	if (err == 0)
		err = move_part(c, &c->tmp);
	struct rle_volume *moved = err == 0 ? rle_volume_encode(c->tmp) : NULL;
	if (!moved)
		return err < 0 ? err : -ENOMEM;
	rle_volume_free(c->created[i]);
	c->created[i] = moved;
	return 0;
}

/* The canvases to make (each object's draws with turn and lift 0, rendered
 * up to the halftone), then every turned object composed at its turn and lift into
 * c->turned_vol (the CPU renderer's halftone: RENDER_ENGINE_CPU). */
static int render_turned(struct cache *c, struct renderer *r, const struct scene *scene)
{
	c->turned_rendered = false;
	if (!c->turned_count && !c->canvas_count)
		return 0;
	unsigned n = 0;
	for (uint32_t i = 0; i < c->canvas_count; i++) {
		const struct entry *e = c->canvases[i];
		if (e->draw_count > c->unturned_cap) {
			if (!cache_resize(&c->unturned, e->draw_count, sizeof(*c->unturned)))
				return -ENOMEM;
			c->unturned_cap = e->draw_count;
		}
		memcpy(c->unturned, scene->draws + e->first_draw, e->draw_count * sizeof(*c->unturned));
		for (uint32_t d = 0; d < e->draw_count; d++) {
			c->unturned[d].turn = 0;
			c->unturned[d].lift = 0;
		}
		struct rle_volume *cv = rle_volume_new(c->tmp->image_count, c->tmp->mask_bytes,
						       volume_tiles_per_image(c->tmp), CANVAS_TILE_BYTES);
		if (!cv)
			return -ENOMEM;
		c->made_canvas[i] = cv;
		struct scene one = sub_scene(c->unturned, e->draw_count);
		int err = r->impl->render_canvas(r, &one, cv);
		if (err < 0)
			return err;
		c->turned_src[n++] = (struct turned_source){ .canvas = cv, .turn = e->turn, .lift = e->lift };
	}
	for (uint32_t i = 0; i < c->turned_count; i++) {
		const struct entry *e = c->turneds[i];
		c->turned_src[n++] = (struct turned_source){ .canvas = e->canvas, .turn = e->turn, .lift = e->lift };
	}
	int err = compose_turned(c->compose, c->turned_vol, c->turned_src, n);
	if (err == 0)
		err = move_part(c, &c->turned_vol);
	c->turned_rendered = err == 0;
	return err;
}

/* Segments and triangles of scene, at most what binning keeps. */
static uint64_t scene_prims(const struct scene *s)
{
	uint64_t n = 0;
	for (uint32_t i = 0; i < s->draw_count; i++)
		if (s->draws[i].prim != SCENE_POINTS)
			n += s->draws[i].count / (s->draws[i].prim == SCENE_LINES ? 2 : 3);
	return n;
}

/* The scene rendered whole, nothing composed; cache_done() drops what
 * another engine made. */
static int render_whole(struct cache *c, struct renderer *r, const struct scene *scene, struct volume *out, int64_t t0)
{
	int err = render_moved(c, r, scene, out);
	c->whole = true;
	c->engine = r->stats.engine;
	c->render_us = (uint32_t)((now_ns() - t0) / 1000);
	c->compose_us = 0;
	c->composed_tiles = 0;
	return err;
}

/* The sources of a composition, and whether they come from one engine
 * (a GL renderer may hand a scene to its CPU fallback: too large, or for
 * good): OR is exact only among volumes of one. */
struct parts {
	unsigned n;
	enum render_engine engine; /* 0: none yet */
	bool mixed;
};

static void add_part(struct cache *c, struct parts *p, struct compose_source src, enum render_engine engine,
		     struct tile_set *marks)
{
	p->mixed |= p->engine && engine != p->engine;
	p->engine = engine;
	c->sources[p->n] = src;
	if (marks) /* new in the composition */
		compose_add_footprint(marks, &c->sources[p->n]);
	p->n++;
}

/* Puts the new entries to render side by side first in c->creates (their
 * scenes in c->batched) and returns how many: the small ones, when there
 * are two or more, the renderer has a serial form and there are workers
 * (the batch made for this renderer at first need). */
static uint32_t batch_creates(struct cache *c, struct renderer *r, const struct scene *scene)
{
	if (c->create_count < 2 || !c->pool || pool_workers(c->pool) < 2 || !r->impl->serial)
		return 0;
	if (c->batch && batch_parent(c->batch) != r) {
		batch_destroy(c->batch);
		c->batch = NULL;
	}
	if (!c->batch && !(c->batch = batch_create(r, c->pool)))
		return 0; /* one at a time, then */
	uint32_t n = 0;
	for (uint32_t i = 0; i < c->create_count; i++) {
		struct entry *e = c->creates[i];
		struct scene one = sub_scene(scene->draws + e->first_draw, e->draw_count);
		if (scene_prims(&one) > BATCH_MAX_PRIMS)
			continue;
		c->creates[i] = c->creates[n]; /* [n, i) are large */
		c->creates[n] = e;
		c->batched[n++] = one;
	}
	return n;
}

/* The tiles the parts rendered anew each time light in the composition
 * about to be made (numbered c->gen + 1 by note_changes()). The slot held
 * those of composition c->gen + 1 - CHANGED_HISTORY, from which no volume
 * is patched any more (held_composition()). */
static struct tile_set *next_lit(struct cache *c)
{
	return &c->lit[(c->gen + 1) % CHANGED_HISTORY];
}

/* What is rendered this time: the rest, the new entries, the turned. */
static int render_parts(struct cache *c, struct renderer *r, const struct scene *scene, struct parts *p)
{
	int err;
	tile_set_clear(next_lit(c));
	if (c->rest_count) {
		struct scene rest = sub_scene(c->rest, c->rest_count);
		if ((err = render_volume(r, &rest, c->rest_vol)) < 0 || (err = move_part(c, &c->rest_vol)) < 0)
			return err;
		add_part(c, p, (struct compose_source){ .vol = c->rest_vol }, r->stats.engine, next_lit(c));
	}
	uint32_t n = batch_creates(c, r, scene);
	if (n && (err = batch_render(c->batch, c->batched, n, c->created)) < 0)
		return err;
	c->stats.batched += n;
	for (uint32_t i = 0; i < c->create_count; i++) {
		const struct entry *e = c->creates[i];
		struct scene one = sub_scene(scene->draws + e->first_draw, e->draw_count);
		if (i >= n && ((err = render_volume(r, &one, c->tmp)) < 0 || (err = move_part(c, &c->tmp)) < 0))
			return err;
		if (i >= n && !(c->created[i] = rle_volume_encode(c->tmp)))
			return -ENOMEM;
		if (i < n && (err = move_created(c, i)) < 0)
			return err;
		c->created_by[i] = i < n ? batch_engine(c->batch) : r->stats.engine;
		add_part(c, p, (struct compose_source){ .rle = c->created[i] }, c->created_by[i], &c->dirty);
	}
	if ((err = render_turned(c, r, scene)) < 0)
		return err;
	if (c->turned_rendered) /* halftoned as the CPU renderer does */
		add_part(c, p, (struct compose_source){ .vol = c->turned_vol }, RENDER_ENGINE_CPU, next_lit(c));
	return 0;
}

/* The composition about to be made numbered, and the tiles where its
 * entries change noted (c->gen's marks): the dirty ones, or all when it
 * is made whole. */
static void note_changes(struct cache *c)
{
	struct tile_set *changed = &c->changed[++c->gen % CHANGED_HISTORY];
	if (c->prev_valid)
		tile_set_copy(changed, &c->dirty);
	else
		tile_set_fill(changed);
}

/* The images of the composition about to be made that may change (all
 * when it is made whole) get new stamps (volume.h): each then differs
 * from every volume handed out before, and an image that does not change
 * keeps the stamp that the volumes handed out with it have, so that an
 * upload against one of them skips comparing it (projwire.h). */
static void stamp_changes(struct cache *c, bool whole)
{
	for (uint32_t k = 0; whole && k < c->dirty.image_count; k++)
		c->stamps[k] = volume_new_stamp();
	if (whole)
		return;
	const struct tile_set *marks[3] = { &c->dirty, &c->lit[(c->gen - 1) % CHANGED_HISTORY],
					    &c->lit[c->gen % CHANGED_HISTORY] };
	for (unsigned i = 0; i < 3; i++)
		for (uint32_t p = 0; p < marks[i]->listed; p++)
			if (tile_set_image_any(marks[i], marks[i]->list[p]))
				c->stamps[marks[i]->list[p]] = volume_new_stamp();
}

/* The composition out holds: the one it was handed out with, when it is
 * a volume handed out lately and unchanged since (its origin mark), and
 * the changes since are all remembered; else 0. */
static uint64_t held_composition(const struct cache *c, const struct volume *out)
{
	uint64_t had = 0;
	for (unsigned i = 0; out->origin && i < HANDED_VOLUMES; i++)
		if (c->handed[i].origin == out->origin)
			had = c->handed[i].gen;
	return had && c->gen - had < CHANGED_HISTORY ? had : 0;
}

/* Out's images stamped anew after composition had, which out holds (by
 * stamp_changes(): where entries changed after it, and where its and the
 * later ones' rendered parts lit), take the last composition's stamps:
 * out now holds that one in every image. */
static void take_stamps(const struct cache *c, uint64_t had, struct volume *out)
{
	for (uint64_t g = had; g <= c->gen; g++)
		for (unsigned i = g == had; i < 2; i++) {
			const struct tile_set *m = i ? &c->lit[g % CHANGED_HISTORY] : &c->changed[g % CHANGED_HISTORY];
			for (uint32_t p = 0; p < m->listed; p++)
				out->images[m->list[p]].stamp = c->stamps[m->list[p]];
		}
}

/* set |= where compositions a <= b (both in the history) may differ:
 * where entries changed after a up to b, and where a's and b's rendered
 * parts lit (a small object moving every volume so counts in two places,
 * not in one a composition between: a tile it lit and left in between is
 * as it was). */
static void mark_between(const struct cache *c, uint64_t a, uint64_t b, struct tile_set *set)
{
	tile_set_or(set, &c->lit[a % CHANGED_HISTORY]);
	tile_set_or(set, &c->lit[b % CHANGED_HISTORY]);
	for (uint64_t g = a + 1; g <= b; g++)
		tile_set_or(set, &c->changed[g % CHANGED_HISTORY]);
}

bool cache_may_differ(const struct cache *c, const struct volume *a, const struct volume *b, struct tile_set *differ)
{
	uint64_t ga = held_composition(c, a), gb = held_composition(c, b);
	if (!ga || !gb || differ->image_count != c->dirty.image_count || differ->mask_bytes != c->dirty.mask_bytes)
		return false;
	mark_between(c, ga < gb ? ga : gb, ga < gb ? gb : ga, differ);
	return true;
}

/* Out patched from the n sources where the last composition (c->gen)
 * may differ from composition had, which out holds. */
static int patch_since(struct cache *c, uint64_t had, struct volume *out, unsigned n)
{
	mark_between(c, had, c->gen, &c->since);
	int err = compose_patch(c->compose, out, &c->since, c->sources, n);
	if (err == 0)
		take_stamps(c, had, out);
	tile_set_clear(&c->since);
	return err;
}

/* The composition of the n sources made in out, which is then marked as
 * holding it: patched where the compositions since the one out holds
 * changed (handed out lately, unchanged since, and the history leads
 * here), else composed whole. */
static int compose_hand_out(struct cache *c, struct volume *out, unsigned n)
{
	static atomic_uint_fast64_t origins;
	bool whole = !c->prev_valid;
	note_changes(c);
	stamp_changes(c, whole);
	uint64_t had = whole ? 0 : held_composition(c, out);
	out->origin = 0; /* not trusted until it is marked again below */
	int err;
	if (had) {
		err = patch_since(c, had, out, n);
	} else {
		err = compose_volumes(c->compose, out, c->sources, n);
		for (uint32_t k = 0; err == 0 && k < out->image_count; k++)
			out->images[k].stamp = c->stamps[k];
	}
	if (err < 0)
		return err;
	c->composed_tiles = compose_last_tiles(c->compose);
	out->seq = 0; /* as a render leaves it */
	out->shown_ns = 0;
	out->origin = atomic_fetch_add(&origins, 1) + 1;
	c->handed[c->handed_next++ % HANDED_VOLUMES] = (struct handed){ out->origin, c->gen };
	return 0;
}

/* The parts rendered, then composed into out (or the scene rendered whole
 * when the parts' engines differ). */
static int render_compose(struct cache *c, struct renderer *r, const struct scene *scene, struct volume *out,
			  int64_t t0)
{
	struct parts p = { .engine = c->prev_valid ? c->engine : 0 };
	int err = render_parts(c, r, scene, &p);
	if (err < 0)
		return err;
	int64_t t1 = now_ns();
	for (uint32_t i = 0; i < c->use_count; i++)
		add_part(c, &p, (struct compose_source){ .rle = c->uses[i]->vol }, c->uses[i]->engine, NULL);
	if (p.mixed)
		return render_whole(c, r, scene, out, t0);
	c->engine = p.engine;
	err = compose_hand_out(c, out, p.n);
	c->composed = err == 0;
	c->render_us = (uint32_t)((t1 - t0) / 1000);
	c->compose_us = (uint32_t)((now_ns() - t1) / 1000);
	return err;
}

int cache_render(struct cache *c, struct renderer *r, const struct scene *scene, struct volume *out)
{
	if (!c->planned)
		return render_moved(c, r, scene, out);
	int64_t t0 = now_ns();
	c->composed = c->whole = c->turned_rendered = false;
	/* Nothing from the cache; or a scene the renderer would hand to
	 * another engine whole (a GL renderer, one with a turn, or too
	 * large), whose parts would each stay native. GL draws grids itself
	 * (a part whose grids exceed its budget goes to its CPU fallback, and
	 * the parts' engines then differ: rendered whole, below). */
	if ((!c->use_count && !c->create_count && !c->turned_count && !c->canvas_count) ||
	    (r->native_prims && scene_prims(scene) > r->native_prims) ||
	    (!r->impl->render_canvas && scene_has_turn(scene->draws, scene->draw_count)))
		return render_whole(c, r, scene, out, t0);
	/* Composed on the renderer's workers, where it has some, as they come
	 * from rendering the parts: another pool's would have to be woken,
	 * and the two pools' workers would look for work on the same cores.
	 * Back on the cache's own after, so that nothing holds the renderer's. */
	bool borrowed = compose_use_pool(c->compose, r->pool, true);
	int err = render_compose(c, r, scene, out, t0);
	if (borrowed)
		compose_use_pool(c->compose, c->pool, false);
	return err;
}
