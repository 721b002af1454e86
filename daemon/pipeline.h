/* The volume pipeline: committed scene -> snapshot -> render (on a worker
 * thread) -> upload into a free projector buffer -> swap at the next
 * boundary (half-turn start where the devices can, devices_half_turns();
 * else revolution start) -> shown. At most one render runs and one swap is
 * pending at a time; a volume is never uploaded into the buffer on show or
 * the one awaiting its swap, so nothing is ever shown half-written. */
#ifndef SPINDLE_PIPELINE_H
#define SPINDLE_PIPELINE_H

#include <stdbool.h>
#include <stdint.h>

#include "calibration.h"
#include "geometry.h"

struct devices;
struct renderer;
struct sd_event;
struct stage;
struct volume;

struct pipeline_stats {
	uint64_t volumes_rendered;
	uint64_t volumes_skipped; /* scenes identical to the last rendered */
	uint64_t volumes_shown;
	uint32_t last_render_us; /* wall time of the last render */
	uint64_t volumes_uploaded;
	uint64_t last_upload_bytes; /* wire bytes of the last upload (whole or delta) */
	uint64_t bytes_uploaded;    /* wire bytes of every upload */
};

struct pipeline_config {
	struct sd_event *event;
	struct stage *stage;     /* what is shown, read at each scene taken */
	struct devices *devices; /* its projector, and when revolutions start */
	uint64_t max_scene_primitives;
	/* The object cache (cache.h): off renders every scene whole. */
	bool cache;
	uint64_t cache_budget;          /* bytes */
	unsigned threads;               /* composing; 0 = one per core */
	struct calibration calibration; /* applied to every volume (calibration.h) */
};

#define PIPELINE_LISTENER_VERSION 1

struct pipeline_listener {
	uint32_t version; /* PIPELINE_LISTENER_VERSION */
	/* A scene was taken from the stage for volume seq: the frames of
	 * every commit made so far belong to it. unchanged: the scene was
	 * the one last rendered, so volume seq (shown already, or on its
	 * way) shows it, and nothing is rendered. */
	void (*scene_taken)(void *data, uint64_t seq, bool unchanged);
	/* Volume seq was swapped in at time_ns (shown then if the projector
	 * is lit). */
	void (*shown)(void *data, uint64_t seq, int64_t time_ns);
};

/* Takes ownership of renderer; the devices stay the caller's, and their
 * projector says how many volume buffers it has. NULL + errno on failure. */
struct pipeline *pipeline_create(const struct pipeline_config *cfg, struct renderer *renderer,
				 const struct pipeline_listener *listener, void *data);
/* Waits for a render in flight. Accepts NULL. */
void pipeline_destroy(struct pipeline *p);

/* The committed scene may have changed, or commits wait for frames: a
 * new scene is taken as soon as no render runs. It is rendered unless it
 * is identical to the scene last rendered; then that volume (shown, or
 * on its way) shows those commits too, and nothing is rendered or
 * uploaded. */
void pipeline_mark_dirty(struct pipeline *p);
/* The calibration from the next scene taken on: a scene is rendered
 * unless it is the one last rendered under the same calibration. */
void pipeline_set_calibration(struct pipeline *p, const struct calibration *cal);
/* The projector reports buffer, holding volume seq, shown from time_ns on. */
void pipeline_swapped(struct pipeline *p, uint32_t buffer, int64_t time_ns, uint64_t seq);
/* The projector lost what was sent to buffer (its error event): a swap
 * pending on it is dropped and its volume sent again, whole. */
void pipeline_device_error(struct pipeline *p, uint32_t buffer, int err);
/* The projector went away: nothing is shown or pending. When one arrives
 * (dark, empty), the newest volume is sent again, whole. */
void pipeline_projector_gone(struct pipeline *p);
void pipeline_projector_arrived(struct pipeline *p);
/* Whether a swap was asked for and not yet reported: a newer volume may
 * be shown from the next boundary on. */
bool pipeline_swap_pending(const struct pipeline *p);
/* When the render in flight started (ns, CLOCK_MONOTONIC), 0 when none
 * runs. Accepts NULL. */
int64_t pipeline_render_started(struct pipeline *p);
/* The volume on display as the daemon sent it, or NULL before the first. */
const struct volume *pipeline_shown(const struct pipeline *p);
void pipeline_get_stats(const struct pipeline *p, struct pipeline_stats *out);
/* The object cache's budget from now on (cache_set_budget()). */
void pipeline_set_cache_budget(struct pipeline *p, uint64_t bytes);
struct cache_stats;
/* The object cache's counters; false (out untouched) when it is off. */
bool pipeline_get_cache_stats(const struct pipeline *p, struct cache_stats *out);

#endif
