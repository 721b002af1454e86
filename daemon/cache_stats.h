/* What the object cache counts (cache.h; `spindlectl status` shows it
 * through the protocol's display.composition event). */
#ifndef SPINDLE_CACHE_STATS_H
#define SPINDLE_CACHE_STATS_H

#include <stdint.h>

struct cache_stats {
	uint32_t objects;       /* entries: objects being followed */
	uint32_t cached;        /* of them holding a volume or a canvas */
	uint64_t bytes;         /* held: coded volumes and canvases, bookkeeping */
	uint64_t budget;        /* cache-budget, or less: what of memory-budget the clients leave */
	uint64_t working_bytes; /* the volumes it renders and composes into (not in bytes) */
	uint64_t hits;          /* objects composed from the cache, summed over volumes */
	uint64_t turned;        /* of them, composed turned from a canvas */
	uint64_t misses;        /* objects rendered, summed over volumes */
	uint64_t creates;       /* volumes cached */
	uint64_t batched;       /* new entries rendered side by side (batch.h) */
	uint64_t invalidations; /* cached volumes dropped because their object changed */
	uint64_t evictions;     /* cached volumes dropped over the budget */
	uint64_t expired;       /* entries dropped, their object gone from the scene */
	uint64_t composed;      /* tiles composed into the volumes handed out, summed (not in status) */
	/* The last volume: */
	uint32_t last_rendered;  /* objects rendered (new entries and the rest) */
	uint32_t last_reused;    /* objects composed from the cache */
	uint32_t last_render_us; /* rendering them */
	uint32_t last_compose_us;
	uint64_t last_composed; /* tiles composed into it: all of its tiles, or those patched */
};

#endif
