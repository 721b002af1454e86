#include "pool.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>

#include "log.h" /* now_ns() */

/* How long a worker looks for the next job, and the caller for the
 * workers' end, before sleeping: a volume's steps come microseconds
 * apart, and a futex wake-up on this kind of machine costs tens of
 * microseconds, about a small object's whole render. */
#define POOL_SPIN_NS 30000

struct pool_thread {
	struct pool *pool;
	unsigned index;
	pthread_t thread;
};

/* generation and running are read by spinning threads without the lock;
 * job and arg are written before generation is bumped (release) and read
 * after it is seen (acquire). sleepers and caller_waiting, under the
 * lock, say who must be woken. */
struct pool {
	unsigned workers;            /* threads + 1 (the caller) */
	struct pool_thread *threads; /* workers - 1 */
	pthread_mutex_t lock;
	pthread_cond_t wake, done;
	atomic_ulong generation; /* bumped per job */
	atomic_ulong running;    /* threads still in the current job */
	atomic_bool quit;
	unsigned sleepers;   /* threads waiting on wake */
	bool caller_waiting; /* the caller waits on done */
	pool_job job;
	void *arg;
};

static inline void relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
	__builtin_ia32_pause();
#endif
}

/* Spins until *word == value is what is wanted (equal) or, for a worker,
 * the pool quits, or POOL_SPIN_NS pass; whether it got there. */
static bool spin_for(atomic_ulong *word, unsigned long value, bool equal, const atomic_bool *quit)
{
	int64_t end = 0;
	for (unsigned i = 0;; i++) {
		if ((atomic_load_explicit(word, memory_order_acquire) == value) == equal ||
		    (quit && atomic_load_explicit(quit, memory_order_relaxed)))
			return true;
		if (i % 64 == 63) { /* the clock now and then, not each turn */
			int64_t now = now_ns();
			if (!end)
				end = now + POOL_SPIN_NS;
			else if (now > end)
				return false;
		}
		relax();
	}
}

static void *thread_main(void *data)
{
	struct pool_thread *t = data;
	struct pool *p = t->pool;
	unsigned long seen = 0;
	for (;;) {
		if (!spin_for(&p->generation, seen, false, &p->quit)) {
			pthread_mutex_lock(&p->lock);
			p->sleepers++;
			while (atomic_load(&p->generation) == seen && !atomic_load(&p->quit))
				pthread_cond_wait(&p->wake, &p->lock);
			p->sleepers--;
			pthread_mutex_unlock(&p->lock);
		}
		if (atomic_load(&p->quit))
			break;
		seen = atomic_load_explicit(&p->generation, memory_order_acquire);
		p->job(p->arg, t->index);
		if (atomic_fetch_sub_explicit(&p->running, 1, memory_order_acq_rel) == 1) {
			pthread_mutex_lock(&p->lock);
			if (p->caller_waiting)
				pthread_cond_signal(&p->done);
			pthread_mutex_unlock(&p->lock);
		}
	}
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
	atomic_init(&p->generation, 0);
	atomic_init(&p->running, 0);
	atomic_init(&p->quit, false);
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
	atomic_store(&p->quit, true);
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
		p->job = job;
		p->arg = arg;
		atomic_store_explicit(&p->running, p->workers - 1, memory_order_relaxed);
		atomic_fetch_add_explicit(&p->generation, 1, memory_order_release);
		pthread_mutex_lock(&p->lock); /* a thread that saw the old generation under it sleeps */
		if (p->sleepers)
			pthread_cond_broadcast(&p->wake);
		pthread_mutex_unlock(&p->lock);
	}
	job(arg, 0);
	if (p->workers > 1 && !spin_for(&p->running, 0, true, NULL)) {
		pthread_mutex_lock(&p->lock);
		p->caller_waiting = true;
		while (atomic_load(&p->running))
			pthread_cond_wait(&p->done, &p->lock);
		p->caller_waiting = false;
		pthread_mutex_unlock(&p->lock);
	}
}
