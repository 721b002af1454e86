#include "snapshot.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "client.h"
#include "server.h"

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

static int add_layer(struct snapshot *snap, const struct layer_state *ls)
{
	const struct draw_array *a = &ls->list->committed;
	for (uint32_t i = 0; i < a->count; i++) {
		const struct list_draw *d = &a->draws[i];
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
		mat4_mul(sd->transform, ls->transform, d->transform);
		for (int c = 0; c < 3; c++)
			sd->rgb[c] = (uint8_t)((d->rgba[c] * d->rgba[3] + 127) / 255);
		snap->data[snap->scene.draw_count++] = vdata_ref(d->data);
	}
	return 0;
}

/* Highest priority first; of equal ones, the older layer. */
static int layer_order(const void *pa, const void *pb)
{
	const struct layer *a = *(const struct layer *const *)pa, *b = *(const struct layer *const *)pb;
	if (a->committed.priority != b->committed.priority)
		return a->committed.priority > b->committed.priority ? -1 : 1;
	return a->serial < b->serial ? -1 : a->serial > b->serial;
}

/* The layers to show, in priority order, into snap->layers: every
 * visible layer with a list, or only the exclusive client's. */
static int gather_layers(struct snapshot *snap, struct server *srv)
{
	struct client *only = server_exclusive_client(srv), *c;
	snap->layer_count = 0;
	link_for_each(c, &srv->clients, link) {
		if (c->dead || (only && c != only))
			continue;
		struct layer *y;
		link_for_each(y, &c->layers, link) {
			if (!y->committed.visible || !y->committed.list)
				continue;
			if (snap->layer_count == snap->layer_cap) {
				uint32_t cap = snap->layer_cap ? 2 * snap->layer_cap : 16;
				struct layer **l = realloc(snap->layers, cap * sizeof(*l));
				if (!l)
					return -ENOMEM;
				snap->layers = l;
				snap->layer_cap = cap;
			}
			snap->layers[snap->layer_count++] = y;
		}
	}
	if (snap->layer_count > 1)
		qsort(snap->layers, snap->layer_count, sizeof(*snap->layers), layer_order);
	return 0;
}

/* Frames of commits made so far are first shown by volume seq. */
static unsigned tie_frames(struct client *c, uint64_t seq)
{
	unsigned n = 0;
	struct waiter *w;
	link_for_each(w, &c->frames, link) {
		if (!w->volume_seq) {
			w->volume_seq = seq;
			n++;
		}
	}
	return n;
}

unsigned snapshot_tie_frames(struct server *srv, uint64_t seq)
{
	unsigned n = 0;
	struct client *c;
	link_for_each(c, &srv->clients, link) {
		if (!c->dead)
			n += tie_frames(c, seq);
	}
	return n;
}

int snapshot_build(struct snapshot *snap, struct server *srv)
{
	snap->scene.draw_count = 0;
	snap->layers_left_out = 0;
	if (gather_layers(snap, srv) < 0)
		return -ENOMEM;
	uint64_t prims = 0, budget = srv->cfg.max_scene_primitives;
	for (uint32_t i = 0; i < snap->layer_count; i++) {
		const struct layer_state *ls = &snap->layers[i]->committed;
		/* Over the budget: this layer and every later (lower) one. */
		if (ls->list->committed.prims > budget - prims) {
			snap->layers_left_out = snap->layer_count - i;
			break;
		}
		prims += ls->list->committed.prims;
		if (add_layer(snap, ls) < 0) {
			snapshot_release(snap);
			return -ENOMEM;
		}
	}
	snap->scene.draws = snap->draws;
	return 0;
}

static bool draw_same(const struct scene_draw *a, const struct scene_draw *b)
{
	return a->prim == b->prim && a->count == b->count && a->xyz == b->xyz && a->point_size == b->point_size &&
	       memcmp(a->transform, b->transform, sizeof(a->transform)) == 0 &&
	       memcmp(a->rgb, b->rgb, sizeof(a->rgb)) == 0;
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
}

void snapshot_finish(struct snapshot *snap)
{
	snapshot_release(snap);
	free(snap->draws);
	free(snap->data);
	free(snap->layers);
	*snap = (struct snapshot){ 0 };
}
