#include "stage.h"

#include <errno.h>
#include <stdlib.h>

void stage_init(struct stage *s, const struct stage_listener *listener, void *data)
{
	*s = (struct stage){ .listener = listener, .data = data };
	link_init(&s->layers);
}

void stage_add(struct stage *s, struct stage_layer *y)
{
	y->serial = ++s->serial;
	link_append(&s->layers, &y->link);
}

bool stage_remove(struct stage_layer *y)
{
	bool on_stage = y->link.next != &y->link;
	link_remove(&y->link);
	return on_stage && stage_layer_affects_scene(y);
}

void stage_changed(struct stage *s)
{
	if (s->listener && s->listener->changed)
		s->listener->changed(s->data);
}

const void *stage_exclusive_owner(const struct stage *s)
{
	const struct stage_layer *y;
	link_for_each(y, &s->layers, link)
		if (stage_layer_exclusive(y))
			return y->owner;
	return NULL;
}

/* Highest priority first; of equal ones, the older layer. */
static int layer_order(const void *pa, const void *pb)
{
	const struct stage_layer *a = *(const struct stage_layer *const *)pa;
	const struct stage_layer *b = *(const struct stage_layer *const *)pb;
	if (a->priority != b->priority)
		return a->priority > b->priority ? -1 : 1;
	return a->serial < b->serial ? -1 : a->serial > b->serial;
}

int stage_shown_layers(const struct stage *s, const struct stage_layer ***layers, uint32_t *cap)
{
	const void *only = stage_exclusive_owner(s);
	uint32_t n = 0;
	const struct stage_layer *y;
	link_for_each(y, &s->layers, link) {
		if (!y->visible || !y->draws || (only && y->owner != only))
			continue;
		if (n == *cap) {
			uint32_t grown = *cap ? 2 * *cap : 16;
			const struct stage_layer **l = realloc(*layers, grown * sizeof(*l));
			if (!l)
				return -ENOMEM;
			*layers = l;
			*cap = grown;
		}
		(*layers)[n++] = y;
	}
	if (n > 1)
		qsort(*layers, n, sizeof(**layers), layer_order);
	return (int)n;
}
