/* Rotation sync sources: the index pulse, once per revolution (rising edge),
 * timestamped with CLOCK_MONOTONIC. Backends: "sim" (a simulated rotor) and
 * "gpiod" (a GPIO line through libgpiod, sync_gpiod.c). The estimator
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

/* An index pulse source for the simulated rotor: one edge at each time the
 * rotor's true angle passes 0. NULL + errno on failure. The rotor must
 * outlive the source. */
struct sync_source *sync_sim_create(struct sim_rotor *rotor);

struct sync_gpiod_config {
	char chip[64]; /* name "gpiochip0", path "/dev/gpiochip0", label, or number */
	char line[64]; /* offset "17" or line name "ROTOR_INDEX" */
	bool active_low; /* the physical falling edge is the index */
};

/* The index pulse from a GPIO line through libgpiod: requests rising-edge
 * events on cfg's line as consumer "spindled" and holds the line until
 * destroyed. NULL + errno on failure (ENOENT: no such chip or line, EBUSY:
 * another consumer holds it, EINVAL: a bad cfg), with a log_error line naming
 * chip, line and why. cfg is copied. */
struct sync_source *sync_gpiod_create(const struct sync_gpiod_config *cfg);

#endif
