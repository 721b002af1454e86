/* Scene snapshots: the committed state of every client, flattened for the
 * renderer. Built and released on the main thread; read-only in between,
 * so a render thread may read it while clients go on committing. */
#ifndef SPINDLE_SNAPSHOT_H
#define SPINDLE_SNAPSHOT_H

#include <stdbool.h>
#include <stdint.h>

#include "scene.h"

struct geometry;
struct stage;
struct stage_layer;
struct vdata;

struct snapshot {
	struct scene scene;
	struct scene_draw *draws;
	struct vdata **data; /* one reference per draw */
	uint32_t cap;
	struct scene_object *objects; /* one per layer drawn, in order */
	uint32_t object_cap;
	/* Work space: the layers shown, in priority order. */
	const struct stage_layer **layers;
	uint32_t layer_count, layer_cap;
	uint32_t layers_left_out; /* over max-scene-primitives */
};

/* Fills snap from the layers the stage shows (stage_shown_layers()), in
 * their order, until budget primitives (max-scene-primitives): the layer
 * that would go over and every later one are left out, whole. turns: NULL,
 * or the renderer draws turns and lifts natively (the CPU renderer), in
 * images and rows of this geometry, so a layer is drawn as its base turned
 * by whole images (scene_draw.turn) and lifted by whole rows
 * (scene_draw.lift, where the row shift loses nothing) rather than by the
 * transform the client gave, which it equals within TURN_TOLERANCE. 0 or
 * -ENOMEM. pre: NULL, or a transform applied after every layer's (the
 * calibration's, calibration_transform(): a turn and a vertical scale,
 * which commute with the layers' turns; a layer is lifted only while the
 * scale is 1). */
int snapshot_build(struct snapshot *snap, const struct stage *stage, uint64_t budget, const struct geometry *turns,
		   const float *pre);
/* Whether a draws exactly what b draws: draw for draw the same primitive,
 * vertex data, transform and colour. Vertex data is compared by identity:
 * safe because b holds references to its data, so none of it can have been
 * freed and its address reused while b lives. */
bool snapshot_same(const struct snapshot *a, const struct snapshot *b);
/* Drops the references (keeps the arrays for the next build). */
void snapshot_release(struct snapshot *snap);
void snapshot_finish(struct snapshot *snap);

#endif
