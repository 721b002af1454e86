/* Fault specs, and the faulty index pulse seen through the sync estimator.
 * Time is the rotor's simulated clock, driven here, so minutes of
 * revolutions take a fraction of a second and every run is the same. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "sim_rig.h"
#include "sim_rotor.h"
#include "sync.h"
#include "sync_estimator.h"

#define RPM 730.0
#define N_SLICES 396
#define MS 1000000LL

static void test_parse_good(void)
{
	struct sim_faults f;
	CHECK_EQ(sim_faults_parse("", &f), 0);
	CHECK(f.jitter == 0 && f.nevents == 0);
	CHECK_EQ(sim_faults_parse("none", &f), 0);
	CHECK_EQ(sim_faults_parse("jitter=0.001,missed=0.01,extra=0.02,drift=-200ppm/s,seed=42,"
				  "stall=3.0+2.0,speed=5.0:800@1.0",
				  &f),
		 0);
	CHECK(f.jitter == 0.001 && f.missed == 0.01 && f.extra == 0.02 && f.drift_ppm_s == -200.0);
	CHECK_EQ(f.seed, 42);
	CHECK_EQ(f.nevents, 2);
	CHECK(f.events[0].kind == SIM_FAULT_STALL && f.events[0].at == 3.0 && f.events[0].dur == 0.0);
	CHECK(f.events[0].restart == 2.0 && f.events[0].spinup == 1.0);
	CHECK(f.events[1].kind == SIM_FAULT_SPEED && f.events[1].at == 5.0);
	CHECK(f.events[1].rpm == 800.0 && f.events[1].dur == 1.0);
	CHECK_EQ(sim_faults_parse("stall=1.5/0.25+3/0.5,stall=10,seed=18446744073709551615", &f), 0);
	CHECK(f.events[0].dur == 0.25 && f.events[0].restart == 3.0 && f.events[0].spinup == 0.5);
	CHECK(f.events[1].at == 10.0 && f.events[1].restart < 0);
	CHECK(f.seed == UINT64_MAX);
	CHECK_EQ(sim_faults_parse("drift=1e2ppm/s,jitter=.01", &f), 0);
	CHECK(f.drift_ppm_s == 100.0 && f.jitter == 0.01);
	CHECK_EQ(sim_faults_parse("unplug=1.5+0.5,unplug=4", &f), 0);
	CHECK(f.nevents == 2 && f.events[0].kind == SIM_FAULT_UNPLUG && f.events[0].at == 1.5);
	CHECK(f.events[0].restart == 0.5 && f.events[1].at == 4.0 && f.events[1].restart < 0);
}

static void test_parse_bad(void)
{
	static const char *const bad[] = {
		"jitter",
		"jitter=",
		"jitter=x",
		"jitter=0.2",
		"jitter=-0.001",
		"jitter=0.001,",
		",jitter=0.001",
		"jitter=0.001,,missed=0.1",
		"jitter=0.001,jitter=0.002",
		"missed=1.5",
		"extra=nan",
		"extra=inf",
		"jitter=0x1p-10",
		"jitter= 0.001",
		"drift=200",
		"drift=200ppm",
		"drift=200ppm/sx",
		"drift=1e9ppm/s",
		"seed=-1",
		"seed=1.5",
		"seed=99999999999999999999",
		"speed=5.0:800",
		"speed=5.0@1.0",
		"speed=-1:800@1",
		"speed=5:0@1",
		"speed=5:800@1:2",
		"stall=",
		"stall=3+",
		"stall=3/",
		"stall=3+2/",
		"stall=3+2+1",
		"stall=-3",
		"stall=3x",
		"JITTER=0.001",
		"wobble=1",
		"none,jitter=0.001",
		"unplug=",
		"unplug=1+",
		"unplug=1/2",
		"unplug=-1",
		"unplug=1+2+3",
		"stall=1,stall=2,stall=3,stall=4,stall=5,stall=6,stall=7,stall=8,stall=9",
	};
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		struct sim_faults f;
		f.jitter = 1.0;
		CHECK_MSG(sim_faults_parse(bad[i], &f) == -EINVAL, "accepted \"%s\"", bad[i]);
		CHECK(f.jitter == 0.0 && f.nevents == 0); /* nothing half-parsed */
	}
	struct sim_faults f;
	CHECK_EQ(sim_faults_parse(NULL, &f), -EINVAL);
}

struct run {
	struct sim_rotor *rotor;
	struct sync_source *src;
	struct sync_estimator *est;
	int64_t now;
};

static void run_init(struct run *r, const char *spec)
{
	pulse_rig_open(spec, RPM, &r->rotor, &r->src, &r->est, &r->now);
}

static void run_finish(struct run *r)
{
	pulse_rig_close(r->rotor, r->src, r->est);
}

/* Advances the clock by 10 ms and reads the edges due into ts. */
static int run_step(struct run *r, int64_t *ts, int max)
{
	r->now += 10 * MS;
	sim_rotor_set_now(r->rotor, r->now);
	int n = sync_read_edges(r->src, ts, max);
	CHECK(n >= 0 && n < max);
	return n;
}

static void test_jitter_statistics(void)
{
	struct run r;
	run_init(&r, "jitter=0.001,seed=42");
	double p = (double)sim_rotor_period_ns(r.rotor), sq = 0;
	int64_t prev = 0, ts[8];
	int periods = 0;
	while (periods < 4000) {
		int n = run_step(&r, ts, 8);
		for (int i = 0; i < n; i++, prev = ts[i - 1]) {
			int64_t true_idx = sim_rotor_index_time(r.rotor, sim_rotor_revolution(r.rotor, ts[i] + 5 * MS));
			CHECK(llabs(ts[i] - true_idx) < 6 * MS / 10); /* 10 sigma */
			if (prev) {
				sq += ((double)(ts[i] - prev) - p) * ((double)(ts[i] - prev) - p);
				periods++;
			}
			sync_estimator_feed(r.est, ts[i]);
		}
	}
	double rms = sqrt(sq / periods) / p;
	printf("jitter=0.001: measured period RMS %.5f of a period over %d periods\n", rms, periods);
	CHECK(fabs(rms - 0.001) < 0.00005);
	const struct sync_state *s = sync_estimator_state(r.est);
	CHECK(s->locked);
	CHECK(fabs((double)s->jitter_ns / p - 0.001) < 0.0005); /* 16 periods: a rough figure */
	run_finish(&r);
}

static void test_missed_and_extra(void)
{
	struct run r;
	run_init(&r, "missed=0.02,extra=0.02,seed=7");
	int64_t ts[8];
	const struct sync_state *s = sync_estimator_state(r.est);
	while (sim_rotor_revolution(r.rotor, r.now) < 3000) {
		int n = run_step(&r, ts, 8);
		for (int i = 0; i < n; i++)
			sync_estimator_feed(r.est, ts[i]);
		sync_estimator_check(r.est, r.now);
	}
	struct sync_sim_stats st;
	sync_sim_get_stats(r.src, &st);
	printf("missed %llu (estimator %llu), extra %llu (estimator glitches %llu), unlocks %llu\n",
	       (unsigned long long)st.missed, (unsigned long long)s->missed, (unsigned long long)st.extra,
	       (unsigned long long)s->glitches, (unsigned long long)s->unlocks);
	CHECK(st.missed > 30 && st.extra > 30);
	/* A glitch in a revolution whose pulse was lost can pass for it. */
	CHECK(llabs((long long)(s->missed - st.missed)) <= 3);
	CHECK(llabs((long long)(s->glitches - st.extra)) <= 3);
	/* Counted as modelled, one revolution ahead of what was read. */
	uint64_t modelled = st.true_edges - st.missed + st.extra;
	CHECK(st.sent <= modelled && st.sent + 2 >= modelled);
	CHECK(s->locked);
	/* Glitches late in a revolution are accepted as the edge, the real
	 * edge then rejected: kept out of the fit, the period stays right. */
	CHECK(llabs(s->period_ns - sim_rotor_period_ns(r.rotor)) < 2000);
	run_finish(&r);
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* The estimator's prediction of each next revolution start, against the
 * true one, in slices of 396: what the projector would be told. */
static void test_fit_prediction(void)
{
	struct run r;
	run_init(&r, "jitter=0.001,seed=1");
	double slice = (double)sim_rotor_period_ns(r.rotor) / N_SLICES, sq = 0, sq_last = 0, fit_err = 0;
	enum { SAMPLES = 3000 };
	static double err[SAMPLES];
	int m = 0, seen = 0;
	int64_t ts[8];
	while (m < SAMPLES) {
		int n = run_step(&r, ts, 8);
		for (int i = 0; i < n; i++)
			sync_estimator_feed(r.est, ts[i]);
		if (!n || ++seen < 2 * SYNC_ESTIMATOR_FIT)
			continue;
		const struct sync_state *s = sync_estimator_state(r.est);
		int64_t true_next = sim_rotor_next_index(r.rotor, ts[n - 1] + 5 * MS);
		int64_t pred = sync_estimator_index_after(r.est, true_next - s->period_ns / 2);
		int64_t naive = ts[n - 1] + s->period_ns; /* the last edge as phase */
		err[m] = fabs((double)(pred - true_next)) / slice;
		sq += err[m] * err[m];
		sq_last += ((double)(naive - true_next) / slice) * ((double)(naive - true_next) / slice);
		fit_err += (double)s->fit_err_ns / slice;
		m++;
	}
	qsort(err, SAMPLES, sizeof(err[0]), cmp_double);
	double rms = sqrt(sq / SAMPLES);
	printf("predicted index error, slices of %d: rms %.3f p99 %.3f max %.3f (fit's own estimate %.3f; "
	       "last edge as phase: rms %.3f); phase_err %.1f us\n",
	       N_SLICES, rms, err[SAMPLES * 99 / 100], err[SAMPLES - 1], fit_err / SAMPLES, sqrt(sq_last / SAMPLES),
	       (double)sync_estimator_state(r.est)->phase_err_ns / 1e3);
	CHECK(rms < 0.1);
	CHECK(err[SAMPLES * 99 / 100] < 0.25);
	CHECK(fabs(fit_err / SAMPLES / rms - 1.0) < 0.3); /* the fit knows its error */
	run_finish(&r);
}

int main(void)
{
	int fds = count_fds();
	test_parse_good();
	test_parse_bad();
	test_jitter_statistics();
	test_missed_and_extra();
	test_fit_prediction();
	CHECK_EQ(count_fds(), fds);
	return check_done();
}
