/* The simulated index pulse: a timerfd armed for the next edge. Edges carry
 * the modelled sensor's timestamps, not the timer's wake-up time, so the
 * estimator sees what a kernel-timestamped GPIO edge would give and
 * scheduling latency does not show up as jitter.
 *
 * Pulse faults model the sensing, never the motion: the rotor is heavy and
 * turns smoothly (sim_rotor.h), while the sensor's edge wanders around the
 * true index time (jitter: Gaussian, independent per edge), sometimes does
 * not fire (missed) and sometimes fires on noise (extra). Independent edge
 * noise of sigma s gives measured periods of RMS deviation s * sqrt(2), so
 * "jitter=0.001" (periods deviating by 0.1 % RMS, what the estimator shows
 * as jitter) means s = 0.001 * period / sqrt(2). Random numbers come from
 * a seeded xorshift64*, drawn in the same order for every revolution, so a
 * seed gives one pulse train whatever is read when. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "sim_rotor.h"
#include "sync.h"

#define QUEUE_MAX 2 /* edges of one revolution: its own and a glitch */

struct sync_sim {
	struct sync_source base;
	struct sim_rotor *rotor;
	int fd;
	double jitter_ns, p_missed, p_extra; /* jitter_ns: per-edge sigma */
	uint64_t rng;
	int64_t next_rev;         /* the next true revolution start to model */
	int64_t queue[QUEUE_MAX]; /* edges not yet read, oldest first */
	int queued, head;
	int64_t last_sent;
	struct sync_sim_stats stats;
};

static const struct sync_impl sim_impl;

static uint64_t rng_next(struct sync_sim *s)
{
	s->rng ^= s->rng >> 12;
	s->rng ^= s->rng << 25;
	s->rng ^= s->rng >> 27;
	return s->rng * 0x2545f4914f6cdd1dull;
}

/* Uniform in (0, 1). */
static double rng_uniform(struct sync_sim *s)
{
	return ((double)(rng_next(s) >> 11) + 0.5) / 9007199254740992.0;
}

static double rng_gauss(struct sync_sim *s)
{
	double u = rng_uniform(s), v = rng_uniform(s);
	return sqrt(-2.0 * log(u)) * cos(2.0 * M_PI * v);
}

static void enqueue(struct sync_sim *s, int64_t t)
{
	if (t <= s->last_sent)
		t = s->last_sent + 1; /* edges are strictly increasing, as a GPIO gives */
	int i = s->queued++;
	while (i > 0 && s->queue[i - 1] > t) {
		s->queue[i] = s->queue[i - 1];
		i--;
	}
	s->queue[i] = t;
	s->last_sent = s->queue[s->queued - 1];
}

/* Models the sensor over the next true revolution start. False when the
 * rotor never gets there. */
static bool model_revolution(struct sync_sim *s)
{
	int64_t t = sim_rotor_index_time(s->rotor, s->next_rev);
	if (t == SIM_ROTOR_NEVER)
		return false;
	int64_t next = sim_rotor_index_time(s->rotor, s->next_rev + 1);
	int64_t span = next == SIM_ROTOR_NEVER ? sim_rotor_period_ns(s->rotor) : next - t;
	s->next_rev++;
	s->stats.true_edges++;
	/* Every draw is made whatever the probabilities, for reproducibility. */
	bool lost = rng_uniform(s) < s->p_missed;
	double noise = rng_gauss(s) * s->jitter_ns;
	bool glitch = rng_uniform(s) < s->p_extra;
	double where = 0.05 + 0.9 * rng_uniform(s); /* clear of the real edges */
	s->queued = s->head = 0;
	if (lost)
		s->stats.missed++;
	else
		enqueue(s, t + llround(noise));
	if (glitch) {
		s->stats.extra++;
		enqueue(s, t + llround(where * (double)span));
	}
	return true;
}

/* The oldest edge not yet read; SIM_ROTOR_NEVER when there is none to come. */
static int64_t peek(struct sync_sim *s)
{
	while (s->head == s->queued)
		if (!model_revolution(s))
			return SIM_ROTOR_NEVER;
	return s->queue[s->head];
}

static int sim_arm(struct sync_sim *s)
{
	int64_t t = peek(s);
	struct itimerspec its = { 0 }; /* never: disarmed */
	if (t != SIM_ROTOR_NEVER)
		its.it_value = (struct timespec){ .tv_sec = t / 1000000000, .tv_nsec = t % 1000000000 };
	if (t != SIM_ROTOR_NEVER && t <= 0)
		its.it_value.tv_nsec = 1; /* 0 would disarm */
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
	int64_t now = sim_rotor_now(s->rotor);
	int n = 0;
	while (n < max && peek(s) <= now) {
		ts[n++] = s->queue[s->head++];
		s->stats.sent++;
	}
	/* Edges left over when max was reached make the fd readable at once,
	 * since the next one is then already in the past. */
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

static void set_faults(struct sync_sim *s, const struct sim_faults *f)
{
	s->rng = f ? f->seed : 0;
	s->rng = (s->rng + 0x9e3779b97f4a7c15ull) * 0xbf58476d1ce4e5b9ull; /* never 0 */
	s->rng ^= s->rng >> 31;
	s->rng |= 1;
	if (!f)
		return;
	s->jitter_ns = f->jitter * (double)sim_rotor_period_ns(s->rotor) / sqrt(2.0);
	s->p_missed = f->missed;
	s->p_extra = f->extra;
}

struct sync_source *sync_sim_create_faults(struct sim_rotor *rotor, const struct sim_faults *faults)
{
	struct sync_sim *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &sim_impl;
	s->rotor = rotor;
	set_faults(s, faults);
	s->fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
	if (s->fd < 0)
		goto err_free; /* free() keeps errno */
	/* Edges from before the source existed were never seen by anyone. */
	int64_t now = sim_rotor_now(rotor);
	s->next_rev = sim_rotor_revolution(rotor, now);
	if (sim_rotor_index_time(rotor, s->next_rev) < now)
		s->next_rev++;
	s->last_sent = INT64_MIN;
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

struct sync_source *sync_sim_create(struct sim_rotor *rotor)
{
	return sync_sim_create_faults(rotor, NULL);
}

void sync_sim_get_stats(struct sync_source *base, struct sync_sim_stats *out)
{
	*out = (struct sync_sim_stats){ 0 };
	if (base->impl == &sim_impl)
		*out = ((struct sync_sim *)base)->stats;
}
