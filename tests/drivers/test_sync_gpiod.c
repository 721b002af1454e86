/* The gpiod sync source's libgpiod 1 backend (sync_gpiod.c) without a GPIO
 * chip: its edge reader runs on a pipe fed with kernel-format GPIO uAPI v1
 * event records (struct gpioevent_data), so libgpiod's own record parsing
 * runs as on a real line. Built only with that backend; the clock picker
 * and sync_gpiod_create()'s failures are test_sync_gpiod_common.c's. */
#include <errno.h>
#include <fcntl.h>
#include <linux/gpio.h>
#include <math.h>
#include <poll.h>
#include <stdint.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "log.h"
#include "sync.h"
#include "sync_estimator.h"
#include "sync_gpiod_priv.h"

#define NSEC 1000000000LL
#define RPM 730.0
#define PERIOD_NS ((int64_t)(60.0 * NSEC / RPM)) /* 82191780 */

static int64_t clock_ns(clockid_t id)
{
	struct timespec ts;
	clock_gettime(id, &ts);
	return (int64_t)ts.tv_sec * NSEC + ts.tv_nsec;
}

static void put(int fd, uint64_t ts, uint32_t id)
{
	struct gpioevent_data ev = { .timestamp = ts, .id = id };
	CHECK_EQ(write(fd, &ev, sizeof(ev)), sizeof(ev));
}

static void put_rising(int fd, int64_t ts)
{
	put(fd, (uint64_t)ts, GPIOEVENT_EVENT_RISING_EDGE);
}

static bool readable(int fd)
{
	struct pollfd pfd = { .fd = fd, .events = POLLIN };
	int r = poll(&pfd, 1, 0);
	CHECK(r >= 0);
	return r == 1 && (pfd.revents & POLLIN);
}

/* A source reading p[0]; the test writes records into p[1]. */
static struct sync_source *pipe_source(int p[2])
{
	CHECK_EQ(pipe2(p, O_CLOEXEC), 0);
	struct sync_source *s = sync_gpiod_from_fd(p[0], "test pipe");
	CHECK(s);
	CHECK_EQ(sync_get_fd(s), p[0]);
	CHECK(fcntl(p[0], F_GETFL) & O_NONBLOCK);
	return s;
}

static void pipe_source_destroy(struct sync_source *s, int p[2])
{
	sync_destroy(s);
	close(p[0]);
	if (p[1] >= 0)
		close(p[1]);
}

static void test_batch(void)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	int64_t ts[32], t0 = clock_ns(CLOCK_MONOTONIC) - 10 * PERIOD_NS;
	CHECK(!readable(p[0]));
	CHECK_EQ(sync_read_edges(s, ts, 32), 0); /* nothing pending: no block */
	for (int i = 0; i < 5; i++)
		put_rising(p[1], t0 + i * PERIOD_NS);
	CHECK(readable(sync_get_fd(s)));
	CHECK_EQ(sync_read_edges(s, ts, 32), 5); /* one read() */
	for (int i = 0; i < 5; i++)
		CHECK_EQ(ts[i], t0 + i * PERIOD_NS);
	CHECK(!readable(sync_get_fd(s)));
	CHECK_EQ(sync_gpiod_clock(s), SYNC_GPIOD_CLOCK_MONOTONIC);
	CHECK_EQ(sync_read_edges(s, ts, 32), 0);
	pipe_source_destroy(s, p);
}

static void test_more_than_max(void)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	int64_t ts[64], t0 = clock_ns(CLOCK_MONOTONIC) - 40 * PERIOD_NS;
	for (int i = 0; i < 30; i++) /* more than libgpiod's 16 a read */
		put_rising(p[1], t0 + i * PERIOD_NS);
	CHECK_EQ(sync_read_edges(s, ts, 4), 4);
	CHECK(readable(p[0])); /* the rest waits */
	CHECK_EQ(sync_read_edges(s, ts + 4, 20), 20);
	CHECK_EQ(sync_read_edges(s, ts + 24, 40), 6);
	for (int i = 0; i < 30; i++)
		CHECK_EQ(ts[i], t0 + i * PERIOD_NS);
	CHECK(!readable(p[0]));
	CHECK_EQ(sync_read_edges(s, ts, 64), 0);
	pipe_source_destroy(s, p);
}

static void test_falling_ignored(void)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	int64_t ts[8], t0 = clock_ns(CLOCK_MONOTONIC) - 10 * PERIOD_NS;
	put_rising(p[1], t0);
	put(p[1], (uint64_t)(t0 + 1000), GPIOEVENT_EVENT_FALLING_EDGE);
	put(p[1], (uint64_t)(t0 + 2000), GPIOEVENT_EVENT_FALLING_EDGE);
	put_rising(p[1], t0 + PERIOD_NS);
	put_rising(p[1], t0 + 2 * PERIOD_NS);
	/* Falling edges don't fill max: it reads on for the second rising. */
	CHECK_EQ(sync_read_edges(s, ts, 2), 2);
	CHECK_EQ(ts[0], t0);
	CHECK_EQ(ts[1], t0 + PERIOD_NS);
	CHECK_EQ(sync_read_edges(s, ts, 8), 1);
	CHECK_EQ(ts[0], t0 + 2 * PERIOD_NS);
	put(p[1], (uint64_t)(t0 + 3 * PERIOD_NS), GPIOEVENT_EVENT_FALLING_EDGE);
	CHECK_EQ(sync_read_edges(s, ts, 8), 0);
	CHECK(!readable(p[0]));
	pipe_source_destroy(s, p);
}

/* A short record, garbage timestamps, then EOF: errors, never a crash, and
 * edges read before an error are not lost. */
static void test_bad_input(void)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	int64_t ts[8], now = clock_ns(CLOCK_MONOTONIC);
	CHECK_EQ(write(p[1], "\1\2\3\4\5\6\7\10", 8), 8);
	CHECK_EQ(sync_read_edges(s, ts, 8), -EIO);
	put_rising(p[1], now - 3 * PERIOD_NS);
	put(p[1], UINT64_MAX, GPIOEVENT_EVENT_RISING_EDGE); /* no time at all */
	CHECK_EQ(sync_read_edges(s, ts, 8), 1);
	CHECK_EQ(ts[0], now - 3 * PERIOD_NS);
	CHECK_EQ(sync_read_edges(s, ts, 8), -EBADMSG); /* the error, next */
	put_rising(p[1], now - 4 * PERIOD_NS);         /* before the last edge */
	CHECK_EQ(sync_read_edges(s, ts, 8), -EBADMSG);
	put_rising(p[1], now + 10 * NSEC); /* ahead of now */
	CHECK_EQ(sync_read_edges(s, ts, 8), -EBADMSG);
	put(p[1], (uint64_t)-1000, GPIOEVENT_EVENT_RISING_EDGE);
	CHECK_EQ(sync_read_edges(s, ts, 8), -EBADMSG);
	put_rising(p[1], now - 2 * PERIOD_NS); /* good again */
	CHECK_EQ(sync_read_edges(s, ts, 8), 1);
	CHECK_EQ(ts[0], now - 2 * PERIOD_NS);
	/* EOF: pending records first, then the hang-up, every time. */
	put_rising(p[1], now - PERIOD_NS);
	close(p[1]);
	p[1] = -1;
	CHECK_EQ(sync_read_edges(s, ts, 8), 1);
	CHECK_EQ(sync_read_edges(s, ts, 8), -ENODEV);
	CHECK_EQ(sync_read_edges(s, ts, 8), -ENODEV);
	CHECK_EQ(sync_gpiod_clock(s), SYNC_GPIOD_CLOCK_MONOTONIC);
	pipe_source_destroy(s, p);
}

static void test_realtime(void)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	int64_t ts[8];
	int64_t mono = clock_ns(CLOCK_MONOTONIC), real = clock_ns(CLOCK_REALTIME);
	for (int i = 5; i > 0; i--)
		put_rising(p[1], real - i * PERIOD_NS);
	CHECK_EQ(sync_read_edges(s, ts, 8), 5);
	CHECK_EQ(sync_gpiod_clock(s), SYNC_GPIOD_CLOCK_REALTIME);
	for (int i = 0; i < 5; i++) {
		int64_t want = mono - (5 - i) * PERIOD_NS;
		CHECK_MSG(llabs(ts[i] - want) < 1000000, "edge %d off by %lld ns", i, (long long)(ts[i] - want));
		if (i)
			CHECK_EQ(ts[i] - ts[i - 1], PERIOD_NS);
	}
	/* Settled: a MONOTONIC-looking stamp is now garbage, not a switch. */
	put_rising(p[1], clock_ns(CLOCK_MONOTONIC));
	CHECK_EQ(sync_read_edges(s, ts, 8), -EBADMSG);
	pipe_source_destroy(s, p);
}

/* A burst of a second's edges at 730 rpm, stamped with clock, read in
 * batches of 8: the estimator locks at 730 rpm. */
static void check_lock_730(clockid_t clock)
{
	int p[2];
	struct sync_source *s = pipe_source(p);
	struct sync_estimator_config cfg;
	sync_estimator_config_default(&cfg, RPM);
	struct sync_estimator *est = sync_estimator_create(&cfg);
	CHECK(est);
	int64_t t0 = clock_ns(clock) - 13 * PERIOD_NS;
	for (int i = 0; i < 12; i++)
		put_rising(p[1], t0 + i * PERIOD_NS);
	int64_t ts[8];
	int n, total = 0;
	while ((n = sync_read_edges(s, ts, 8)) > 0) {
		for (int i = 0; i < n; i++)
			sync_estimator_feed(est, ts[i]);
		total += n;
	}
	CHECK_EQ(n, 0);
	CHECK_EQ(total, 12);
	const struct sync_state *st = sync_estimator_state(est);
	CHECK(st->locked);
	/* REALTIME edges move by the offset between the clocks, read once a
	 * batch: a few ns apart from batch to batch. */
	int64_t slack = clock == CLOCK_MONOTONIC ? 0 : 2000;
	CHECK_MSG(llabs(st->period_ns - PERIOD_NS) <= slack, "period %lld", (long long)st->period_ns);
	CHECK_MSG(fabs(st->rpm - RPM) < 0.001, "rpm %f", st->rpm);
	CHECK_EQ(st->glitches, 0);
	CHECK_EQ(st->missed, 0);
	sync_estimator_destroy(est);
	pipe_source_destroy(s, p);
}

static void test_estimator(void)
{
	check_lock_730(CLOCK_MONOTONIC);
	check_lock_730(CLOCK_REALTIME);
}

int main(void)
{
	int fds = count_fds();
	test_batch();
	test_more_than_max();
	test_falling_ignored();
	test_bad_input();
	test_realtime();
	test_estimator();
	CHECK_EQ(count_fds(), fds);
	return check_done();
}
