/* Scene snapshots: the committed state of every client, flattened for the
 * renderer. Built and released on the main thread; read-only in between,
 * so a render thread may read it while clients go on committing. */
#ifndef SPINDLE_SNAPSHOT_H
#define SPINDLE_SNAPSHOT_H

#include <stdint.h>

#include "scene.h"

struct server;
struct vdata;

struct snapshot {
	struct scene scene;
	struct scene_draw *draws;
	struct vdata **data; /* one reference per draw */
	uint32_t cap;
};

/* Fills snap from every visible layer of every client, and ties the frame
 * callbacks of the commits it includes to volume seq. 0 or -ENOMEM. */
int snapshot_build(struct snapshot *snap, struct server *srv, uint64_t seq);
/* Drops the references (keeps the arrays for the next build). */
void snapshot_release(struct snapshot *snap);
void snapshot_finish(struct snapshot *snap);

#endif
