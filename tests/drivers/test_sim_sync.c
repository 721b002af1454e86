/* The simulated rotor and its index pulse source, in real time (short: about
 * half a second at 1800 rpm). Tolerances are generous for loaded machines;
 * the edge times themselves are exact because they are the rotor's true
 * index times, whenever they are read. */
#include <math.h>
#include <poll.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "log.h"
#include "sim_rotor.h"
#include "sync.h"
#include "sync_estimator.h"

#define RPM 1800.0

static void test_rotor(void)
{
	struct sim_rotor *r = sim_rotor_create(RPM);
	CHECK(r);
	int64_t p = sim_rotor_period_ns(r);
	CHECK_EQ(p, 33333333);
	int64_t now = now_ns();
	int64_t idx = sim_rotor_next_index(r, now);
	CHECK(idx >= now && idx - now <= p);
	CHECK_EQ(sim_rotor_next_index(r, idx), idx);
	CHECK_EQ(sim_rotor_next_index(r, idx + 1), idx + p);
	int64_t n = sim_rotor_revolution(r, idx);
	CHECK_EQ(sim_rotor_index_time(r, n), idx);
	CHECK_EQ(sim_rotor_revolution(r, idx - 1), n - 1);
	CHECK(fabs(sim_rotor_angle(r, idx)) < 1e-9);
	CHECK(fabs(sim_rotor_angle(r, idx + p / 4) - M_PI / 2) < 1e-6);
	CHECK(fabs(sim_rotor_angle(r, idx - p / 4) - 3 * M_PI / 2) < 1e-6);
	sim_rotor_destroy(r);
	CHECK(!sim_rotor_create(0.0));
	sim_rotor_destroy(NULL);
}

static int wait_readable(int fd, int timeout_ms)
{
	struct pollfd pfd = { .fd = fd, .events = POLLIN };
	int r = poll(&pfd, 1, timeout_ms);
	CHECK(r >= 0);
	return r;
}

static void test_edges_realtime(void)
{
	struct sim_rotor *rotor = sim_rotor_create(RPM);
	CHECK(rotor);
	struct sync_source *src = sync_sim_create(rotor);
	CHECK(src);
	struct sync_estimator_config cfg;
	sync_estimator_config_default(&cfg, RPM);
	struct sync_estimator *est = sync_estimator_create(&cfg);
	CHECK(est);
	int64_t p = sim_rotor_period_ns(rotor);
	int64_t start = now_ns(), prev = 0;
	int total = 0;
	while (now_ns() - start < 400000000LL) {
		CHECK(wait_readable(sync_get_fd(src), 1000) == 1);
		int64_t ts[8];
		int n = sync_read_edges(src, ts, 8);
		CHECK(n >= 0);
		int64_t now = now_ns();
		for (int i = 0; i < n; i++) {
			CHECK_EQ(sim_rotor_next_index(rotor, ts[i]), ts[i]); /* a true index time */
			CHECK(ts[i] <= now && now - ts[i] < 250000000LL);    /* delivered soon */
			if (prev)
				CHECK_EQ(ts[i] - prev, p); /* none lost, none doubled */
			prev = ts[i];
			sync_estimator_feed(est, ts[i]);
		}
		total += n;
	}
	CHECK(total >= 6); /* 12 expected */
	CHECK(sync_estimator_state(est)->locked);
	CHECK_EQ(sync_estimator_state(est)->period_ns, p);
	sync_estimator_destroy(est);
	sync_destroy(src);
	sim_rotor_destroy(rotor);
}

static void test_batched_read(void)
{
	struct sim_rotor *rotor = sim_rotor_create(RPM);
	CHECK(rotor);
	struct sync_source *src = sync_sim_create(rotor);
	CHECK(src);
	int64_t p = sim_rotor_period_ns(rotor);
	struct timespec nap = { 0, 150000000 }; /* several edges pile up */
	nanosleep(&nap, NULL);
	int64_t ts[64];
	CHECK_EQ(sync_read_edges(src, ts, 2), 2);
	CHECK_EQ(ts[1] - ts[0], p);
	CHECK(wait_readable(sync_get_fd(src), 0) == 1); /* more left: still readable */
	int n = sync_read_edges(src, ts + 2, 62);
	CHECK(n >= 2);
	for (int i = 1; i < n + 2; i++)
		CHECK_EQ(ts[i] - ts[i - 1], p);
	CHECK_EQ(sync_read_edges(src, ts, 64), 0); /* drained */
	sync_destroy(src);
	sim_rotor_destroy(rotor);
}

int main(void)
{
	int fds = count_fds();
	test_rotor();
	test_edges_realtime();
	test_batched_read();
	CHECK_EQ(count_fds(), fds);
	return 0;
}
