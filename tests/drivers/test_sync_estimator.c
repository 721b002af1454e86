/* The sync estimator on synthetic edge trains: no real time involved. */
#include <math.h>

#include "check.h"
#include "sync_estimator.h"

#define RPM 1800.0
#define P 33333333LL /* ns per revolution at 1800 rpm */
#define T0 1000000000LL

static struct sync_estimator *make(void)
{
	struct sync_estimator_config cfg;
	sync_estimator_config_default(&cfg, RPM);
	struct sync_estimator *est = sync_estimator_create(&cfg);
	CHECK(est);
	return est;
}

/* Feeds n edges a period apart after *t (advancing *t); returns lock changes. */
static int feed_regular(struct sync_estimator *est, int64_t *t, int n, int64_t period)
{
	int changes = 0;
	for (int i = 0; i < n; i++) {
		*t += period;
		changes += sync_estimator_feed(est, *t);
	}
	return changes;
}

/* An estimator locked by 7 regular edges from T0; *t is the last edge. */
static struct sync_estimator *make_locked(int64_t *t)
{
	struct sync_estimator *est = make();
	*t = T0;
	sync_estimator_feed(est, *t);
	feed_regular(est, t, 6, P);
	CHECK(sync_estimator_state(est)->locked);
	return est;
}

static void test_lock_after_consistent_revolutions(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	int64_t t = T0;
	CHECK(!sync_estimator_feed(est, t));
	CHECK_EQ(sync_estimator_next_index(est), 0);
	CHECK_EQ(feed_regular(est, &t, 3, P), 0);
	CHECK(!s->locked);
	CHECK_EQ(feed_regular(est, &t, 1, P), 1); /* the 4th consistent revolution */
	CHECK(s->locked);
	CHECK_EQ(s->period_ns, P);
	CHECK(fabs(s->rpm - RPM) < 0.01);
	CHECK_EQ(s->jitter_ns, 0);
	CHECK_EQ(s->phase_ns, t);
	CHECK_EQ(sync_estimator_next_index(est), t + P);
	CHECK_EQ(sync_estimator_index_after(est, t + 1), t + P);
	CHECK_EQ(sync_estimator_index_after(est, t + 2 * P), t + 2 * P);
	CHECK_EQ(s->locks, 1);
	CHECK_EQ(s->edges, 5);
	sync_estimator_destroy(est);
}

static void test_jitter(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	const int64_t d = 100000; /* 0.3 %: within tolerance */
	int64_t t = T0;
	sync_estimator_feed(est, t);
	for (int i = 0; i < 32; i++) {
		t += (i % 2) ? P + d : P - d;
		sync_estimator_feed(est, t);
	}
	CHECK(s->locked);
	CHECK(llabs(s->jitter_ns - d) < d / 50);
	CHECK(llabs(s->period_ns - P) < 2);
	sync_estimator_destroy(est);
}

static void test_glitch_rejected(void)
{
	int64_t t;
	struct sync_estimator *est = make_locked(&t);
	const struct sync_state *s = sync_estimator_state(est);
	CHECK(!sync_estimator_feed(est, t + P / 3));
	CHECK_EQ(s->glitches, 1);
	CHECK_EQ(s->phase_ns, t); /* the glitch moved nothing */
	CHECK_EQ(feed_regular(est, &t, 2, P), 0);
	CHECK(s->locked);
	CHECK_EQ(s->period_ns, P);
	CHECK_EQ(s->missed, 0);
	/* A run of glitches means the pulse train is nonsense: unlock. */
	for (int i = 1; i <= 3; i++)
		sync_estimator_feed(est, t + i * 1000);
	CHECK(!s->locked);
	CHECK_EQ(s->unlock_reason, SYNC_UNLOCK_UNSTABLE);
	sync_estimator_destroy(est);
}

static void test_missed_pulses(void)
{
	int64_t t;
	struct sync_estimator *est = make_locked(&t);
	const struct sync_state *s = sync_estimator_state(est);
	t += 2 * P; /* one pulse missing */
	sync_estimator_feed(est, t);
	CHECK_EQ(s->missed, 1);
	t += 3 * P; /* two more */
	sync_estimator_feed(est, t);
	CHECK_EQ(s->missed, 3);
	CHECK_EQ(s->period_ns, P);
	CHECK_EQ(s->glitches, 0);
	/* A gap far longer is a stall: not counted as missed pulses. */
	t += 40 * P;
	sync_estimator_feed(est, t);
	CHECK_EQ(s->missed, 3);
	CHECK(!s->locked);
	CHECK_EQ(s->period_ns, 0);
	sync_estimator_destroy(est);
}

static void test_unlock_on_timeout(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	CHECK_EQ(sync_estimator_deadline(est), INT64_MAX);
	CHECK(!sync_estimator_check(est, T0));
	int64_t t = T0;
	sync_estimator_feed(est, t);
	feed_regular(est, &t, 5, P);
	CHECK(s->locked);
	CHECK(llabs(sync_estimator_deadline(est) - (t + P * 3 / 2)) <= 1);
	CHECK(!sync_estimator_check(est, t + P * 14 / 10));
	CHECK(s->locked);
	CHECK(sync_estimator_check(est, t + P * 16 / 10));
	CHECK(!s->locked);
	CHECK_EQ(s->unlock_reason, SYNC_UNLOCK_TIMEOUT);
	CHECK_EQ(s->unlocks, 1);
	CHECK(!sync_estimator_check(est, t + P * 2)); /* reported once */
	/* The late pulse arrives (one missed); relock needs 4 good revolutions. */
	t += 2 * P;
	CHECK(!sync_estimator_feed(est, t));
	CHECK_EQ(s->missed, 1);
	CHECK_EQ(feed_regular(est, &t, 3, P), 0);
	CHECK(!s->locked);
	CHECK_EQ(feed_regular(est, &t, 1, P), 1);
	CHECK(s->locked);
	sync_estimator_destroy(est);
}

static void test_unlock_out_of_band(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	int64_t t = T0;
	double period = (double)P;
	sync_estimator_feed(est, t);
	feed_regular(est, &t, 20, P);
	CHECK(s->locked);
	/* Speed up by 0.5 % a revolution: every step is consistent, yet the
	 * speed leaves the band. */
	int revs = 0;
	while (s->locked && revs < 100) {
		period /= 1.005;
		t += llround(period);
		sync_estimator_feed(est, t);
		revs++;
	}
	CHECK(!s->locked);
	CHECK_EQ(s->unlock_reason, SYNC_UNLOCK_BAND);
	CHECK(s->rpm > RPM * 1.09);
	/* Back to nominal: relocks once the recent periods agree again. */
	revs = 0;
	while (!s->locked && revs < 100) {
		t += P;
		sync_estimator_feed(est, t);
		revs++;
	}
	CHECK(s->locked);
	CHECK_EQ(s->locks, 2);
	sync_estimator_destroy(est);
}

static void test_spin_up(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	int64_t t = T0;
	double rpm = 300.0;
	sync_estimator_feed(est, t);
	while (rpm < RPM) {
		rpm *= 1.05;
		if (rpm > RPM)
			rpm = RPM;
		t += llround(60e9 / rpm);
		sync_estimator_feed(est, t);
		if (rpm < RPM * 0.9)
			CHECK(!s->locked);
	}
	CHECK_EQ(s->glitches, 0);
	CHECK_EQ(s->missed, 0);
	feed_regular(est, &t, 4, P);
	CHECK(s->locked);
	sync_estimator_destroy(est);
}

/* Reseeded on a slow revolution while spinning up, the next edges come
 * at under 0.75 of that period: edges, not glitches, or the estimator
 * settles on every other one and never locks. */
static void test_reseed_while_spinning_up(void)
{
	struct sync_estimator *est = make();
	const struct sync_state *s = sync_estimator_state(est);
	int64_t t = T0;
	sync_estimator_feed(est, t);
	t += 2 * P; /* the first period after a restart: slow */
	sync_estimator_feed(est, t);
	feed_regular(est, &t, 8, P);
	CHECK_EQ(s->glitches, 0);
	CHECK(s->locked);
	CHECK(llabs(s->period_ns - P) < 2);
	sync_estimator_destroy(est);
}

static void test_bad_config(void)
{
	struct sync_estimator_config cfg;
	sync_estimator_config_default(&cfg, RPM);
	cfg.timeout_periods = 0.5;
	CHECK(!sync_estimator_create(&cfg));
	sync_estimator_config_default(&cfg, 0.0);
	CHECK(!sync_estimator_create(&cfg));
}

int main(void)
{
	test_lock_after_consistent_revolutions();
	test_jitter();
	test_glitch_rejected();
	test_missed_pulses();
	test_unlock_on_timeout();
	test_unlock_out_of_band();
	test_spin_up();
	test_reseed_while_spinning_up();
	test_bad_config();
	return 0;
}
