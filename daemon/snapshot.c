#include "snapshot.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "draw.h"
#include "geometry.h"
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

/* The last scene_draw.data_id given (main thread only), likewise for
 * vertex data: a renderer keeps its binning of draws whose data and
 * everything else are the same. */
static uint64_t data_ids;

/* Rows of margin a lifted draw keeps from the image's top and bottom: a
 * point's square reaches 8 rows from its centre, and the conservative
 * raster a row beyond a primitive's edge. */
#define LIFT_MARGIN_ROWS 10

/* Lowest and highest y of a draw of d under m (its box, or a grid's).
 * False when d has no finite box. */
static bool draw_y_range(const struct vdata *d, const float m[16], double *lo, double *hi)
{
	float box[2][3];
	if (d->grid) {
		for (int a = 0; a < 3; a++) {
			box[0][a] = 0;
			box[1][a] = (float)d->grid->grid.n[a] * d->grid->grid.spacing[a];
		}
	} else if (d->bounded) {
		memcpy(box[0], d->lo, sizeof(box[0]));
		memcpy(box[1], d->hi, sizeof(box[1]));
	} else {
		return false;
	}
	*lo = *hi = m[13];
	for (int a = 0; a < 3; a++) {
		double p = (double)m[a * 4 + 1] * box[0][a], q = (double)m[a * 4 + 1] * box[1][a];
		*lo += p < q ? p : q;
		*hi += p < q ? q : p;
	}
	return true;
}

/* Whether y's lift can be drawn as a row shift (scene.h, scene_draw.lift):
 * every draw lies LIFT_MARGIN_ROWS inside the image rows both unlifted and
 * lifted, so the shifted render of the base loses nothing and brings in
 * nothing a render of the moved draws would not show, and the calibration
 * does not scale rows (pre's y scale is 1). */
static bool lift_fits(const struct stage_layer *y, const struct geometry *g, const float *pre)
{
	if (pre && pre[5] != 1.0f)
		return false;
	double h = g->half_height, row_h = 2.0 * h / g->height, margin = LIFT_MARGIN_ROWS * row_h;
	double up = y->lift * row_h;
	for (uint32_t i = 0; i < y->draws->count; i++) {
		const struct list_item *d = &y->draws->items[i];
		float m[16];
		double lo, hi;
		mat4_mul(m, y->base, d->transform);
		if (pre)
			mat4_mul(m, pre, m);
		if (!draw_y_range(d->data, m, &lo, &hi))
			return false;
		if (lo + (up < 0 ? up : 0) < margin - h || hi + (up > 0 ? up : 0) > h - margin)
			return false;
	}
	return true;
}

/* With turns, a layer is drawn as its base turned by whole images and
 * lifted by whole rows (layer.h): the renderer shifts images and rows
 * instead of moving vertices, and the cache reuses what it rendered. The
 * base into base, and the lift; a lift that cannot be a row shift is put
 * back into the base (a move up the axis). */
static int32_t layer_base(const struct stage_layer *y, const struct geometry *turns, const float *pre, float base[16])
{
	memcpy(base, y->base, sizeof(y->base));
	if (y->lift && lift_fits(y, turns, pre))
		return y->lift;
	base[13] += (float)(y->lift * 2.0 * turns->half_height / turns->height);
	return 0;
}

static int add_layer(struct snapshot *snap, const struct stage_layer *y, const struct geometry *turns, const float *pre)
{
	float base[16];
	int32_t lift = turns ? layer_base(y, turns, pre, base) : 0;
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
		if (!d->data->id)
			d->data->id = ++data_ids;
		sd->data_id = d->data->id;
		/* A grid whose volume is gone draws nothing (grid NULL). */
		if (d->data->grid && !d->data->grid->gone) {
			struct vgrid *g = d->data->grid;
			if (!g->id)
				g->id = ++grid_ids;
			sd->grid = &g->grid;
			sd->transfer = d->data->transfer;
			sd->grid_id = g->id;
		}
		mat4_mul(sd->transform, turns ? base : y->transform, d->transform);
		if (pre)
			mat4_mul(sd->transform, pre, sd->transform);
		sd->turn = turns ? (uint16_t)y->turn : 0;
		sd->lift = (int16_t)lift;
		for (int c = 0; c < 3; c++)
			sd->rgb[c] = (uint8_t)((d->rgba[c] * d->rgba[3] + 127) / 255);
		snap->data[snap->scene.draw_count++] = vdata_ref(d->data);
	}
	return 0;
}

int snapshot_build(struct snapshot *snap, const struct stage *stage, uint64_t budget, const struct geometry *turns,
		   const float *pre)
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

bool snapshot_same(const struct snapshot *a, const struct snapshot *b)
{
	if (a->scene.draw_count != b->scene.draw_count)
		return false;
	for (uint32_t i = 0; i < a->scene.draw_count; i++)
		if (!scene_draw_same(&a->draws[i], &b->draws[i]))
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
