/* Scene snapshots: the committed state of every client, flattened for the
 * renderer. Built and released on the main thread; read-only in between,
 * so a render thread may read it while clients go on committing. */
#ifndef SPINDLE_SNAPSHOT_H
#define SPINDLE_SNAPSHOT_H

#include <stdbool.h>
#include <stdint.h>

#include "scene.h"

struct server;
struct vdata;
struct layer;

struct snapshot {
	struct scene scene;
	struct scene_draw *draws;
	struct vdata **data; /* one reference per draw */
	uint32_t cap;
	/* Work space: the layers shown, in priority order. */
	struct layer **layers;
	uint32_t layer_count, layer_cap;
	uint32_t layers_left_out; /* over max-scene-primitives */
};

/* Fills snap from every visible layer of every client (of the client
 * with an exclusive layer only, when one has), highest priority first,
 * until max-scene-primitives: the layer that would go over and every
 * later one are left out, whole. 0 or -ENOMEM. */
int snapshot_build(struct snapshot *snap, struct server *srv);
/* Ties the frame callbacks of every commit made so far, not yet tied, to
 * volume seq (the first volume showing their state). Returns how many. */
unsigned snapshot_tie_frames(struct server *srv, uint64_t seq);
/* Whether a draws exactly what b draws: draw for draw the same primitive,
 * vertex data, transform and colour. Vertex data is compared by identity:
 * safe because b holds references to its data, so none of it can have been
 * freed and its address reused while b lives. */
bool snapshot_same(const struct snapshot *a, const struct snapshot *b);
/* Drops the references (keeps the arrays for the next build). */
void snapshot_release(struct snapshot *snap);
void snapshot_finish(struct snapshot *snap);

#endif
