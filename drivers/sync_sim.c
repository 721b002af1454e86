/* The simulated index pulse: a timerfd armed for the rotor's next revolution
 * start. Edges carry the rotor's true index times, not the timer's wake-up
 * time, so the estimator sees what a kernel-timestamped GPIO edge would give
 * and scheduling latency does not show up as jitter. */
#include <errno.h>
#include <stdlib.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "log.h"
#include "sim_rotor.h"
#include "sync.h"

struct sync_sim {
	struct sync_source base;
	struct sim_rotor *rotor;
	int fd;
	int64_t next_edge; /* the oldest edge not yet read */
};

static int sim_arm(struct sync_sim *s)
{
	struct itimerspec its = {
		.it_value = { .tv_sec = s->next_edge / 1000000000, .tv_nsec = s->next_edge % 1000000000 },
	};
	if (timerfd_settime(s->fd, TFD_TIMER_ABSTIME, &its, NULL) < 0)
		return -errno;
	return 0;
}

static int sim_get_fd(struct sync_source *base)
{
	struct sync_sim *s = (struct sync_sim *)base;
	return s->fd;
}

static int sim_read_edges(struct sync_source *base, int64_t *ts, int max)
{
	struct sync_sim *s = (struct sync_sim *)base;
	uint64_t expirations;
	/* Drain first: re-arming below decides readability from here on. */
	if (read(s->fd, &expirations, sizeof(expirations)) < 0 && errno != EAGAIN)
		return -errno;
	int64_t now = now_ns();
	int n = 0;
	while (n < max && s->next_edge <= now) {
		ts[n++] = s->next_edge;
		s->next_edge = sim_rotor_next_index(s->rotor, s->next_edge + 1);
	}
	/* Edges left over when max was reached make the fd readable at once,
	 * since next_edge is then already in the past. */
	int r = sim_arm(s);
	return r < 0 ? r : n;
}

static void sim_destroy(struct sync_source *base)
{
	struct sync_sim *s = (struct sync_sim *)base;
	close(s->fd);
	free(s);
}

static const struct sync_impl sim_impl = {
	.name = "sim",
	.get_fd = sim_get_fd,
	.read_edges = sim_read_edges,
	.destroy = sim_destroy,
};

struct sync_source *sync_sim_create(struct sim_rotor *rotor)
{
	struct sync_sim *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &sim_impl;
	s->rotor = rotor;
	s->fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
	if (s->fd < 0)
		goto err_free; /* free() keeps errno */
	/* Edges from before the source existed were never seen by anyone. */
	s->next_edge = sim_rotor_next_index(rotor, now_ns());
	int r = sim_arm(s);
	if (r < 0)
		goto err_close;
	return &s->base;

err_close:
	close(s->fd);
	errno = -r;
err_free:
	free(s);
	return NULL;
}
