/* The object cache's state, shared by its two halves: cache.c (planning
 * and bookkeeping, on the loop's thread) and cache_render.c (rendering and
 * composing, on the render thread). Private to them. */
#ifndef SPINDLE_CACHE_PRIV_H
#define SPINDLE_CACHE_PRIV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cache_stats.h"
#include "compose.h"
#include "renderer.h"
#include "scene.h"

/* Compositions whose changed images are remembered, and volumes handed
 * out whose composition is: a volume handed back within that many gets
 * only the images changed since (cache_render()). */
#define CHANGED_HISTORY 8
#define HANDED_VOLUMES 8

struct batch;
struct pool;
struct rle_volume;
struct turned_source;
struct vdata;
struct volume;

enum role {
	ROLE_REST,   /* rendered with every other object not cached */
	ROLE_CREATE, /* rendered alone; its volume kept */
	ROLE_USE,    /* composed from its volume */
	ROLE_CANVAS, /* rendered alone, unturned, before the halftone; its canvas kept, then as ROLE_TURNED */
	ROLE_TURNED, /* composed from its canvas, turned (compose_turned()) */
};

struct entry {
	uint64_t key;
	uint8_t reuse;       /* volumes in a row it came unchanged, saturating */
	uint8_t backoff;     /* times its cached volume was dropped for a change, saturating */
	uint8_t hits;        /* hits of its cached volume, saturating at PAYOFF_HITS */
	uint8_t absent;      /* volumes in a row it was not in the scene */
	bool seen;           /* in the scene being planned */
	bool in_prev;        /* its volume is in the last composition */
	enum role role;      /* in the plan */
	uint32_t first_draw; /* in the planned scene */
	uint64_t last_used;  /* the plan that last composed it */
	/* What it draws (copies of the scene's draws, with references to
	 * their vertex data so that identity means equality). */
	struct scene_draw *draws;
	struct vdata **refs;
	uint32_t draw_count;
	struct rle_volume *vol;    /* its rendered volume, or NULL */
	enum render_engine engine; /* what rendered it */
	/* Its render unturned, before the halftone (the CPU renderer's
	 * canvas), or NULL: an object that only turns about the axis by
	 * whole images is composed from it (cache.h). */
	struct rle_volume *canvas;
	uint32_t turn; /* its draws' turn in the planned scene */
	int32_t lift;  /* and their lift */
};

struct cache {
	struct geometry geom;
	uint64_t budget;
	struct compose *compose;
	struct pool *pool;   /* the workers it composes on, or NULL */
	struct batch *batch; /* small new entries rendered side by side, or NULL */
	/* Entries, sorted by key. */
	struct entry **entries;
	uint32_t count, cap;
	/* Whether the last volume cache_render() made was composed (the
	 * history below then leads up to it), and per image the tiles of that
	 * composition where entries change in the next: where they leave it,
	 * where they come (back or new). The parts rendered anew each time (the
	 * rest, the turned) are marked apart (lit below). No volume of a
	 * composition is kept: each is made in the volume it is handed out in. */
	bool prev_valid, composed;
	struct tile_set dirty;
	/* The plan, made by cache_plan() for cache_render(). */
	bool planned;
	uint64_t plan_seq;
	struct entry **uses, **creates;
	uint32_t use_count, create_count, array_cap;
	struct scene_draw *rest;
	uint32_t rest_count, rest_cap, rest_objects;
	/* Turns: whether objects are composed turned from canvases (the
	 * renderer renders canvases, compose_turned() can turn them); the
	 * entries composed so (turneds) and those whose canvas the render
	 * makes first (canvases, made into made_canvas). */
	bool turns;
	struct entry **turneds, **canvases;
	uint32_t turned_count, canvas_count;
	struct rle_volume **made_canvas;
	struct turned_source *turned_src;
	struct volume *turned_vol;   /* what they light this volume */
	struct scene_draw *unturned; /* a canvas entry's draws with turn 0 */
	uint32_t unturned_cap;
	bool turned_rendered;
	struct rle_volume **created;    /* creates[i]'s volume, made by the render */
	struct scene *batched;          /* creates[i]'s draws, the first batched_count */
	enum render_engine *created_by; /* and what rendered it */
	bool whole;                     /* the last volume was rendered whole, not composed */
	enum render_engine engine;      /* of the last composition, or of the whole render */
	struct volume *rest_vol, *tmp;
	/* The axis offset the parts and entries are moved by (cache_set_offset()),
	 * and the volume a part is moved into, then exchanged with it (made
	 * when first needed). */
	int32_t du, dv;
	struct volume *moved;
	struct compose_source *sources;
	uint32_t source_cap;
	uint32_t render_us, compose_us; /* of the last render */
	uint64_t composed_tiles;        /* and the tiles it composed */
	/* Handing out: compositions made (gen); for each of the last
	 * CHANGED_HISTORY (at gen % CHANGED_HISTORY), the tiles where its
	 * entries changed (changed: the dirty marks above, or all when it was
	 * made whole) and those its parts rendered anew lit (lit: the rest's
	 * and the turned's); the stamp (volume.h) of each image of the last;
	 * and the last volumes handed out, known by the origin mark (volume.h)
	 * each got and the composition it holds. Composition b differs from an
	 * earlier a only where entries changed after a up to b, or where a's
	 * or b's rendered parts lit: what passed between them does not count
	 * (patch_since()). */
	uint64_t gen;
	struct tile_set changed[CHANGED_HISTORY], lit[CHANGED_HISTORY];
	struct tile_set since; /* work space: what changed since a volume handed out */
	uint64_t *stamps;
	struct handed {
		uint64_t origin, gen;
	} handed[HANDED_VOLUMES];
	unsigned handed_next;
	struct cache_stats stats;
};

/* The tiles src lights are composed anew next time (c->dirty). */
void cache_add_footprint(struct cache *c, const struct compose_source *src);
/* *pp (a pointer to an array) resized to n elements of size bytes; false
 * when out of memory, *pp untouched. */
bool cache_resize(void *pp, size_t n, size_t size);

#endif
