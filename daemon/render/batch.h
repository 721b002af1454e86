/* Many small scenes rendered side by side: each worker of a pool renders
 * whole scenes, one at a time, with a serial renderer of its own (the
 * renderer's serial(): the same engine, bit-identical output), and codes
 * each result (compose.h). What the object cache uses to make the volumes
 * of many small objects at once, where rendering them one after another
 * would leave all but one core idle (a small scene renders on one thread). */
#ifndef SPINDLE_BATCH_H
#define SPINDLE_BATCH_H

#include <stdint.h>

#include "renderer.h"

struct batch;
struct pool;
struct rle_volume;

/* A batch for renderer r over pool's workers, or NULL (errno ENOTSUP
 * where r has no serial form, ENOMEM). r and pool outlive the batch. */
struct batch *batch_create(struct renderer *r, struct pool *pool);
/* Accepts NULL. */
void batch_destroy(struct batch *b);

/* The renderer the batch renders like. */
const struct renderer *batch_parent(const struct batch *b);

/* Renders scenes[i] and codes it into out[i] (NULL first; the caller
 * frees them), for i < n. 0, or the first error (the out[] made are
 * still the caller's). */
int batch_render(struct batch *b, const struct scene *scenes, uint32_t n, struct rle_volume **out);

/* What rendered the last batch (the parent's engine). */
enum render_engine batch_engine(const struct batch *b);

/* Bytes the workers' scratch volumes hold. */
uint64_t batch_held(const struct batch *b);

#endif
