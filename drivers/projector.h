/* Projectors: a volumetric frame buffer holding 2 or 3 volume buffers. The
 * daemon uploads a volume into a free buffer and asks for a swap; the device
 * shows that buffer from the next revolution start and reports the swap.
 * Backends: "sim" (a simulated projector speaking the projector wire
 * protocol of proto/projector.md through drivers/projwire), later "usb". */
#ifndef SPINDLE_PROJECTOR_H
#define SPINDLE_PROJECTOR_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry.h"
#include "volume.h"

struct projector;

struct projector_info {
	char name[64];
	struct geometry geom;
	uint32_t buffers;            /* volume buffers, 2 or 3 */
	uint64_t link_bytes_per_sec; /* sustained upload rate, 0 = unknown */
};

struct projector_listener {
	/* buffer is shown from the revolution that started at time_ns. */
	void (*swapped)(void *data, uint32_t buffer, int64_t time_ns);
	/* The device failed or went away; the projector object stays valid
	 * but every call returns -ENODEV. */
	void (*gone)(void *data, int err);
};

struct projector_impl {
	const char *name;
	int (*get_info)(struct projector *p, struct projector_info *out);
	/* Dark (true) or lit (false). Takes effect at once. */
	int (*blank)(struct projector *p, bool blank);
	/* Revolution period and the time of the latest index pulse. */
	int (*set_timing)(struct projector *p, int64_t period_ns, int64_t index_ns);
	/* Writes vol into buffer (not the one shown nor one awaiting a swap).
	 * Returns 0 once queued; -EBUSY if that buffer is not free. */
	int (*upload)(struct projector *p, uint32_t buffer, const struct volume *vol);
	/* Shows buffer from the next revolution start after its upload is
	 * complete; swapped() reports it. */
	int (*swap)(struct projector *p, uint32_t buffer);
	/* A pollable fd for the event loop (-1 if none) and its handler. */
	int (*get_fd)(struct projector *p);
	int (*dispatch)(struct projector *p);
	/* The volume on display now as the device holds it, when the device
	 * can tell (sim); NULL otherwise. Valid until the next dispatch. */
	const struct volume *(*shown)(struct projector *p);
	void (*destroy)(struct projector *p);
};

/* Base struct, embedded first in each backend. */
struct projector {
	const struct projector_impl *impl;
	const struct projector_listener *listener;
	void *listener_data;
};

struct sim_rotor;

struct proj_sim_config {
	struct geometry geom;
	uint32_t buffers;            /* 2 or 3 */
	uint64_t link_bytes_per_sec; /* modelled link rate, 0 = unlimited */
};

/* A simulated projector on the simulated rotor. Starts blanked. NULL + errno
 * on failure. The rotor must outlive it. */
struct projector *proj_sim_create(struct sim_rotor *rotor, const struct proj_sim_config *cfg,
				  const struct projector_listener *listener, void *data);

/* Counters the simulated projector keeps (for status and tests). */
struct proj_sim_stats {
	uint64_t revolutions; /* revolution starts seen */
	uint64_t swaps;
	uint64_t underruns;   /* swaps that missed a revolution start for want of data */
	uint64_t bytes;       /* wire bytes received */
};
void proj_sim_get_stats(struct projector *p, struct proj_sim_stats *out);

#endif
