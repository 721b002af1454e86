/* The display hardware as the daemon sees it: a rotation sync source with
 * its estimator, and a projector; the simulated ones for --device sim. Owns
 * the safety rule: the projector is lit only while the sync is locked, and
 * dark at start and on exit. */
#ifndef SPINDLE_DEVICES_H
#define SPINDLE_DEVICES_H

#include <stdbool.h>
#include <stdint.h>

struct config;
struct geometry;
struct projector;
struct sd_event;
struct volume;

#define DEVICES_LISTENER_VERSION 1

/* What the devices report, from the event loop. */
struct devices_listener {
	uint32_t version; /* DEVICES_LISTENER_VERSION */
	/* The projector was lit at time_ns (a volume swapped in while it
	 * was dark is shown from then on). */
	void (*lit)(void *data, int64_t time_ns);
	/* A revolution started at time_ns (an accepted index edge), the
	 * projector lit. */
	void (*revolution)(void *data, int64_t time_ns);
	/* With half-turn swaps (devices_half_turns()): the half-turn start of
	 * the revolution in progress, as the sync estimator predicts it, the
	 * projector lit: the volume on display is shown anew from there, and
	 * a new one could have been. */
	void (*half_turn)(void *data, int64_t time_ns);
	/* A batch of index edges was taken and the projector is lit: the
	 * volume on display is whole at a revolution start. */
	void (*synced)(void *data);
	/* Lock, light or projector presence changed (devices_get_status()). */
	void (*state_changed)(void *data);
	/* The projector's events (drivers/projector.h): buffer, holding
	 * volume seq, is shown from time_ns on; it lost what buffer held;
	 * it went away; one (dark, empty) arrived. */
	void (*swapped)(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq);
	void (*buffer_error)(void *data, uint32_t buffer, int err);
	void (*gone)(void *data);
	void (*arrived)(void *data);
};

struct devices_status {
	float rpm; /* measured; 0 when not turning */
	bool locked;
	bool blanked;
	bool projector_present;
	uint64_t underruns;
	float jitter_us;
	uint64_t missed_pulses;                 /* missed and glitch edges */
	uint64_t upload_rate;                   /* bytes/s over the last second */
	float index_error_us;                   /* RMS, predicted vs measured index */
	float angle_error_p99, angle_error_max; /* slices, < 0: unknown */
};

/* Opens the devices of cfg->device (cfg is kept) with geom, their event
 * sources in event. NULL + errno on failure. */
struct devices *devices_create(struct sd_event *event, const struct config *cfg, const struct geometry *geom,
			       const struct devices_listener *listener, void *data);
/* Blanks the projector and closes everything. Accepts NULL. */
void devices_destroy(struct devices *dev);

struct config;
/* spindled --blank: darkens the projector of cfg, if one is attached, and
 * lets it go. 0 (also with no projector, or device sim) or negative errno. */
int devices_blank(const struct config *cfg);

/* What the devices are, for logs and clients ("simulated small"). */
const char *devices_name(const struct devices *dev);
struct projector *devices_projector(struct devices *dev);
/* The volume on display as the projector holds it, if it can tell. */
const struct volume *devices_shown(struct devices *dev);
/* Whether the projector is lit (not blanked). */
bool devices_lit(const struct devices *dev);
void devices_get_status(struct devices *dev, struct devices_status *out);
/* While lit: the predicted start of the first revolution after now (ns,
 * CLOCK_MONOTONIC), with the period in *period_ns; 0 when dark or not
 * locked. */
int64_t devices_next_revolution(const struct devices *dev, int64_t now, int64_t *period_ns);
/* Whether volumes are swapped in at half-turn starts: the key
 * half-turn-swaps is on, and the projector attached can (a mirrored device
 * speaking projector protocol 1.2: drivers/projector.h). */
bool devices_half_turns(const struct devices *dev);
/* Like devices_next_revolution(), for the boundaries a swap can take:
 * half-turn starts when devices_half_turns() (then *period_ns is half a
 * revolution), else revolution starts. */
int64_t devices_next_boundary(const struct devices *dev, int64_t now, int64_t *period_ns);

#endif
