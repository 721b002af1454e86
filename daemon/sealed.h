/* A sealed memfd filled once: how the daemon hands a client a volume it may
 * read but never change (captures, frames.c; watch volumes, watch.c). */
#ifndef SPINDLE_SEALED_H
#define SPINDLE_SEALED_H

#include <stdint.h>

/* Writes size bytes into out. */
typedef void (*sealed_fill_fn)(const void *ctx, uint8_t *out);

/* A memfd called name of size bytes, filled by fill(ctx, ...) through a
 * shared mapping, then sealed against shrinking, growing, writing and
 * further seals. Returns the fd (close-on-exec), or negative errno. */
int sealed_memfd(const char *name, uint64_t size, sealed_fill_fn fill, const void *ctx);

#endif
