/* spindle-gl: a map of GL object names (display lists, buffer objects) to
 * pointers: open addressing, linear probing, deletion by backward shift. */
#ifndef SPINDLE_GL_NAMES_H
#define SPINDLE_GL_NAMES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct sgl_names {
	struct sgl_name_slot {
		uint32_t key; /* 0: free (GL never names an object 0) */
		void *value;
	} * slots;
	size_t cap, count;
};

void *sgl_names_get(const struct sgl_names *m, uint32_t key);
/* Sets key (not 0) to value, returning the value it replaced (or NULL);
 * false in *ok when out of memory. */
void *sgl_names_put(struct sgl_names *m, uint32_t key, void *value, bool *ok);
/* Removes key, returning its value (or NULL). */
void *sgl_names_remove(struct sgl_names *m, uint32_t key);
/* Calls fn on every value, then empties the map and frees its memory. */
void sgl_names_clear(struct sgl_names *m, void (*fn)(void *value));

#endif
