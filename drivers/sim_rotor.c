/* The simulated rotor.
 *
 * The rotor's motion is kept as a piecewise description from which both the
 * true angle and the true revolution starts are derived: for now a single
 * segment of constant speed starting at creation. Faults (jitter, drift,
 * missed or extra pulses, stall) belong in two places, which is why they are
 * kept apart here: speed changes alter the motion (more segments), while
 * pulse faults only alter what the index sensor reports, never the true
 * revolution starts the projector model and the tests compare against. */
#include "sim_rotor.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "log.h"

struct sim_rotor {
	double rpm;
	int64_t t0;        /* a revolution start (angle 0) */
	int64_t period_ns; /* whole nanoseconds, so index times are exact */
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
	r->rpm = rpm;
	r->period_ns = llround(60e9 / rpm);
	r->t0 = now_ns();
	return r;
}

void sim_rotor_destroy(struct sim_rotor *r)
{
	free(r);
}

int64_t sim_rotor_period_ns(const struct sim_rotor *r)
{
	return r->period_ns;
}

/* Revolution number in progress at t (0 from creation; negative before). */
int64_t sim_rotor_revolution(const struct sim_rotor *r, int64_t t)
{
	int64_t d = t - r->t0;
	int64_t n = d / r->period_ns;
	if (d < 0 && d % r->period_ns)
		n--; /* floor, not truncation */
	return n;
}

int64_t sim_rotor_index_time(const struct sim_rotor *r, int64_t n)
{
	return r->t0 + n * r->period_ns;
}

int64_t sim_rotor_next_index(const struct sim_rotor *r, int64_t t)
{
	int64_t n = sim_rotor_revolution(r, t);
	int64_t start = sim_rotor_index_time(r, n);
	return start == t ? t : start + r->period_ns;
}

double sim_rotor_angle(const struct sim_rotor *r, int64_t t)
{
	int64_t n = sim_rotor_revolution(r, t);
	int64_t into = t - sim_rotor_index_time(r, n);
	return 2.0 * M_PI * (double)into / (double)r->period_ns;
}
