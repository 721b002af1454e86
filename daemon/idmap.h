/* A map from client-chosen object ids to objects: open addressing, linear
 * probing, backward-shift deletion (no tombstones). */
#ifndef SPINDLE_IDMAP_H
#define SPINDLE_IDMAP_H

#include <stdint.h>

struct idmap_slot {
	uint32_t id; /* 0 = empty */
	void *value;
};

struct idmap {
	struct idmap_slot *slots;
	uint32_t cap; /* power of two, or 0 */
	uint32_t count;
};

void idmap_finish(struct idmap *map);
void *idmap_get(const struct idmap *map, uint32_t id);
/* id must be non-zero and absent. 0 or -ENOMEM. */
int idmap_insert(struct idmap *map, uint32_t id, void *value);
/* Returns the removed value, or NULL. */
void *idmap_remove(struct idmap *map, uint32_t id);

#endif
