#include "pool.h"

#include <errno.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>

struct pool_thread {
	struct pool *pool;
	unsigned index;
	pthread_t thread;
};

struct pool {
	unsigned workers;            /* threads + 1 (the caller) */
	struct pool_thread *threads; /* workers - 1 */
	pthread_mutex_t lock;
	pthread_cond_t wake, done;
	unsigned long generation; /* bumped per job */
	unsigned running;         /* threads still in the current job */
	bool quit;
	pool_job job;
	void *arg;
};

static void *thread_main(void *data)
{
	struct pool_thread *t = data;
	struct pool *p = t->pool;
	unsigned long seen = 0;
	pthread_mutex_lock(&p->lock);
	for (;;) {
		while (p->generation == seen && !p->quit)
			pthread_cond_wait(&p->wake, &p->lock);
		if (p->quit)
			break;
		seen = p->generation;
		pool_job job = p->job;
		void *arg = p->arg;
		pthread_mutex_unlock(&p->lock);
		job(arg, t->index);
		pthread_mutex_lock(&p->lock);
		if (--p->running == 0)
			pthread_cond_signal(&p->done);
	}
	pthread_mutex_unlock(&p->lock);
	return NULL;
}

struct pool *pool_create(unsigned n)
{
	struct pool *p = calloc(1, sizeof(*p));
	if (!p)
		return NULL;
	if (n == 0)
		n = 1;
	p->threads = calloc(n, sizeof(*p->threads));
	if (!p->threads) {
		free(p);
		return NULL;
	}
	pthread_mutex_init(&p->lock, NULL);
	pthread_cond_init(&p->wake, NULL);
	pthread_cond_init(&p->done, NULL);
	p->workers = 1;
	for (unsigned i = 1; i < n; i++) {
		struct pool_thread *t = &p->threads[i - 1];
		t->pool = p;
		t->index = i;
		if (pthread_create(&t->thread, NULL, thread_main, t) != 0)
			break; /* fewer workers: still correct */
		p->workers++;
	}
	return p;
}

void pool_destroy(struct pool *p)
{
	if (!p)
		return;
	pthread_mutex_lock(&p->lock);
	p->quit = true;
	pthread_cond_broadcast(&p->wake);
	pthread_mutex_unlock(&p->lock);
	for (unsigned i = 0; i + 1 < p->workers; i++)
		pthread_join(p->threads[i].thread, NULL);
	pthread_mutex_destroy(&p->lock);
	pthread_cond_destroy(&p->wake);
	pthread_cond_destroy(&p->done);
	free(p->threads);
	free(p);
}

unsigned pool_workers(const struct pool *p)
{
	return p->workers;
}

void pool_run(struct pool *p, pool_job job, void *arg)
{
	if (p->workers > 1) {
		pthread_mutex_lock(&p->lock);
		p->job = job;
		p->arg = arg;
		p->running = p->workers - 1;
		p->generation++;
		pthread_cond_broadcast(&p->wake);
		pthread_mutex_unlock(&p->lock);
	}
	job(arg, 0);
	if (p->workers > 1) {
		pthread_mutex_lock(&p->lock);
		while (p->running)
			pthread_cond_wait(&p->done, &p->lock);
		pthread_mutex_unlock(&p->lock);
	}
}
