/* Rotation sync sources: the index pulse, once per revolution (rising edge),
 * timestamped with CLOCK_MONOTONIC. Backends: "sim" (a simulated rotor) and
 * "gpiod" (a GPIO line through libgpiod: sync_gpiod_common.c, with
 * sync_gpiod.c for libgpiod 1 or sync_gpiod2.c for libgpiod 2). The estimator
 * turning edges into period/phase/lock lives in sync_estimator.h and is
 * shared by every backend. */
#ifndef SPINDLE_SYNC_H
#define SPINDLE_SYNC_H

#include <stdbool.h>
#include <stdint.h>

struct sync_source;

struct sync_impl {
	const char *name;
	/* A pollable fd that becomes readable when edges are pending. */
	int (*get_fd)(struct sync_source *s);
	/* Reads up to max pending edge timestamps (ns, CLOCK_MONOTONIC) into
	 * ts, oldest first. Returns the count (0: none pending) or -errno. */
	int (*read_edges)(struct sync_source *s, int64_t *ts, int max);
	void (*destroy)(struct sync_source *s);
};

/* Base struct, embedded first in each backend. */
struct sync_source {
	const struct sync_impl *impl;
};

static inline int sync_get_fd(struct sync_source *s)
{
	return s->impl->get_fd(s);
}

static inline int sync_read_edges(struct sync_source *s, int64_t *ts, int max)
{
	return s->impl->read_edges(s, ts, max);
}

/* Accepts NULL. */
static inline void sync_destroy(struct sync_source *s)
{
	if (s)
		s->impl->destroy(s);
}

struct sim_rotor;
struct sim_faults;

/* An index pulse source for the simulated rotor: one edge at each time the
 * rotor's true angle passes 0. Same as sync_sim_create_faults(rotor, NULL). */
struct sync_source *sync_sim_create(struct sim_rotor *rotor);

/* The same with the pulse faults of faults (NULL: none): each edge moved
 * from the true index time by Gaussian noise of sigma jitter * period /
 * sqrt(2), so that measured periods deviate by jitter * period RMS; a
 * revolution's pulse lost with probability missed; a glitch edge at a
 * random time within a revolution with probability extra. Deterministic
 * for a given seed. The motion faults are the rotor's
 * (sim_rotor_apply_faults), applied before this is created. NULL + errno
 * on failure. The rotor must outlive the source; faults is copied. */
struct sync_source *sync_sim_create_faults(struct sim_rotor *rotor, const struct sim_faults *faults);

/* What a sim source actually sent (tests compare the estimator with it). */
struct sync_sim_stats {
	uint64_t true_edges; /* revolution starts passed */
	uint64_t sent;       /* edges reported, glitches included */
	uint64_t missed;     /* revolution starts not reported */
	uint64_t extra;      /* glitch edges reported */
};
/* Zeroes out when s is not a sim source. */
void sync_sim_get_stats(struct sync_source *s, struct sync_sim_stats *out);

struct sync_gpiod_config {
	char chip[64];   /* name "gpiochip0", path "/dev/gpiochip0", label, or number */
	char line[64];   /* offset "17" or line name "ROTOR_INDEX" */
	bool active_low; /* the physical falling edge is the index */
};

/* The index pulse from a GPIO line through libgpiod: requests rising-edge
 * events on cfg's line as consumer "spindled" and holds the line until
 * destroyed. NULL + errno on failure (ENOENT: no such chip or line, EBUSY:
 * another consumer holds it, EINVAL: a bad cfg), with a log_error line naming
 * chip, line and why. cfg is copied. */
struct sync_source *sync_gpiod_create(const struct sync_gpiod_config *cfg);

#endif
