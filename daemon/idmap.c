#include "idmap.h"

#include <errno.h>
#include <stdlib.h>

static uint32_t slot_of(const struct idmap *map, uint32_t id)
{
	return (id * 2654435761u) & (map->cap - 1);
}

void idmap_finish(struct idmap *map)
{
	free(map->slots);
	*map = (struct idmap){ 0 };
}

void *idmap_get(const struct idmap *map, uint32_t id)
{
	if (!map->cap || id == 0)
		return NULL;
	for (uint32_t i = slot_of(map, id);; i = (i + 1) & (map->cap - 1)) {
		if (map->slots[i].id == id)
			return map->slots[i].value;
		if (map->slots[i].id == 0)
			return NULL;
	}
}

static void place(struct idmap *map, uint32_t id, void *value)
{
	uint32_t i = slot_of(map, id);
	while (map->slots[i].id != 0)
		i = (i + 1) & (map->cap - 1);
	map->slots[i] = (struct idmap_slot){ id, value };
}

static int grow(struct idmap *map)
{
	uint32_t cap = map->cap ? map->cap * 2 : 16;
	struct idmap_slot *old = map->slots;
	uint32_t old_cap = map->cap;
	map->slots = calloc(cap, sizeof(*map->slots));
	if (!map->slots) {
		map->slots = old;
		return -ENOMEM;
	}
	map->cap = cap;
	for (uint32_t i = 0; i < old_cap; i++)
		if (old[i].id)
			place(map, old[i].id, old[i].value);
	free(old);
	return 0;
}

int idmap_insert(struct idmap *map, uint32_t id, void *value)
{
	if ((map->count + 1) * 4 > map->cap * 3) {
		int r = grow(map);
		if (r < 0)
			return r;
	}
	place(map, id, value);
	map->count++;
	return 0;
}

void *idmap_remove(struct idmap *map, uint32_t id)
{
	if (!map->cap || id == 0)
		return NULL;
	uint32_t mask = map->cap - 1, i = slot_of(map, id);
	while (map->slots[i].id != id) {
		if (map->slots[i].id == 0)
			return NULL;
		i = (i + 1) & mask;
	}
	void *value = map->slots[i].value;
	/* Shift back later entries of the same cluster that may sit after the hole. */
	for (uint32_t j = (i + 1) & mask; map->slots[j].id != 0; j = (j + 1) & mask) {
		uint32_t home = slot_of(map, map->slots[j].id);
		if (((j - home) & mask) >= ((j - i) & mask)) {
			map->slots[i] = map->slots[j];
			i = j;
		}
	}
	map->slots[i] = (struct idmap_slot){ 0 };
	map->count--;
	return value;
}
