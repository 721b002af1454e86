#include "sync_estimator.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A run of this many glitches means the estimate, not the pulses, is wrong. */
#define GLITCH_RUN_RESEED 3
/* A run of this many edges off the fitted line means the line is wrong. */
#define OUTLIER_RUN_REFIT 3

struct sync_estimator {
	struct sync_estimator_config cfg;
	struct sync_state state;
	int64_t nominal_period;
	int64_t hist[SYNC_ESTIMATOR_WINDOW];
	uint32_t hist_len, hist_pos;
	int64_t mean_period; /* of hist: the speed for band, glitch and timeout */
	struct {
		int64_t rev, t; /* revolution number, edge time */
	} fit[SYNC_ESTIMATOR_FIT];
	uint32_t fit_len, fit_pos;
	double err_sq; /* running mean of squared prediction residuals */
	bool have_last;
	int64_t last_edge, last_rev;
	uint32_t consecutive; /* consistent revolutions in a row */
	uint32_t glitch_run, outlier_run;
};

void sync_estimator_config_default(struct sync_estimator_config *cfg, double nominal_rpm)
{
	*cfg = (struct sync_estimator_config){
		.nominal_rpm = nominal_rpm,
		.band = 0.10,
		.tolerance = 0.02,
		.lock_revs = 4,
		.timeout_periods = 1.5,
		.glitch_fraction = 0.75,
		.max_missed = 8,
	};
}

static bool config_valid(const struct sync_estimator_config *c)
{
	return c->nominal_rpm >= 1.0 && c->nominal_rpm <= 100000.0 && c->band > 0.0 && c->band < 1.0 &&
	       c->tolerance > 0.0 && c->tolerance < 0.5 && c->lock_revs >= 1 && c->lock_revs <= SYNC_ESTIMATOR_WINDOW &&
	       c->timeout_periods > 1.0 && c->glitch_fraction > 0.0 && c->glitch_fraction < 1.0 && c->max_missed >= 1;
}

struct sync_estimator *sync_estimator_create(const struct sync_estimator_config *cfg)
{
	if (!config_valid(cfg)) {
		errno = EINVAL;
		return NULL;
	}
	struct sync_estimator *est = calloc(1, sizeof(*est));
	if (!est)
		return NULL;
	est->cfg = *cfg;
	est->nominal_period = llround(60e9 / cfg->nominal_rpm);
	return est;
}

void sync_estimator_destroy(struct sync_estimator *est)
{
	free(est);
}

static void history_clear(struct sync_estimator *est)
{
	est->hist_len = 0;
	est->hist_pos = 0;
	est->fit_len = 0;
	est->fit_pos = 0;
	est->outlier_run = 0;
	est->consecutive = 0;
	est->mean_period = 0;
	est->state.period_ns = 0;
	est->state.fit_err_ns = 0;
	est->state.fit_edges = 0;
	est->state.rpm = 0.0;
	est->state.jitter_ns = 0;
}

static bool unlock(struct sync_estimator *est, enum sync_unlock_reason why)
{
	est->consecutive = 0;
	if (!est->state.locked)
		return false;
	est->state.locked = false;
	est->state.unlock_reason = why;
	est->state.unlocks++;
	return true;
}

void sync_estimator_reset(struct sync_estimator *est)
{
	unlock(est, SYNC_UNLOCK_NONE);
	history_clear(est);
	est->have_last = false;
	est->glitch_run = 0;
	est->state.phase_ns = 0;
	est->state.edge_ns = 0;
	est->state.phase_err_ns = 0;
	est->err_sq = 0.0;
}

static int64_t expected_period(const struct sync_estimator *est)
{
	return est->mean_period ? est->mean_period : est->nominal_period;
}

static void history_add(struct sync_estimator *est, int64_t sample)
{
	est->hist[est->hist_pos] = sample;
	est->hist_pos = (est->hist_pos + 1) % SYNC_ESTIMATOR_WINDOW;
	if (est->hist_len < SYNC_ESTIMATOR_WINDOW)
		est->hist_len++;

	double sum = 0.0, sq = 0.0;
	for (uint32_t i = 0; i < est->hist_len; i++)
		sum += (double)est->hist[i];
	double mean = sum / est->hist_len;
	for (uint32_t i = 0; i < est->hist_len; i++)
		sq += ((double)est->hist[i] - mean) * ((double)est->hist[i] - mean);
	est->mean_period = llround(mean);
	est->state.rpm = 60e9 / mean;
	est->state.jitter_ns = llround(sqrt(sq / est->hist_len));
}

/* Starts over from edge t: the pulses so far say nothing about what comes. */
static bool reseed(struct sync_estimator *est, int64_t t, enum sync_unlock_reason why)
{
	bool changed = unlock(est, why);
	history_clear(est);
	est->glitch_run = 0;
	est->last_edge = t;
	est->last_rev = 0;
	est->state.phase_ns = t;
	est->state.edge_ns = t;
	return changed;
}

static bool update_lock(struct sync_estimator *est)
{
	const struct sync_estimator_config *c = &est->cfg;
	bool in_band = fabs(est->state.rpm - c->nominal_rpm) <= c->band * c->nominal_rpm;
	if (est->state.locked && !in_band)
		return unlock(est, SYNC_UNLOCK_BAND);
	if (!est->state.locked && in_band && est->consecutive >= c->lock_revs) {
		est->state.locked = true;
		est->state.locks++;
		return true;
	}
	return false;
}

/* Adds one revolution's period; consistent ones extend the run towards lock.
 * Out of lock an inconsistent period starts a new run from itself, so a
 * rotor spinning up is tracked rather than averaged. */
static void take_sample(struct sync_estimator *est, int64_t sample, bool after_gap)
{
	int64_t mean = est->mean_period;
	bool consistent = est->hist_len == 0 || fabs((double)(sample - mean)) <= est->cfg.tolerance * (double)mean;
	if (after_gap || !consistent) {
		if (!est->state.locked)
			history_clear(est);
		est->consecutive = after_gap ? 0 : 1;
	} else {
		est->consecutive++;
	}
	history_add(est, sample);
}

/* The least-squares line through the fit's edges, x = revolutions and
 * y = ns relative to the latest edge (so the sums keep their precision):
 * returns where it puts the latest revolution start, fills its slope and
 * the variance of its prediction for the next revolution start. */
static double fit_line(const struct sync_estimator *est, double *slope, double *next_var)
{
	double n = est->fit_len, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
	for (uint32_t i = 0; i < est->fit_len; i++) {
		double x = (double)(est->fit[i].rev - est->last_rev);
		double y = (double)(est->fit[i].t - est->last_edge);
		sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y;
	}
	double dxx = sxx - sx * sx / n, dxy = sxy - sx * sy / n, dyy = syy - sy * sy / n;
	*slope = dxy / dxx;
	double resid = fmax(dyy - *slope * dxy, 0.0), xm = sx / n;
	double var = n > 2 ? resid / (n - 2) : 0.0;
	*next_var = var * (1.0 / n + (1.0 - xm) * (1.0 - xm) / dxx);
	return (sy - *slope * sx) / n;
}

/* Adds the latest accepted edge to the fit (after the previous one, which
 * starts a fit anew), or with outlier only moves the phase to it, and
 * refits period and phase. */
static void fit_add(struct sync_estimator *est, int64_t prev_rev, int64_t prev_t, bool outlier)
{
	if (est->fit_len == 0) {
		est->fit[0].rev = prev_rev;
		est->fit[0].t = prev_t;
		est->fit_len = est->fit_pos = 1;
		outlier = false;
	}
	if (!outlier) {
		est->fit[est->fit_pos].rev = est->last_rev;
		est->fit[est->fit_pos].t = est->last_edge;
		est->fit_pos = (est->fit_pos + 1) % SYNC_ESTIMATOR_FIT;
		if (est->fit_len < SYNC_ESTIMATOR_FIT)
			est->fit_len++;
	}
	double slope, next_var;
	double at = fit_line(est, &slope, &next_var);
	est->state.period_ns = llround(slope);
	est->state.phase_ns = est->last_edge + llround(at);
	est->state.fit_err_ns = llround(sqrt(next_var));
	est->state.fit_edges = est->fit_len;
}

/* Judges edge t, k revolutions after the last, against the prediction
 * (once the fit has enough edges to predict at all) and keeps the RMS of
 * the residuals. An edge off by more than the tolerance is an outlier,
 * kept out of the fit: a glitch late in a revolution passes the glitch
 * test, and one such edge would pull a fit of 64 off by milliseconds. A
 * run of outliers means the fit, not the edges, is off (a speed ramp the
 * line lags): it starts over. Returns whether t is an outlier. */
static bool judge_residual(struct sync_estimator *est, int64_t t, long k)
{
	if (est->fit_len < 4)
		return false;
	double e = (double)(t - est->state.phase_ns - k * est->state.period_ns);
	if (fabs(e) > est->cfg.tolerance * (double)est->state.period_ns) {
		if (++est->outlier_run < OUTLIER_RUN_REFIT)
			return true;
		est->fit_len = est->fit_pos = 0;
		est->outlier_run = 0;
		return false;
	}
	est->outlier_run = 0;
	est->err_sq = est->err_sq ? est->err_sq + (e * e - est->err_sq) / SYNC_ESTIMATOR_FIT : e * e;
	est->state.phase_err_ns = llround(sqrt(est->err_sq));
	return false;
}

/* Too soon after the last accepted edge to be the next. Out of lock the
 * yardstick is never longer than the nominal period: a rotor spinning up
 * after a reseed on a slow revolution would otherwise see every other
 * edge as a glitch and settle on twice the period, never to lock. */
static bool is_glitch(const struct sync_estimator *est, int64_t dt)
{
	int64_t ref = expected_period(est);
	if (!est->state.locked && ref > est->nominal_period)
		ref = est->nominal_period;
	bool judged = est->hist_len > 0; /* the first period has nothing to compare to */
	return dt <= 0 || (judged && (double)dt < est->cfg.glitch_fraction * (double)ref);
}

bool sync_estimator_feed(struct sync_estimator *est, int64_t t)
{
	est->state.edges++;
	if (!est->have_last) {
		est->have_last = true;
		return reseed(est, t, SYNC_UNLOCK_NONE);
	}
	int64_t dt = t - est->last_edge, prev_t = est->last_edge, prev_rev = est->last_rev;
	double ratio = (double)dt / (double)expected_period(est);
	if (is_glitch(est, dt)) {
		est->state.glitches++;
		if (++est->glitch_run >= GLITCH_RUN_RESEED)
			return reseed(est, t, SYNC_UNLOCK_UNSTABLE);
		return false;
	}
	long k = est->hist_len > 0 && ratio >= 1.5 ? lround(ratio) : 1;
	if (k > (long)est->cfg.max_missed + 1)
		return reseed(est, t, SYNC_UNLOCK_TIMEOUT); /* a stall, not missed pulses */
	est->glitch_run = 0;
	bool outlier = judge_residual(est, t, k);
	est->last_edge = t;
	est->last_rev += k;
	est->state.edge_ns = t;
	est->state.missed += (uint64_t)(k - 1);
	take_sample(est, dt / k, k > 1);
	fit_add(est, prev_rev, prev_t, outlier);
	return update_lock(est);
}

int64_t sync_estimator_deadline(const struct sync_estimator *est)
{
	if (!est->have_last)
		return INT64_MAX;
	return est->last_edge + llround(est->cfg.timeout_periods * (double)expected_period(est));
}

bool sync_estimator_check(struct sync_estimator *est, int64_t now)
{
	if (now <= sync_estimator_deadline(est))
		return false;
	return unlock(est, SYNC_UNLOCK_TIMEOUT);
}

bool sync_estimator_settled(const struct sync_estimator *est, int64_t max_err_ns)
{
	const struct sync_state *st = &est->state;
	return st->fit_edges >= SYNC_ESTIMATOR_FIT ||
	       (st->fit_edges >= SYNC_ESTIMATOR_SETTLE_EDGES && st->fit_err_ns <= max_err_ns);
}

int64_t sync_estimator_next_index(const struct sync_estimator *est)
{
	if (!est->state.period_ns)
		return 0;
	return est->state.phase_ns + est->state.period_ns;
}

int64_t sync_estimator_index_after(const struct sync_estimator *est, int64_t t)
{
	int64_t p = est->state.period_ns;
	if (!p)
		return 0;
	if (t <= est->state.phase_ns)
		return est->state.phase_ns;
	int64_t n = (t - est->state.phase_ns + p - 1) / p;
	return est->state.phase_ns + n * p;
}

const struct sync_state *sync_estimator_state(const struct sync_estimator *est)
{
	return &est->state;
}
