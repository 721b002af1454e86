/* The sync estimator: turns index-pulse timestamps into the rotor's period,
 * phase, speed, jitter and a lock state, for any sync backend.
 *
 * Lock means "the rotor turns as it must, the projector may be lit": it is
 * gained after lock_revs consecutive revolutions that agree within tolerance
 * at a speed inside the band, and lost at once when the speed leaves the band
 * or no edge comes for timeout_periods expected periods (found by
 * sync_estimator_check(), which the owner calls from a timer armed at
 * sync_estimator_deadline()). Edges far too early are glitches and ignored;
 * gaps of about k periods count k - 1 missed pulses.
 *
 * Period and phase come from a least-squares line through the last
 * SYNC_ESTIMATOR_FIT accepted edges, edge time against revolution number
 * (missed pulses counted in, glitches left out). The rotor is heavy, so
 * its revolution starts lie on a line and edge-to-edge wander is sensing
 * noise: the line's prediction of the next index is about sqrt(4/n) times
 * the noise of one edge (n edges in the fit), where taking the last edge
 * as the phase passes all of it on. The price is lag when the speed
 * changes: under a constant change of period per revolution c (ns/rev)
 * the line's index misses by about c * n^2 / 12, e.g. 0.46 ms (2.2 slices
 * of 396 at 730 rpm) for a speed drifting 200 ppm/s, 23 us for 10 ppm/s.
 * Lock and band are judged on the mean of the last SYNC_ESTIMATOR_WINDOW
 * periods instead, which follows speed changes within a few revolutions. */
#ifndef SPINDLE_SYNC_ESTIMATOR_H
#define SPINDLE_SYNC_ESTIMATOR_H

#include <stdbool.h>
#include <stdint.h>

#define SYNC_ESTIMATOR_WINDOW 16 /* recent periods kept for mean, band and jitter */
#define SYNC_ESTIMATOR_FIT 64    /* accepted edges in the period/phase fit */

struct sync_estimator_config {
	double nominal_rpm;
	double band;            /* allowed relative speed deviation, e.g. 0.10 */
	double tolerance;       /* relative period deviation of a consistent revolution */
	uint32_t lock_revs;     /* consistent revolutions before lock */
	double timeout_periods; /* no edge for this many periods unlocks */
	double glitch_fraction; /* an edge sooner than this fraction of a period is a glitch */
	uint32_t max_missed;    /* a longer gap is a stall: start over */
};

enum sync_unlock_reason {
	SYNC_UNLOCK_NONE = 0, /* never locked yet */
	SYNC_UNLOCK_TIMEOUT,  /* no edge in time: stopped, or pulses missing */
	SYNC_UNLOCK_BAND,     /* speed outside nominal +/- band */
	SYNC_UNLOCK_UNSTABLE, /* a run of glitches: the pulse train makes no sense */
};

struct sync_state {
	bool locked;
	enum sync_unlock_reason unlock_reason; /* why the last unlock happened */
	int64_t period_ns;                     /* fitted period, 0 until one is measured */
	int64_t phase_ns;                      /* fitted time of the latest revolution start, 0 if none */
	int64_t edge_ns;                       /* the latest accepted index edge, 0 if none */
	double rpm;                            /* from the mean of recent periods (what the band
			    * is judged on), 0 until known */
	int64_t jitter_ns;                     /* RMS deviation of recent periods from their mean */
	/* How far each new edge fell from where the fit predicted it: RMS,
	 * over about the last SYNC_ESTIMATOR_FIT edges (0 until known). Edge
	 * noise and prediction error together, so an upper bound on how far
	 * off the projector places slices (in time) on any hardware. */
	int64_t phase_err_ns;
	/* The standard error of the fit's next predicted index, from the
	 * scatter of the edges about it: the slice placement error itself if
	 * the scatter is sensing noise on a smoothly turning rotor. */
	int64_t fit_err_ns;
	/* Edges in the fit now. Right after lock it holds few and the
	 * prediction is about as noisy as one edge; it needs some 30 edges to
	 * place slices to a tenth of one edge's jitter: an owner that wants
	 * accurate slices from the first lit revolution waits for fit_edges
	 * and fit_err_ns, not just for lock. */
	uint32_t fit_edges;
	uint64_t edges;    /* edges fed, glitches included */
	uint64_t glitches; /* edges rejected as too early */
	uint64_t missed;   /* pulses inferred missing from gaps */
	uint64_t locks, unlocks;
};

struct sync_estimator;

/* Fills cfg with defaults for nominal_rpm: band 10 %, tolerance 2 %, lock
 * after 4 revolutions, timeout 1.5 periods, glitch before 0.75 periods,
 * gaps of up to 8 periods counted as missed pulses. */
void sync_estimator_config_default(struct sync_estimator_config *cfg, double nominal_rpm);

/* NULL + errno (EINVAL for a bad config) on failure. */
struct sync_estimator *sync_estimator_create(const struct sync_estimator_config *cfg);
/* Accepts NULL. */
void sync_estimator_destroy(struct sync_estimator *est);

/* Forgets everything but the counters; unlocks. */
void sync_estimator_reset(struct sync_estimator *est);

/* Feeds one edge timestamp (ns, CLOCK_MONOTONIC, oldest first). Returns true
 * when the lock state changed. */
bool sync_estimator_feed(struct sync_estimator *est, int64_t t_ns);

/* Unlocks if no edge came within timeout_periods expected periods before
 * now_ns. Returns true when the lock state changed. */
bool sync_estimator_check(struct sync_estimator *est, int64_t now_ns);

/* When sync_estimator_check() should next run: the time the edge timeout
 * expires, INT64_MAX when no edge has been seen. */
int64_t sync_estimator_deadline(const struct sync_estimator *est);

/* Whether the fit places revolution starts well enough to light the
 * projector: its standard error is at most max_err_ns over at least
 * SYNC_ESTIMATOR_SETTLE_EDGES edges (fewer say too little about the
 * scatter), or its window is full (the best this sensor allows). Lock is
 * the safety condition; this one is about slice accuracy. */
#define SYNC_ESTIMATOR_SETTLE_EDGES 8
bool sync_estimator_settled(const struct sync_estimator *est, int64_t max_err_ns);

/* The max_err_ns the daemon lights at: a sixteenth of a slice, so that
 * three standard errors stay under the quarter slice the display is held
 * to. At 730 rpm with 0.1 % period jitter that takes some 55 revolutions
 * after the first lock (a fit kept through a missed pulse needs none). */
static inline int64_t sync_light_max_err(int64_t period_ns, uint32_t images_per_rev)
{
	return period_ns / images_per_rev / 16;
}

/* Predicted next index time: phase + period, 0 while the period is unknown. */
int64_t sync_estimator_next_index(const struct sync_estimator *est);

/* Predicted first index time at or after t, 0 while the period is unknown. */
int64_t sync_estimator_index_after(const struct sync_estimator *est, int64_t t);

/* The current state; owned by est, valid until it is destroyed. */
const struct sync_state *sync_estimator_state(const struct sync_estimator *est);

#endif
