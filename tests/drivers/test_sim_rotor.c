/* The simulated rotor's motion under speed changes, stalls, restarts and
 * drift: pure arithmetic on the rotor's schedule, no waiting. */
#include <errno.h>
#include <math.h>

#include "check.h"
#include "sim_rotor.h"

#define RPM 730.0
#define SEC 1000000000LL

/* The half-turn starts of revolution n (starting at index time t): the
 * first is the revolution start itself, the second where the rotor is half
 * a turn on; next_half_turn() finds each and says which it is. */
static void check_half_turns(const struct sim_rotor *r, int64_t n, int64_t t)
{
	bool second = true;
	CHECK_EQ(sim_rotor_half_turn_time(r, 2 * n), t);
	CHECK_EQ(sim_rotor_next_half_turn(r, t, &second), t);
	CHECK(!second);
	CHECK_EQ(sim_rotor_next_half_turn(r, t - 1, &second), t);
	CHECK(!second);
	int64_t h = sim_rotor_half_turn_time(r, 2 * n + 1);
	if (h == SIM_ROTOR_NEVER) {
		CHECK_EQ(sim_rotor_next_half_turn(r, t + 1, NULL), SIM_ROTOR_NEVER);
		return;
	}
	CHECK(h > t);
	CHECK_EQ(sim_rotor_next_half_turn(r, t + 1, &second), h);
	CHECK(second);
	CHECK_EQ(sim_rotor_next_half_turn(r, h, &second), h);
	CHECK(second);
	CHECK_EQ(sim_rotor_next_half_turn(r, h - 1, NULL), h);
	CHECK_EQ(sim_rotor_revolution(r, h), n);
	double a = sim_rotor_angle(r, h);
	CHECK_MSG(a >= M_PI && a < M_PI + 1e-6, "angle %g at half-turn %lld", a, (long long)(2 * n + 1));
	CHECK(sim_rotor_angle(r, h - 1) < M_PI);
	int64_t next = sim_rotor_index_time(r, n + 1);
	CHECK(next == SIM_ROTOR_NEVER || next > h);
	CHECK_EQ(sim_rotor_next_half_turn(r, h + 1, &second), next);
	CHECK(next == SIM_ROTOR_NEVER || !second);
}

/* revolution() and index_time() agree around every index in [from, to];
 * so do the half-turn starts. */
static void check_consistent(const struct sim_rotor *r, int64_t from, int64_t to)
{
	int64_t n = sim_rotor_revolution(r, from);
	for (int64_t t = sim_rotor_index_time(r, n); t <= to && t != SIM_ROTOR_NEVER;
	     t = sim_rotor_index_time(r, ++n)) {
		CHECK_EQ(sim_rotor_revolution(r, t), n);
		CHECK_EQ(sim_rotor_revolution(r, t - 1), n - 1);
		CHECK_EQ(sim_rotor_next_index(r, t), t);
		CHECK_EQ(sim_rotor_next_index(r, t - 1), t);
		double a = sim_rotor_angle(r, t);
		CHECK_MSG(a < 1e-6 || a > 2 * M_PI - 1e-6, "angle %g at index %lld", a, (long long)n);
		check_half_turns(r, n, t);
	}
}

/* The angle never jumps: sampled every 1 ms, it moves by at most what the
 * fastest speed allows. */
static void check_continuous(const struct sim_rotor *r, int64_t from, int64_t to, double max_rpm)
{
	double prev = sim_rotor_angle(r, from), max_step = 2 * M_PI * max_rpm / 60.0 / 1000.0 * 1.001;
	for (int64_t t = from + SEC / 1000; t <= to; t += SEC / 1000) {
		double a = sim_rotor_angle(r, t), d = a - prev;
		if (d < -M_PI)
			d += 2 * M_PI;
		CHECK_MSG(d >= -1e-9 && d <= max_step, "step %g at %lld", d, (long long)(t - from));
		prev = a;
	}
}

static void test_steady_exact(void)
{
	struct sim_rotor *r = sim_rotor_create(RPM);
	CHECK(r);
	int64_t t0 = sim_rotor_start(r), p = sim_rotor_period_ns(r);
	CHECK_EQ(p, llround(60e9 / RPM));
	for (int64_t n = -3; n < 100000; n += 997) {
		CHECK_EQ(sim_rotor_index_time(r, n), t0 + n * p);
		/* The middle of each: the first whole nanosecond at p / 2. */
		CHECK_EQ(sim_rotor_half_turn_time(r, 2 * n + 1), t0 + n * p + (p + 1) / 2);
	}
	check_consistent(r, t0 - 2 * p, t0 + 20 * p);
	CHECK(fabs(sim_rotor_rpm_at(r, t0 + SEC) - 60e9 / (double)p) < 1e-9);
	CHECK_EQ(sim_rotor_band_cross(r, t0, RPM * 0.9, RPM * 1.1, false), SIM_ROTOR_NEVER);
	sim_rotor_destroy(r);
}

static void test_ramp(void)
{
	struct sim_rotor *r = sim_rotor_create(RPM);
	CHECK(r);
	int64_t t0 = sim_rotor_start(r);
	CHECK_EQ(sim_rotor_set_speed(r, t0 + 5 * SEC, 800.0, SEC), 0);
	CHECK(fabs(sim_rotor_rpm_at(r, t0 + 5 * SEC) - RPM) < 1e-4); /* the period is whole ns */
	CHECK(fabs(sim_rotor_rpm_at(r, t0 + 5 * SEC + SEC / 2) - (RPM + 800.0) / 2) < 1e-4);
	CHECK(fabs(sim_rotor_rpm_at(r, t0 + 7 * SEC) - 800.0) < 1e-6);
	/* Before the ramp: untouched, exact. */
	CHECK_EQ(sim_rotor_index_time(r, 60), t0 + 60 * sim_rotor_period_ns(r));
	check_consistent(r, t0, t0 + 10 * SEC);
	check_continuous(r, t0 + 4 * SEC, t0 + 8 * SEC, 800.0);
	/* After it: revolutions 60e9 / 800 apart, to the nanosecond. */
	int64_t n = sim_rotor_revolution(r, t0 + 8 * SEC);
	int64_t d = sim_rotor_index_time(r, n + 1) - sim_rotor_index_time(r, n);
	CHECK(llabs(d - 75000000) <= 1);
	/* Leaving a 730 +/- 5 % band: when the ramp passes 766.5 rpm. */
	int64_t out = sim_rotor_band_cross(r, t0, RPM * 0.95, RPM * 1.05, false);
	CHECK(llabs(out - (t0 + 5 * SEC + (int64_t)(36.5 / 70.0 * 1e9))) < 1000);
	CHECK_EQ(sim_rotor_band_cross(r, out, RPM * 0.95, RPM * 1.05, true), SIM_ROTOR_NEVER);
	CHECK_EQ(sim_rotor_set_speed(r, t0 + SEC, -1.0, 0), -EINVAL);
	CHECK_EQ(sim_rotor_set_speed(r, t0 - 1, 100.0, 0), -EINVAL);
	sim_rotor_destroy(r);
}

static void test_stall_restart(void)
{
	struct sim_rotor *r = sim_rotor_create(RPM);
	CHECK(r);
	int64_t t0 = sim_rotor_start(r), p = sim_rotor_period_ns(r);
	int64_t stop = sim_rotor_index_time(r, 36) + p / 3; /* a third into a revolution */
	CHECK_EQ(sim_rotor_set_speed(r, stop, 0.0, 0), 0);
	int64_t last = sim_rotor_index_time(r, sim_rotor_revolution(r, stop));
	CHECK(last <= stop && stop - last < p);
	CHECK_EQ(sim_rotor_next_index(r, last + 1), SIM_ROTOR_NEVER); /* stopped for good */
	CHECK_EQ(sim_rotor_rpm_at(r, stop + 1), 0);
	double a = sim_rotor_angle(r, stop);
	CHECK(fabs(a - 2 * M_PI / 3) < 1e-6);
	CHECK(fabs(sim_rotor_angle(r, stop + 100 * SEC) - a) < 1e-12);
	CHECK_EQ(sim_rotor_band_cross(r, t0, RPM * 0.9, RPM * 1.1, false), stop);
	CHECK_EQ(sim_rotor_band_cross(r, stop, RPM * 0.9, RPM * 1.1, true), SIM_ROTOR_NEVER);

	/* Restart 2 s later, back to nominal over 1 s: the first index comes
	 * when the remaining two thirds of a turn are done, spacing ends at p. */
	int64_t go = stop + 2 * SEC;
	CHECK_EQ(sim_rotor_set_speed(r, go, RPM, SEC), 0);
	int64_t next = sim_rotor_next_index(r, last + 1);
	/* (2/3 rev) = 1/2 a t^2, a = (RPM / 60 rev/s) per s */
	double t_first = sqrt(2.0 * (2.0 / 3.0) / (RPM / 60.0));
	CHECK(llabs(next - (go + (int64_t)(t_first * 1e9))) < 1000);
	CHECK_EQ(sim_rotor_revolution(r, next), sim_rotor_revolution(r, last) + 1);
	check_consistent(r, t0, t0 + 10 * SEC);
	check_continuous(r, stop - SEC, go + 2 * SEC, RPM);
	int64_t in = sim_rotor_band_cross(r, stop, RPM * 0.9, RPM * 1.1, true);
	CHECK(llabs(in - (go + SEC * 9 / 10)) < 1000);
	int64_t n = sim_rotor_revolution(r, go + 3 * SEC);
	CHECK(llabs(sim_rotor_index_time(r, n + 1) - sim_rotor_index_time(r, n) - p) <= 1);

	/* A stall that slows down over 0.5 s instead. */
	CHECK_EQ(sim_rotor_set_speed(r, t0 + 20 * SEC, 0.0, SEC / 2), 0);
	int64_t slow = sim_rotor_band_cross(r, t0 + 19 * SEC, RPM * 0.9, RPM * 1.1, false);
	CHECK(llabs(slow - (t0 + 20 * SEC + SEC / 20)) < 1000);
	check_consistent(r, t0 + 19 * SEC, t0 + 22 * SEC);
	check_continuous(r, t0 + 19 * SEC, t0 + 22 * SEC, RPM);
	CHECK_EQ(sim_rotor_next_index(r, t0 + 21 * SEC), SIM_ROTOR_NEVER);
	sim_rotor_destroy(r);
}

static void test_drift(void)
{
	struct sim_rotor *r = sim_rotor_create(RPM);
	CHECK(r);
	int64_t t0 = sim_rotor_start(r);
	sim_rotor_set_drift(r, 200.0);
	CHECK(fabs(sim_rotor_rpm_at(r, t0 + 10 * SEC) / sim_rotor_rpm_at(r, t0) - 1.002) < 1e-9);
	check_consistent(r, t0, t0 + 20 * SEC);
	/* 10 % faster after 500 s: out of band. */
	int64_t out = sim_rotor_band_cross(r, t0, 0, 60e9 / (double)sim_rotor_period_ns(r) * 1.1, false);
	CHECK(llabs(out - (t0 + 500 * SEC)) < SEC / 1000);
	sim_rotor_destroy(r);

	/* Drifting down stops rather than turning backwards. */
	r = sim_rotor_create(RPM);
	CHECK(r);
	t0 = sim_rotor_start(r);
	sim_rotor_set_drift(r, -10000.0); /* 1 % a second: stopped after 100 s */
	CHECK_EQ(sim_rotor_rpm_at(r, t0 + 101 * SEC), 0);
	CHECK(sim_rotor_rpm_at(r, t0 + 99 * SEC) > 0);
	CHECK_EQ(sim_rotor_next_index(r, t0 + 101 * SEC), SIM_ROTOR_NEVER);
	check_consistent(r, t0 + 90 * SEC, t0 + 101 * SEC);
	sim_rotor_destroy(r);
}

int main(void)
{
	test_steady_exact();
	test_ramp();
	test_stall_restart();
	test_drift();
	return check_done();
}
