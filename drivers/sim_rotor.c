/* The simulated rotor.
 *
 * The motion is a short list of segments, each of constant angular
 * acceleration (a == 0: constant speed), continuous in position and, except
 * where a speed is set "at once", in speed. Position is counted in
 * revolutions since creation, so revolution starts are where it crosses a
 * whole number: closed form within a segment (a square root at most), cheap
 * enough to evaluate per slice. The first segment has an integer period, so
 * that a rotor without faults keeps exact index times t0 + n * period.
 *
 * Faults (see sim_rotor.h) belong in two places, which is why they are kept
 * apart: speed changes alter the motion (more segments), while pulse faults
 * only alter what the index sensor reports (sync_sim.c), never the true
 * revolution starts the projector model and the tests compare against. */
#include "sim_rotor.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "log.h"

struct segment {
	int64_t ts;    /* start time; the first segment also extends backwards */
	double p0;     /* position at ts, revolutions */
	double period; /* ns per revolution when a == 0 (INFINITY: stopped) */
	double w0;     /* speed at ts, revolutions per ns */
	double a;      /* acceleration, revolutions per ns^2 */
};

struct sim_rotor {
	double rpm;
	int64_t t0;        /* a revolution start (angle 0): creation */
	int64_t period_ns; /* nominal, whole nanoseconds */
	double drift_a;    /* acceleration of steady segments from now on */
	bool manual;       /* the clock is simulated */
	int64_t now;
	struct segment *seg;
	size_t nseg, cap;
};

struct sim_rotor *sim_rotor_create(double rpm)
{
	if (!(rpm >= 1.0 && rpm <= 100000.0)) {
		errno = EINVAL;
		return NULL;
	}
	struct sim_rotor *r = calloc(1, sizeof(*r));
	if (!r)
		return NULL;
	r->seg = calloc(4, sizeof(*r->seg));
	if (!r->seg) {
		free(r);
		return NULL;
	}
	r->cap = 4;
	r->nseg = 1;
	r->rpm = rpm;
	r->period_ns = llround(60e9 / rpm);
	r->t0 = now_ns();
	r->seg[0] = (struct segment){ .ts = r->t0, .period = (double)r->period_ns, .w0 = 1.0 / (double)r->period_ns };
	return r;
}

void sim_rotor_destroy(struct sim_rotor *r)
{
	if (!r)
		return;
	free(r->seg);
	free(r);
}

int64_t sim_rotor_now(const struct sim_rotor *r)
{
	return r->manual ? r->now : now_ns();
}

void sim_rotor_set_now(struct sim_rotor *r, int64_t t)
{
	r->manual = true;
	r->now = t;
}

int64_t sim_rotor_start(const struct sim_rotor *r)
{
	return r->t0;
}

int64_t sim_rotor_period_ns(const struct sim_rotor *r)
{
	return r->period_ns;
}

/* The segment in force at t. */
static const struct segment *seg_at(const struct sim_rotor *r, int64_t t)
{
	size_t i = r->nseg - 1;
	while (i > 0 && r->seg[i].ts > t)
		i--;
	return &r->seg[i];
}

static double seg_pos(const struct segment *s, int64_t t)
{
	double dt = (double)(t - s->ts);
	if (s->a == 0.0 || dt < 0.0)
		return s->w0 == 0.0 ? s->p0 : s->p0 + dt / s->period;
	return s->p0 + dt * (s->w0 + 0.5 * s->a * dt);
}

static double seg_speed(const struct segment *s, int64_t t)
{
	double dt = (double)(t - s->ts);
	return dt > 0.0 ? s->w0 + s->a * dt : s->w0;
}

/* Time after s->ts (ns, fractional) at which s reaches position p >= p0. */
static double seg_solve(const struct segment *s, double p)
{
	double dp = p - s->p0;
	if (s->a == 0.0 || dp < 0.0)
		return dp * s->period; /* dp < 0: the first segment, backwards */
	if (dp == 0.0)
		return 0.0;
	/* The stable root of a/2 dt^2 + w0 dt - dp = 0, valid for w0 = 0. */
	return 2.0 * dp / (s->w0 + sqrt(s->w0 * s->w0 + 2.0 * s->a * dp));
}

/* Whether segment i ever reaches position p (within its time span). */
static bool seg_reaches(const struct sim_rotor *r, size_t i, double p)
{
	if (i + 1 < r->nseg)
		return r->seg[i + 1].p0 >= p;
	const struct segment *s = &r->seg[i];
	return s->w0 > 0.0 || s->a > 0.0 || p <= s->p0;
}

/* The first whole nanosecond at which the rotor is at position p. */
static int64_t position_time(const struct sim_rotor *r, double p)
{
	for (size_t i = 0; i < r->nseg; i++) {
		if (!seg_reaches(r, i, p))
			continue;
		double dt = ceil(seg_solve(&r->seg[i], p));
		if (dt > 9e18)
			return SIM_ROTOR_NEVER;
		return r->seg[i].ts + (int64_t)dt;
	}
	return SIM_ROTOR_NEVER;
}

int64_t sim_rotor_index_time(const struct sim_rotor *r, int64_t n)
{
	return position_time(r, (double)n);
}

int64_t sim_rotor_half_turn_time(const struct sim_rotor *r, int64_t h)
{
	/* h / 2 is exact in a double: even h gives index_time(h / 2) to the
	 * nanosecond. */
	return position_time(r, 0.5 * (double)h);
}

int64_t sim_rotor_next_half_turn(const struct sim_rotor *r, int64_t t, bool *second)
{
	/* From the position, then checked against the half-turn times, as
	 * revolution() does. */
	int64_t h = (int64_t)floor(2.0 * seg_pos(seg_at(r, t), t));
	if (sim_rotor_half_turn_time(r, h + 1) <= t)
		h++;
	else if (sim_rotor_half_turn_time(r, h) > t)
		h--;
	int64_t at = sim_rotor_half_turn_time(r, h);
	if (at != t)
		at = sim_rotor_half_turn_time(r, ++h);
	if (second)
		*second = at != SIM_ROTOR_NEVER && (h & 1);
	return at;
}

/* Revolution number at t: from the position, then checked against the
 * index times so the two can never disagree by a rounding. */
int64_t sim_rotor_revolution(const struct sim_rotor *r, int64_t t)
{
	int64_t n = (int64_t)floor(seg_pos(seg_at(r, t), t));
	if (sim_rotor_index_time(r, n + 1) <= t)
		return n + 1;
	if (sim_rotor_index_time(r, n) > t)
		return n - 1;
	return n;
}

int64_t sim_rotor_next_index(const struct sim_rotor *r, int64_t t)
{
	int64_t n = sim_rotor_revolution(r, t);
	int64_t start = sim_rotor_index_time(r, n);
	return start == t ? t : sim_rotor_index_time(r, n + 1);
}

double sim_rotor_angle(const struct sim_rotor *r, int64_t t)
{
	double p = seg_pos(seg_at(r, t), t);
	double a = 2.0 * M_PI * (p - floor(p));
	return a < 2.0 * M_PI ? a : 0.0;
}

double sim_rotor_rpm_at(const struct sim_rotor *r, int64_t t)
{
	return seg_speed(seg_at(r, t), t) * 60e9;
}

static int push(struct sim_rotor *r, struct segment s)
{
	if (r->nseg == r->cap) {
		struct segment *n = realloc(r->seg, 2 * r->cap * sizeof(*n));
		if (!n)
			return -ENOMEM;
		r->seg = n;
		r->cap *= 2;
	}
	r->seg[r->nseg++] = s;
	return 0;
}

/* A constant-speed stretch from ts at speed w, drifting if asked; a drift
 * downwards ends in a stop rather than turning backwards. */
static int push_steady(struct sim_rotor *r, int64_t ts, double p0, double w)
{
	struct segment s = { .ts = ts, .p0 = p0, .w0 = w, .period = w > 0.0 ? 1.0 / w : INFINITY };
	if (w > 0.0)
		s.a = r->drift_a;
	int e = push(r, s);
	if (e < 0 || s.a >= 0.0)
		return e;
	int64_t stop = ts + (int64_t)ceil(-w / s.a);
	return push(r, (struct segment){ .ts = stop, .p0 = seg_pos(&s, stop), .period = INFINITY });
}

int sim_rotor_set_speed(struct sim_rotor *r, int64_t t, double rpm, int64_t dur_ns)
{
	if (!(rpm >= 0.0 && rpm <= 100000.0) || dur_ns < 0 || t < r->t0)
		return -EINVAL;
	const struct segment *s = seg_at(r, t);
	double p = seg_pos(s, t), w = seg_speed(s, t), wt = rpm / 60e9;
	size_t keep = r->nseg;
	while (keep > 0 && r->seg[keep - 1].ts >= t)
		keep--;
	r->nseg = keep;
	if (dur_ns > 0 && wt != w) {
		struct segment ramp = { .ts = t, .p0 = p, .w0 = w, .a = (wt - w) / (double)dur_ns };
		ramp.period = w > 0.0 ? 1.0 / w : INFINITY;
		if (push(r, ramp) < 0)
			return -ENOMEM;
		t += dur_ns;
		p = seg_pos(&ramp, t);
	}
	return push_steady(r, t, p, wt);
}

void sim_rotor_set_drift(struct sim_rotor *r, double ppm_per_s)
{
	r->drift_a = ppm_per_s * 1e-6 / (double)r->period_ns / 1e9;
	/* A new rotor drifts from creation; the first segment keeps its
	 * exact integer period for the way back before creation. */
	if (r->nseg == 1 && r->drift_a != 0.0) {
		r->seg[0].a = r->drift_a;
		if (r->drift_a < 0.0) {
			const struct segment *s = &r->seg[0];
			int64_t stop = s->ts + (int64_t)ceil(-s->w0 / s->a);
			push(r, (struct segment){ .ts = stop, .p0 = seg_pos(s, stop), .period = INFINITY });
		}
	}
}

/* Within s from 'from' on, before 'end': the first time the speed meets
 * the band condition; SIM_ROTOR_NEVER if not in this segment. */
static int64_t seg_band_cross(const struct segment *s, int64_t from, int64_t end, double wl, double wh, bool inside)
{
	double w = seg_speed(s, from);
	if ((w >= wl && w <= wh) == inside)
		return from;
	if (s->a == 0.0)
		return SIM_ROTOR_NEVER;
	double target;
	if (!inside)
		target = s->a > 0.0 ? wh : wl;
	else if ((w < wl && s->a > 0.0) || (w > wh && s->a < 0.0))
		target = w < wl ? wl : wh;
	else
		return SIM_ROTOR_NEVER; /* moving away from the band */
	double dt = ceil((target - s->w0) / s->a) + (inside ? 0.0 : 1.0);
	if (dt > 9e18 || s->ts + (int64_t)dt >= end)
		return SIM_ROTOR_NEVER;
	int64_t when = s->ts + (int64_t)dt;
	return when > from ? when : from;
}

int64_t sim_rotor_band_cross(const struct sim_rotor *r, int64_t t, double lo, double hi, bool inside)
{
	size_t i = (size_t)(seg_at(r, t) - r->seg);
	for (; i < r->nseg; i++) {
		const struct segment *s = &r->seg[i];
		int64_t from = s->ts > t ? s->ts : t;
		int64_t end = i + 1 < r->nseg ? r->seg[i + 1].ts : INT64_MAX;
		int64_t when = seg_band_cross(s, from, end, lo / 60e9, hi / 60e9, inside);
		if (when != SIM_ROTOR_NEVER)
			return when;
	}
	return SIM_ROTOR_NEVER;
}
