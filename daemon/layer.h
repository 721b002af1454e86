/* What the display shows, as the stage and the renderer's input see it:
 * the draws of a display list, and a layer's committed state (which list,
 * placed how, ranked how). Client objects (client.h) embed these; nothing
 * here knows about clients or the protocol. */
#ifndef SPINDLE_LAYER_H
#define SPINDLE_LAYER_H

#include <stdbool.h>
#include <stdint.h>

#include "draw.h"
#include "link.h"

/* One draw of a display list: its vertex data (a reference) and the list
 * state it was drawn with. */
struct list_item {
	struct vdata *data;
	float transform[16];
	uint8_t rgba[4]; /* used when data has no colour per primitive */
	uint8_t point_size;
};

/* The draws of a list in one of its states (pending or committed). */
struct draw_array {
	struct list_item *items;
	uint32_t count, cap;
	uint64_t vertices;
	uint64_t prims;
};

/* A layer as committed: what the stage ranks and the snapshot draws. */
struct stage_layer {
	/* The committed draws of the layer's list (the layer holds a
	 * reference to the list), or NULL: no list. */
	const struct draw_array *draws;
	float transform[16]; /* as the client set it */
	/* The same as a base turned about the axis by whole images and
	 * moved along it by whole rows (turn.h): transform is, within
	 * TURN_TOLERANCE, base turned by turn images and lifted by lift rows
	 * of the volume (before calibration). */
	float base[16];
	uint32_t turn;
	int32_t lift;
	int32_t priority;
	bool visible;
	bool exclusive;
	uint64_t serial;   /* creation order, set by stage_add(): ties of priority */
	const void *owner; /* the client: an exclusive layer shows its owner alone */
	struct link link;  /* stage.layers */
};

/* Visible and exclusive: its owner is shown alone. */
static inline bool stage_layer_exclusive(const struct stage_layer *y)
{
	return y->visible && y->exclusive;
}

/* Whether the layer, if it went, would change the scene: it shows a list,
 * or hides every other owner (exclusive). */
static inline bool stage_layer_affects_scene(const struct stage_layer *y)
{
	return y->visible && (y->draws || y->exclusive);
}

#endif
