/* Editing spindled's config file in place (spindlectl calibrate --save):
 * one key set, every other line kept as it was. */
#ifndef SPINDLE_CONFIG_EDIT_H
#define SPINDLE_CONFIG_EDIT_H

#include <stddef.h>

/* The largest config file edited (bytes). */
#define CONFIG_EDIT_MAX (1u << 20)

/* Sets key to value in the config file at path: each active "key = value"
 * line of that key is rewritten (a comment after it kept), or, when there
 * is none, "key = value" is appended; a missing file is created (mode
 * 0644). Written to a temporary file in the same directory, synced, then
 * renamed over path, with path's mode, so a reader sees the old file or
 * the new one. 0, or -errno with a message naming the file in err. */
int config_edit_set(const char *path, const char *key, const char *value, char *err, size_t err_size);

#endif
