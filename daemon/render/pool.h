/* A persistent pool of worker threads for the CPU renderer: created once,
 * woken per job, no thread creation per volume. The calling thread works
 * as worker 0, so a pool of n workers has n - 1 threads. */
#ifndef SPINDLE_POOL_H
#define SPINDLE_POOL_H

struct pool;

/* job(arg, worker) runs once on each of the n workers (worker 0..n-1). */
typedef void (*pool_job)(void *arg, unsigned worker);

/* A pool of up to n workers (fewer when threads cannot be started; never
 * fewer than 1). NULL + errno on failure. */
struct pool *pool_create(unsigned n);
/* Accepts NULL. */
void pool_destroy(struct pool *p);

unsigned pool_workers(const struct pool *p);

/* Runs job on every worker and returns when all have finished. Not
 * reentrant: one job at a time. */
void pool_run(struct pool *p, pool_job job, void *arg);

#endif
