/* What the simulated projector measures about itself against the true
 * rotor: where each slice it lit really landed (angle error), and a safety
 * record of every stretch the rotor was stopped or out of speed band.
 * Private to the device model (proj_sim_dev.c) and the tests. */
#ifndef SPINDLE_PROJ_SIM_METER_H
#define SPINDLE_PROJ_SIM_METER_H

#include <stdbool.h>
#include <stdint.h>

#include "projwire.h"

/* The band outside which the rotor counts as not turning as it must: the
 * sync estimator's default (10 % of nominal). */
#define PROJ_METER_BAND 0.10

struct proj_simdev_stats {
	/* Slice angle error: for each slice lit with a volume shown, the true
	 * rotor angle at its time minus its nominal angle 2 pi k / N, wrapped
	 * to (-pi, pi], in slices; p50/p99 of its magnitude from a histogram
	 * of 1/1000-slice bins (upper bin edges), max exact. -1 while no slice
	 * was measured. */
	uint64_t slices;
	double angle_err_p50, angle_err_p99, angle_err_max;
	double angle_err_mean; /* signed: a bias in the timing */
	/* Safety record. A stall is a stretch in which the true speed is 0 or
	 * outside nominal +/- PROJ_METER_BAND; it starts at the last true
	 * index before the speed left the band. Dark delay: from that index
	 * to the moment the device went dark (0 when it already was dark;
	 * to the stall's end when it never went dark). */
	uint64_t stalls;
	int64_t max_dark_delay_ns, last_dark_delay_ns;
	int64_t lit_stopped_ns;   /* time lit during stalls (detection included) */
	int64_t lit_untimed_ns;   /* time lit before any SET_TIMING */
	uint64_t lit_through;     /* stalls that ended with the device never dark */
	uint64_t watchdog_blanks; /* darkened for want of control requests */
};

struct sim_rotor;
struct proj_meter;

/* A meter from time t on, for N = images_per_rev slices a revolution.
 * NULL + errno. */
struct proj_meter *proj_meter_create(struct sim_rotor *rotor, uint32_t images_per_rev, double nominal_rpm, int64_t t);
/* Accepts NULL. */
void proj_meter_destroy(struct proj_meter *m);

/* The device from the meter's time up to 'to': lit (light on, a volume
 * shown) or not, slices placed by timing (NULL: never set). The caller
 * splits time where any of these change: going dark at t is a run to t
 * lit, then runs from t dark. */
void proj_meter_run(struct proj_meter *m, int64_t to, bool lit, const struct projwire_timing *timing);

/* Fills the meter's part of out (everything but watchdog_blanks). */
void proj_meter_get(const struct proj_meter *m, struct proj_simdev_stats *out);

#endif
