#include "snapshot.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "client.h"
#include "server.h"

/* out = a * b, column-major 4x4. */
static void mat_mul(float out[16], const float a[16], const float b[16])
{
	for (int c = 0; c < 4; c++)
		for (int r = 0; r < 4; r++) {
			float s = 0;
			for (int k = 0; k < 4; k++)
				s += a[k * 4 + r] * b[c * 4 + k];
			out[c * 4 + r] = s;
		}
}

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
		sd->prim = d->prim;
		sd->count = d->data->count;
		sd->xyz = d->data->xyz;
		mat_mul(sd->transform, ls->transform, d->transform);
		for (int c = 0; c < 3; c++)
			sd->rgb[c] = (uint8_t)((d->rgba[c] * d->rgba[3] + 127) / 255);
		snap->data[snap->scene.draw_count++] = vdata_ref(d->data);
	}
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
	struct client *c;
	snap->scene.draw_count = 0;
	link_for_each(c, &srv->clients, link) {
		if (c->dead)
			continue;
		struct layer *y;
		link_for_each(y, &c->layers, link) {
			if (!y->committed.visible || !y->committed.list)
				continue;
			if (add_layer(snap, &y->committed) < 0) {
				snapshot_release(snap);
				return -ENOMEM;
			}
		}
	}
	snap->scene.draws = snap->draws;
	return 0;
}

static bool draw_same(const struct scene_draw *a, const struct scene_draw *b)
{
	return a->prim == b->prim && a->count == b->count && a->xyz == b->xyz &&
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
	*snap = (struct snapshot){ 0 };
}
