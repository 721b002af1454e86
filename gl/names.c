#include "names.h"

#include <stdlib.h>

static size_t slot_of(const struct sgl_names *m, uint32_t key)
{
	uint32_t h = key * 2654435761u;
	return (size_t)h & (m->cap - 1);
}

void *sgl_names_get(const struct sgl_names *m, uint32_t key)
{
	if (!m->cap || !key)
		return NULL;
	for (size_t i = slot_of(m, key);; i = (i + 1) & (m->cap - 1)) {
		if (m->slots[i].key == key)
			return m->slots[i].value;
		if (!m->slots[i].key)
			return NULL;
	}
}

static bool grow(struct sgl_names *m)
{
	size_t cap = m->cap ? m->cap * 2 : 64;
	struct sgl_name_slot *old = m->slots, *slots = calloc(cap, sizeof(*slots));
	if (!slots)
		return false;
	size_t old_cap = m->cap;
	m->slots = slots;
	m->cap = cap;
	for (size_t i = 0; i < old_cap; i++) {
		if (!old[i].key)
			continue;
		size_t j = slot_of(m, old[i].key);
		while (slots[j].key)
			j = (j + 1) & (cap - 1);
		slots[j] = old[i];
	}
	free(old);
	return true;
}

void *sgl_names_put(struct sgl_names *m, uint32_t key, void *value, bool *ok)
{
	*ok = key != 0;
	if (!key)
		return NULL;
	if ((m->count + 1) * 4 > m->cap * 3 && !grow(m)) {
		*ok = false;
		return NULL;
	}
	size_t i = slot_of(m, key);
	while (m->slots[i].key && m->slots[i].key != key)
		i = (i + 1) & (m->cap - 1);
	void *old = m->slots[i].key ? m->slots[i].value : NULL;
	if (!m->slots[i].key)
		m->count++;
	m->slots[i] = (struct sgl_name_slot){ key, value };
	return old;
}

void *sgl_names_remove(struct sgl_names *m, uint32_t key)
{
	if (!m->cap || !key)
		return NULL;
	size_t i = slot_of(m, key);
	while (m->slots[i].key != key) {
		if (!m->slots[i].key)
			return NULL;
		i = (i + 1) & (m->cap - 1);
	}
	void *value = m->slots[i].value;
	/* Backward shift: move later entries of the run into the hole. */
	for (size_t j = (i + 1) & (m->cap - 1); m->slots[j].key; j = (j + 1) & (m->cap - 1)) {
		size_t home = slot_of(m, m->slots[j].key);
		bool movable = i <= j ? (home <= i || home > j) : (home <= i && home > j);
		if (movable) {
			m->slots[i] = m->slots[j];
			i = j;
		}
	}
	m->slots[i] = (struct sgl_name_slot){ 0, NULL };
	m->count--;
	return value;
}

void sgl_names_clear(struct sgl_names *m, void (*fn)(void *value))
{
	for (size_t i = 0; i < m->cap; i++)
		if (m->slots[i].key && fn)
			fn(m->slots[i].value);
	free(m->slots);
	*m = (struct sgl_names){ 0 };
}
