/* Small scenes rendered side by side (batch.h). */
#include "batch.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "compose.h"
#include "pool.h"

struct batch_worker {
	struct renderer *r; /* serial, of the parent's engine */
	struct volume *tmp;
	int err;
	enum render_engine engine; /* of its last render, 0 if none */
};

struct batch {
	struct renderer *parent;
	struct pool *pool;
	struct batch_worker *w;
	unsigned workers;
	/* Per call: */
	const struct scene *scenes;
	struct rle_volume **out;
	uint32_t n;
	atomic_uint next;
};

struct batch *batch_create(struct renderer *r, struct pool *pool)
{
	if (!r->impl->serial) {
		errno = ENOTSUP;
		return NULL;
	}
	struct batch *b = calloc(1, sizeof(*b));
	unsigned n = pool_workers(pool);
	if (!b || !(b->w = calloc(n, sizeof(*b->w)))) {
		free(b);
		errno = ENOMEM;
		return NULL;
	}
	b->parent = r;
	b->pool = pool;
	b->workers = n;
	for (unsigned i = 0; i < n; i++) {
		b->w[i].r = r->impl->serial(r);
		b->w[i].tmp = volume_create(&r->geom);
		if (!b->w[i].r || !b->w[i].tmp) {
			batch_destroy(b);
			errno = ENOMEM;
			return NULL;
		}
	}
	return b;
}

void batch_destroy(struct batch *b)
{
	if (!b)
		return;
	for (unsigned i = 0; i < b->workers; i++) {
		render_destroy(b->w[i].r);
		volume_destroy(b->w[i].tmp);
	}
	free(b->w);
	free(b);
}

const struct renderer *batch_parent(const struct batch *b)
{
	return b->parent;
}

/* Scenes are handed out one at a time: each result depends on its scene
 * alone, so any split gives the same volumes. */
static void batch_job(void *arg, unsigned index)
{
	struct batch *b = arg;
	struct batch_worker *w = &b->w[index];
	for (;;) {
		uint32_t i = atomic_fetch_add(&b->next, 1);
		if (i >= b->n || w->err)
			break;
		int err = render_volume(w->r, &b->scenes[i], w->tmp);
		w->engine = w->r->stats.engine;
		if (err == 0 && !(b->out[i] = rle_volume_encode(w->tmp)))
			err = -ENOMEM;
		if (err < 0)
			w->err = err;
	}
}

int batch_render(struct batch *b, const struct scene *scenes, uint32_t n, struct rle_volume **out)
{
	b->scenes = scenes;
	b->out = out;
	b->n = n;
	atomic_store(&b->next, 0);
	for (unsigned i = 0; i < b->workers; i++)
		b->w[i].err = 0;
	pool_run(b->pool, batch_job, b);
	int err = 0;
	for (unsigned i = 0; i < b->workers && err == 0; i++)
		err = b->w[i].err;
	return err;
}

enum render_engine batch_engine(const struct batch *b)
{
	for (unsigned i = 0; i < b->workers; i++)
		if (b->w[i].engine)
			return b->w[i].engine;
	return 0;
}

uint64_t batch_held(const struct batch *b)
{
	uint64_t bytes = 0;
	for (unsigned i = 0; b && i < b->workers; i++)
		bytes += volume_held_bytes(b->w[i].tmp);
	return bytes;
}
