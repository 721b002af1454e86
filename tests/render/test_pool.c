/* The renderers' worker pool (pool.h): every job runs once on each worker,
 * the caller sees everything the workers wrote when pool_run() returns,
 * and workers see what the caller wrote before it; back to back (workers
 * still looking for work), after a pause longer than they look (workers
 * asleep), alternating, and destroyed in either state. */
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "check.h"
#include "pool.h"

#define MAX_WORKERS 8
#define CELLS 4096

struct job {
	unsigned workers;
	uint64_t round; /* written by the caller before each run */
	atomic_uint calls[MAX_WORKERS];
	uint64_t seen[MAX_WORKERS]; /* each worker's view of round */
	uint64_t cells[MAX_WORKERS][CELLS];
};

static void work(void *arg, unsigned worker)
{
	struct job *j = arg;
	atomic_fetch_add(&j->calls[worker], 1);
	j->seen[worker] = j->round;
	for (unsigned i = 0; i < CELLS; i++) /* plain stores, read by the caller */
		j->cells[worker][i] = j->round * CELLS + i;
}

static void pause_us(long us)
{
	struct timespec ts = { .tv_sec = 0, .tv_nsec = us * 1000 };
	nanosleep(&ts, NULL);
}

/* rounds runs of p, with a pause of pause_us before every other one when
 * alternate, else before each when pause_us; checks each. */
static void run_rounds(struct pool *p, struct job *j, unsigned rounds, long pause, bool alternate)
{
	for (unsigned r = 0; r < rounds; r++) {
		if (pause && (!alternate || r % 2))
			pause_us(pause);
		j->round++;
		pool_run(p, work, j);
		for (unsigned w = 0; w < j->workers; w++) {
			CHECK_EQ(atomic_load(&j->calls[w]), j->round);
			CHECK_EQ(j->seen[w], j->round);
			CHECK_EQ(j->cells[w][CELLS - 1], j->round * CELLS + CELLS - 1);
			CHECK_EQ(j->cells[w][0], j->round * CELLS);
		}
	}
}

static void check_pool(unsigned n)
{
	struct pool *p = pool_create(n);
	CHECK(p);
	struct job *j = calloc(1, sizeof(*j));
	CHECK(j);
	j->workers = pool_workers(p);
	CHECK(j->workers >= 1 && j->workers <= n);
	run_rounds(p, j, 2000, 0, false);  /* back to back */
	run_rounds(p, j, 20, 2000, false); /* asleep each time (2 ms > the spin) */
	run_rounds(p, j, 200, 100, true);  /* both, in turn */
	pool_destroy(p);                   /* workers still looking */
	CHECK_EQ(atomic_load(&j->calls[0]), j->round);
	p = pool_create(n);
	CHECK(p);
	run_rounds(p, j, 1, 0, false);
	pause_us(5000);
	pool_destroy(p); /* workers asleep */
	free(j);
}

int main(void)
{
	for (unsigned n = 1; n <= 4; n++)
		check_pool(n);
	check_pool(MAX_WORKERS);
	return check_done();
}
