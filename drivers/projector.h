/* Projectors: a volumetric frame buffer holding 2 or 3 volume buffers. The
 * daemon uploads a volume into a free buffer and asks for a swap; the device
 * shows that buffer from the next revolution start (with swap_half(), on a
 * device that can, from the next half-turn start) and reports the swap.
 * Backends: "sim" (a simulated projector speaking the projector wire
 * protocol of proto/projector.md through drivers/projwire) and "usb" (a
 * real one through libusb, proj_usb.c).
 *
 * Boundaries. With period P and index time I as last given to set_timing(),
 * image k of a revolution starts at I + m * P + P * k / N (m whole). A
 * revolution start is the start of image 0: I + m * P. On mirrored geometry
 * (a volume of N/2 images shown twice a revolution, image k + N/2 being
 * image k mirrored) the first image of the volume also comes round at the
 * start of image N/2: the half-turn start I + m * P + P / 2. "Half-turn
 * starts" are both kinds: every I + j * P / 2. Before the first set_timing()
 * they are the device's own (nominal speed, unknown phase). The simulated
 * projector uses its rotor's true revolution and half-turn starts, which
 * these predict to the sync estimator's precision. A volume shown from
 * boundary T is shown whole from there: its image k at T + P * k / N, for
 * k < N/2 and then mirrored (or for k < N when not mirrored). */
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
	/* swap_half() swaps at half-turn starts: the device speaks protocol
	 * 1.2 or later and its geometry is mirrored. A new volume can then be
	 * shown every half revolution (twice the rate of swap()); when false,
	 * swap_half() is swap(). It may differ after arrived(), and turns
	 * false if a device that claims it refuses a half-turn swap (that
	 * swap is then made at the revolution start). */
	bool half_turn_swaps;
};

/* Counters for status; every field 0 when unknown. */
struct projector_stats {
	bool present;         /* a device is attached and set up */
	uint64_t revolutions; /* revolution starts the device saw */
	uint64_t swaps;
	uint64_t underruns;     /* swaps that missed their first boundary for want of data */
	uint64_t bytes_sent;    /* bulk OUT bytes the host completed, since creation */
	uint64_t device_errors; /* ERROR events and stalled requests */
	uint64_t arrivals;      /* times a device was set up (hot-plug included) */
	/* Slice angle error, in slices, over the revolutions shown so far:
	 * measured against the true rotor by the simulated projector; negative
	 * when the backend cannot know it. */
	double angle_err_p50, angle_err_p99, angle_err_max;
};

/* Listener callbacks run from dispatch() only, never from another call. */
struct projector_listener {
	/* buffer, holding volume seq, is shown from time_ns on: the boundary
	 * the swap took effect at. For swap() a revolution start; for
	 * swap_half() on a device with half_turn_swaps a half-turn start,
	 * either a revolution start or the start of image N/2 (see
	 * "Boundaries" above), whichever came first with the upload
	 * complete. The buffer shown before is free (uploadable) from this
	 * call on. Not called when swapped_at is set. */
	void (*swapped)(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq);
	/* Optional; when set, called instead of swapped(), with the same
	 * arguments and which boundary time_ns is: half_turn true for the
	 * start of image N/2 (the middle of a revolution, only ever after
	 * swap_half()), false for a revolution start. */
	void (*swapped_at)(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq, bool half_turn);
	/* The device refused or lost what was sent to buffer
	 * (PROJWIRE_NO_BUFFER: no buffer concerned); err is a negative errno.
	 * The buffer's content is unknown from now on and a swap pending on it
	 * is dropped: the owner uploads again, in full. */
	void (*error)(void *data, uint32_t buffer, int err);
	/* The device failed or went away. Every call returns -ENODEV until
	 * arrived(); the projector object stays valid. */
	void (*gone)(void *data, int err);
	/* A device was attached after creation (plugged in, or re-plugged)
	 * and set up: dark, every buffer empty, nothing shown. get_info()
	 * describes it. A device present at creation is set up by create and
	 * not reported (get_stats().present says). */
	void (*arrived)(void *data);
};

struct projector_impl {
	const char *name;
	/* -ENODEV while no device is present. */
	int (*get_info)(struct projector *p, struct projector_info *out);
	/* Dark (true) or lit (false). Takes effect at once. */
	int (*blank)(struct projector *p, bool blank);
	/* Revolution period and the time of a recent revolution start. */
	int (*set_timing)(struct projector *p, int64_t period_ns, int64_t index_ns);
	/* Writes vol into buffer (not the one shown nor one awaiting a swap).
	 * base is what the buffer holds now as far as the caller knows (the
	 * last volume it uploaded there, completed without error), or NULL
	 * when unknown or empty: with a base only the tiles that differ are
	 * sent. differ, with a base, may mark the tiles that may differ from
	 * it (projwire_upload_plan(): a mask per image; NULL: any may), so
	 * that the others are not compared. Returns the wire bytes queued
	 * (> 0) once queued (vol, base and differ need not outlive the call);
	 * -EBUSY if that buffer is not free; -ENODEV with no device. */
	int (*upload)(struct projector *p, uint32_t buffer, const struct volume *vol, const struct volume *base,
		      const uint8_t *differ);
	/* Shows buffer from the next revolution start after its upload is
	 * complete; swapped() reports it. 0; -EINVAL (no such buffer),
	 * -EBUSY (buffer shown, or a swap pending: one at a time), -ENODATA
	 * (nothing, or a failed volume, uploaded there), -ENODEV. (The USB
	 * backend holds a request back until the upload's first record is
	 * out; a refusal then comes through error().) An upload not complete
	 * by the next revolution start counts one underrun and shows from the
	 * first revolution start after it is. */
	int (*swap)(struct projector *p, uint32_t buffer);
	/* swap(), but at half-turn granularity when get_info() says
	 * half_turn_swaps: buffer is shown from the next half-turn start
	 * (the next start of image 0 or of image N/2) after its upload is
	 * complete, so a volume can be swapped in every half revolution. The
	 * same returns and rules as swap(): one swap pending at a time (either
	 * kind), the previously shown buffer busy until swapped() reports
	 * this one; an upload not complete by the next half-turn start counts
	 * one underrun and shows from the first half-turn start after it is.
	 * swapped() (swapped_at()) gives the boundary. Without
	 * half_turn_swaps (an older device, or one not mirrored) it is swap()
	 * exactly, and the device never sees a half-turn request. */
	int (*swap_half)(struct projector *p, uint32_t buffer);
	/* A pollable fd for the event loop (-1 if none) and its handler. */
	int (*get_fd)(struct projector *p);
	int (*dispatch)(struct projector *p);
	/* The volume on display now as the device holds it, when the device
	 * can tell (sim); NULL otherwise. Valid until the next dispatch. */
	const struct volume *(*shown)(struct projector *p);
	void (*get_stats)(struct projector *p, struct projector_stats *out);
	/* Blanks the device, cancels whatever is in flight and frees. */
	void (*destroy)(struct projector *p);
};

/* Base struct, embedded first in each backend. */
struct projector {
	const struct projector_impl *impl;
	const struct projector_listener *listener;
	void *listener_data;
};

struct sim_rotor;

struct sim_faults;

struct proj_sim_config {
	struct geometry geom;
	uint32_t buffers;                /* 2 or 3 */
	uint64_t link_bytes_per_sec;     /* modelled link rate, 0 = unlimited */
	const struct sim_faults *faults; /* its unplug events; NULL = none */
	/* The device's protocol version 1.minor, for tests of the fallback:
	 * 0 = the latest (PROJWIRE_VERSION_MINOR, 2: half-turn swaps); 1 = a
	 * 1.1 device, which stalls SWAP_HALF (so swap_half() never sends it
	 * one); above the latest, create fails (EINVAL). The model takes
	 * delta volumes at any minor. */
	uint8_t version_minor;
};

/* A simulated projector on the simulated rotor. Starts blanked. NULL + errno
 * on failure. The rotor must outlive it. */
struct projector *proj_sim_create(struct sim_rotor *rotor, const struct proj_sim_config *cfg,
				  const struct projector_listener *listener, void *data);

struct proj_usb_config {
	uint16_t vid, pid;    /* 0 = any; the interface must be Spindle's (class
			      * ff, subclass 53, protocol 01) either way */
	char bus_path[32];    /* "BUS-PORT.PORT..." as in sysfs (e.g. "1-2.4"),
			      * empty = any */
	struct geometry geom; /* what the daemon renders: a device reporting
			       * another geometry is refused (logged) */
};

/* The USB projector. Succeeds without a device attached: it is set up when
 * it arrives (hot-plug), and arrived()/gone() report it. NULL + errno when
 * libusb cannot start. */
struct projector *proj_usb_create(const struct proj_usb_config *cfg, const struct projector_listener *listener,
				  void *data);

/* Counters the simulated projector keeps (for status and tests). */
struct proj_sim_stats {
	uint64_t revolutions; /* revolution starts seen */
	uint64_t swaps;
	uint64_t underruns; /* swaps that missed their first boundary for want of data */
	uint64_t bytes;     /* wire bytes received */
	/* Measured by the device model against the true rotor (see
	 * drivers/proj_sim_meter.h): slice angle error in slices (-1 until
	 * measured), and the safety record. */
	double angle_err_p50, angle_err_p99, angle_err_max;
	uint64_t stalls;           /* stretches stopped or out of band */
	int64_t max_dark_delay_ns; /* last true index before a stall -> dark */
	int64_t lit_stopped_ns;    /* lit during stalls, detection included */
	int64_t lit_untimed_ns;    /* lit before any SET_TIMING */
	uint64_t watchdog_blanks;  /* darkened for want of control requests */
};
void proj_sim_get_stats(struct projector *p, struct proj_sim_stats *out);

#endif
