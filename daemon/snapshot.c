#include "snapshot.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "draw.h"
#include "mat4.h"
#include "stage.h"

static int snapshot_grow(struct snapshot *snap)
{
	uint32_t cap = snap->cap ? snap->cap * 2 : 64;
	struct scene_draw *draws = realloc(snap->draws, cap * sizeof(*draws));
	if (!draws)
		return -ENOMEM;
	snap->draws = draws;
	struct vdata **data = realloc(snap->data, cap * sizeof(*data));
	if (!data)
		return -ENOMEM;
	snap->data = data;
	snap->cap = cap;
	return 0;
}

static int add_object(struct snapshot *snap, const struct stage_layer *y)
{
	if (snap->scene.object_count == snap->object_cap) {
		uint32_t cap = snap->object_cap ? snap->object_cap * 2 : 16;
		struct scene_object *o = realloc(snap->objects, cap * sizeof(*o));
		if (!o)
			return -ENOMEM;
		snap->objects = o;
		snap->object_cap = cap;
	}
	snap->objects[snap->scene.object_count++] = (struct scene_object){
		.key = y->serial,
		.first_draw = snap->scene.draw_count,
		.draw_count = y->draws->count,
	};
	return 0;
}

/* The last scene_draw.grid_id given (main thread only): grids are numbered
 * when first drawn, never twice, so that a renderer keeping what it made
 * of a grid cannot take a new grid at a freed one's address for it. */
static uint64_t grid_ids;

static int add_layer(struct snapshot *snap, const struct stage_layer *y, bool turns, const float *pre)
{
	const struct draw_array *a = y->draws;
	if (a->count && add_object(snap, y) < 0)
		return -ENOMEM;
	for (uint32_t i = 0; i < a->count; i++) {
		const struct list_item *d = &a->items[i];
		if (snap->scene.draw_count == snap->cap && snapshot_grow(snap) < 0)
			return -ENOMEM;
		struct scene_draw *sd = &snap->draws[snap->scene.draw_count];
		*sd = (struct scene_draw){
			.prim = d->data->prim,
			.count = d->data->count,
			.xyz = d->data->xyz,
			.point_size = d->point_size,
			.prim_rgb = d->data->prim_rgb,
		};
		/* A grid whose volume is gone draws nothing (grid NULL). */
		if (d->data->grid && !d->data->grid->gone) {
			struct vgrid *g = d->data->grid;
			if (!g->id)
				g->id = ++grid_ids;
			sd->grid = &g->grid;
			sd->transfer = d->data->transfer;
			sd->grid_id = g->id;
		}
		/* With turns, the layer's base and its turn by whole images
		 * (layer.h): the renderer shifts images instead of turning
		 * vertices, and the cache reuses what it rendered. */
		mat4_mul(sd->transform, turns ? y->base : y->transform, d->transform);
		if (pre)
			mat4_mul(sd->transform, pre, sd->transform);
		sd->turn = turns ? (uint16_t)y->turn : 0;
		for (int c = 0; c < 3; c++)
			sd->rgb[c] = (uint8_t)((d->rgba[c] * d->rgba[3] + 127) / 255);
		snap->data[snap->scene.draw_count++] = vdata_ref(d->data);
	}
	return 0;
}

int snapshot_build(struct snapshot *snap, const struct stage *stage, uint64_t budget, bool turns, const float *pre)
{
	snap->scene.draw_count = 0;
	snap->scene.object_count = 0;
	snap->layers_left_out = 0;
	int n = stage_shown_layers(stage, &snap->layers, &snap->layer_cap);
	if (n < 0)
		return -ENOMEM;
	snap->layer_count = (uint32_t)n;
	uint64_t prims = 0;
	for (uint32_t i = 0; i < snap->layer_count; i++) {
		const struct stage_layer *y = snap->layers[i];
		/* Over the budget: this layer and every later (lower) one. */
		if (y->draws->prims > budget - prims) {
			snap->layers_left_out = snap->layer_count - i;
			break;
		}
		prims += y->draws->prims;
		if (add_layer(snap, y, turns, pre) < 0) {
			snapshot_release(snap);
			return -ENOMEM;
		}
	}
	snap->scene.draws = snap->draws;
	snap->scene.objects = snap->objects;
	return 0;
}

static bool draw_same(const struct scene_draw *a, const struct scene_draw *b)
{
	return a->prim == b->prim && a->count == b->count && a->xyz == b->xyz && a->point_size == b->point_size &&
	       a->turn == b->turn && memcmp(a->transform, b->transform, sizeof(a->transform)) == 0 &&
	       memcmp(a->rgb, b->rgb, sizeof(a->rgb)) == 0 && (a->prim != SCENE_GRID || scene_grid_same(a, b));
}

bool snapshot_same(const struct snapshot *a, const struct snapshot *b)
{
	if (a->scene.draw_count != b->scene.draw_count)
		return false;
	for (uint32_t i = 0; i < a->scene.draw_count; i++)
		if (!draw_same(&a->draws[i], &b->draws[i]))
			return false;
	return true;
}

void snapshot_release(struct snapshot *snap)
{
	for (uint32_t i = 0; i < snap->scene.draw_count; i++)
		vdata_unref(snap->data[i]);
	snap->scene.draw_count = 0;
	snap->scene.object_count = 0;
}

void snapshot_finish(struct snapshot *snap)
{
	snapshot_release(snap);
	free(snap->draws);
	free(snap->data);
	free(snap->objects);
	free(snap->layers);
	*snap = (struct snapshot){ 0 };
}
