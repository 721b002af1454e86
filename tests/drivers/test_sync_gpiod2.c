/* The gpiod sync source's libgpiod 2 backend (drivers/sync_gpiod2.c) against
 * a fake of the libgpiod 2 calls it makes (fake_gpiod2.c), on any machine:
 * what it asks libgpiod for, how it fails, and recorded edge sequences
 * replayed through the request's fd (a real pipe, kernel v2 records) and
 * on through the sync estimator: steady rotation, jitter, events the kernel
 * dropped (gaps in the sequence numbers), glitches, a stall, events for
 * another line and records that are no kernel's.
 *
 * Not run against a real libgpiod 2, gpio-sim or a GPIO chip. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "fake_gpiod2_ctl.h"
#include "gpiod_create.h"
#include "sync.h"
#include "sync_estimator.h"
#include "sync_gpiod_priv.h"

#define NSEC 1000000000LL
#define RPM 730.0
#define PERIOD_NS ((int64_t)(60.0 * NSEC / RPM)) /* 82191780 */
#define CHIP "/dev/gpiochip5"
#define LINE 17
#define OTHER_LINE 3
#define NAMED_LINE 11
#define MAX_TAPE 512

static const char *const line_names[] = { "", "", "", "", "", "", "", "", "", "", "", "ROTOR_INDEX", NULL };

/* A recorded edge sequence: times relative to its start, numbered as the
 * kernel numbers them (the request's seqno and each line's line_seqno). */
struct tape {
	struct fake_gpiod2_edge e[MAX_TAPE];
	size_t n;
	int64_t t;         /* the time of the latest event */
	uint32_t seq;      /* the request's latest seqno */
	uint32_t line_seq; /* LINE's latest line_seqno */
	uint32_t other_seq;
	int64_t base; /* where it is placed: the time of 0 */
};

/* An event dt after the one before, on LINE. */
static void tape_event(struct tape *tp, int64_t dt, enum gpiod_edge_event_type type)
{
	CHECK(tp->n < MAX_TAPE);
	tp->t += dt;
	tp->e[tp->n++] = (struct fake_gpiod2_edge){
		.ts_ns = (uint64_t)tp->t,
		.type = type,
		.offset = LINE,
		.line_seqno = ++tp->line_seq,
		.seqno = ++tp->seq
	};
}

static void tape_rising(struct tape *tp, int64_t dt)
{
	tape_event(tp, dt, GPIOD_EDGE_EVENT_RISING_EDGE);
}

/* n index edges a period apart, the first a period after the last event. */
static void tape_steady(struct tape *tp, int n)
{
	for (int i = 0; i < n; i++)
		tape_rising(tp, PERIOD_NS);
}

/* k events the kernel dropped, its buffer full: numbered, never read. */
static void tape_drop(struct tape *tp, uint32_t k)
{
	tp->seq += k;
	tp->line_seq += k;
}

/* An event for OTHER_LINE, dt after the one before. */
static void tape_other(struct tape *tp, int64_t dt)
{
	CHECK(tp->n < MAX_TAPE);
	tp->t += dt;
	tp->e[tp->n++] = (struct fake_gpiod2_edge){
		.ts_ns = (uint64_t)tp->t,
		.type = GPIOD_EDGE_EVENT_RISING_EDGE,
		.offset = OTHER_LINE,
		.line_seqno = ++tp->other_seq,
		.seqno = ++tp->seq
	};
}

static int64_t mono_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * NSEC + ts.tv_nsec;
}

/* Places the whole tape in the past: its last event half a period ago. */
static void tape_place(struct tape *tp)
{
	tp->base = mono_ns() - tp->t - PERIOD_NS / 2;
	CHECK(tp->base > 0);
}

static int64_t tape_time(const struct tape *tp, size_t i)
{
	return tp->base + (int64_t)tp->e[i].ts_ns;
}

/* Writes events [from, to) into the request, at their placed times. */
static void tape_push(const struct tape *tp, size_t from, size_t to)
{
	for (size_t i = from; i < to; i++) {
		struct fake_gpiod2_edge e = tp->e[i];
		e.ts_ns = (uint64_t)tape_time(tp, i);
		fake_gpiod2_push(&e, 1);
	}
}

/* A source on the fake chip's LINE, and an estimator for it. */
struct rig {
	struct sync_source *s;
	struct sync_estimator *est;
	const struct sync_state *st;
	struct tape tape;
};

static void fake_setup(void)
{
	fake_gpiod2_setup(CHIP, "pinctrl-test", 32, line_names);
}

static struct rig *rig_open(void)
{
	struct rig *r = calloc(1, sizeof(*r));
	CHECK(r);
	fake_setup();
	struct sync_gpiod_config cfg = { .chip = CHIP, .line = "17" };
	r->s = sync_gpiod_create(&cfg);
	CHECK(r->s);
	struct sync_estimator_config ec;
	sync_estimator_config_default(&ec, RPM);
	r->est = sync_estimator_create(&ec);
	CHECK(r->est);
	r->st = sync_estimator_state(r->est);
	return r;
}

static void rig_close(struct rig *r)
{
	sync_destroy(r->s);
	sync_estimator_destroy(r->est);
	free(r);
	CHECK_EQ(fake_gpiod2_live(), 0);
	CHECK_EQ(fake_gpiod2_seen()->fd, -1);
}

/* Reads every pending edge, batch at a time, into the estimator; returns
 * how many. */
static int rig_drain(struct rig *r, int batch)
{
	int64_t ts[64];
	int n, total = 0;
	CHECK(batch <= 64);
	while ((n = sync_read_edges(r->s, ts, batch)) > 0) {
		for (int i = 0; i < n; i++)
			sync_estimator_feed(r->est, ts[i]);
		total += n;
	}
	CHECK_EQ(n, 0);
	return total;
}

/* The tape placed, pushed whole and read. */
static int rig_play(struct rig *r, int batch)
{
	tape_place(&r->tape);
	tape_push(&r->tape, 0, r->tape.n);
	return rig_drain(r, batch);
}

static struct sync_gpiod_stats rig_stats(struct rig *r)
{
	struct sync_gpiod_stats st;
	sync_gpiod_get_stats(r->s, &st);
	return st;
}

static bool readable(int fd)
{
	struct pollfd pfd = { .fd = fd, .events = POLLIN };
	int r = poll(&pfd, 1, 0);
	CHECK(r >= 0);
	return r == 1 && (pfd.revents & POLLIN);
}

/* ---- the request ---- */

static void check_request(const char *chip, const char *line, bool active_low, unsigned int offset)
{
	fake_setup();
	struct sync_gpiod_config cfg = { .active_low = active_low };
	snprintf(cfg.chip, sizeof(cfg.chip), "%s", chip);
	snprintf(cfg.line, sizeof(cfg.line), "%s", line);
	struct sync_source *s = sync_gpiod_create(&cfg);
	CHECK_MSG(s, "chip %s line %s", chip, line);
	const struct fake_gpiod2_seen *seen = fake_gpiod2_seen();
	CHECK_EQ(seen->requests, 1);
	CHECK_EQ(seen->num_offsets, 1);
	CHECK_EQ(seen->offset, offset);
	CHECK_EQ(seen->direction, GPIOD_LINE_DIRECTION_INPUT);
	/* As v1: rising edges, which active low makes the physical falling. */
	CHECK_EQ(seen->edge, GPIOD_LINE_EDGE_RISING);
	CHECK_EQ(seen->active_low, active_low);
	CHECK_EQ(seen->clock, GPIOD_LINE_CLOCK_MONOTONIC);
	CHECK_EQ(seen->debounce_us, 0);
	CHECK(strcmp(seen->consumer, "spindled") == 0);
	CHECK_EQ(sync_get_fd(s), seen->fd);
	CHECK(fcntl(seen->fd, F_GETFL) & O_NONBLOCK);
	/* The clock is the one asked for, known before any edge. */
	CHECK_EQ(sync_gpiod_clock(s), SYNC_GPIOD_CLOCK_MONOTONIC);
	int64_t ts[4];
	CHECK_EQ(sync_read_edges(s, ts, 4), 0); /* nothing pending: no block */
	sync_destroy(s);
	CHECK_EQ(fake_gpiod2_live(), 0);
}

static void test_request(void)
{
	check_request(CHIP, "17", false, LINE);
	check_request(CHIP, "17", true, LINE);
	check_request("5", "17", false, LINE);         /* a chip number */
	check_request("gpiochip5", "0", false, 0);     /* a chip name */
	check_request(CHIP, "ROTOR_INDEX", false, 11); /* a line name */
	check_request(CHIP, "31", false, 31);
}

static void test_create_fails(void)
{
	char log[2048];
	fake_setup();
	struct sync_gpiod_config cfg = { .chip = "/dev/gpiochip7", .line = "17" };
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), ENOENT); /* no such chip */
	CHECK_MSG(strstr(log, "/dev/gpiochip7") && strstr(log, "17"), "log: %s", log);
	strcpy(cfg.chip, "no-such-label"); /* nor a label of any */
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), ENOENT);
	strcpy(cfg.chip, CHIP);
	strcpy(cfg.line, "32"); /* one past the last line */
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), ENOENT);
	CHECK_MSG(strstr(log, "no line at that offset"), "log: %s", log);
	strcpy(cfg.line, "NO_SUCH_LINE");
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), ENOENT);
	CHECK_MSG(strstr(log, "no line of that name"), "log: %s", log);
	strcpy(cfg.line, "");
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), EINVAL);
	CHECK_EQ(fake_gpiod2_live(), 0);

	/* Another consumer holds the line: EBUSY, and it says so. */
	strcpy(cfg.line, "17");
	struct sync_source *held = sync_gpiod_create(&cfg);
	CHECK(held);
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), EBUSY);
	CHECK_MSG(strstr(log, "another consumer"), "log: %s", log);
	sync_destroy(held);
	fake_gpiod2_fail_requests(EPERM);
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), EPERM);
	CHECK_EQ(fake_gpiod2_live(), 0);
}

/* ---- edges ---- */

static void test_more_than_max(void)
{
	struct rig *r = rig_open();
	tape_steady(&r->tape, 30); /* more than the 16 of the event buffer */
	tape_place(&r->tape);
	tape_push(&r->tape, 0, 30);
	int64_t ts[64];
	CHECK_EQ(sync_read_edges(r->s, ts, 4), 4);
	CHECK(readable(sync_get_fd(r->s))); /* the rest waits */
	CHECK_EQ(sync_read_edges(r->s, ts + 4, 20), 20);
	CHECK_EQ(sync_read_edges(r->s, ts + 24, 40), 6);
	for (int i = 0; i < 30; i++)
		CHECK_EQ(ts[i], tape_time(&r->tape, (size_t)i)); /* the kernel's stamps, as they are */
	CHECK(!readable(sync_get_fd(r->s)));
	CHECK_EQ(sync_read_edges(r->s, ts, 64), 0);
	rig_close(r);
}

/* What every clean replay ends in, as test_sync_gpiod.c's check_lock_730
 * asks of the v1 backend: locked at 730 rpm, nothing rejected or missed. */
static void check_clean_lock(struct rig *r)
{
	CHECK(r->st->locked);
	CHECK_MSG(r->st->period_ns == PERIOD_NS, "period %lld", (long long)r->st->period_ns);
	CHECK_MSG(fabs(r->st->rpm - RPM) < 0.001, "rpm %f", r->st->rpm);
	CHECK_EQ(r->st->glitches, 0);
	CHECK_EQ(r->st->missed, 0);
}

static void test_steady(void)
{
	struct rig *r = rig_open();
	tape_steady(&r->tape, 100);
	CHECK_EQ(rig_play(r, 8), 100);
	check_clean_lock(r);
	CHECK_EQ(r->st->edges, 100);
	struct sync_gpiod_stats st = rig_stats(r);
	CHECK_EQ(st.edges, 100);
	CHECK_EQ(st.lost, 0);
	CHECK_EQ(st.other_line, 0);
	rig_close(r);
}

/* Edges off their true times by up to +-100 us (uniform, a fixed seed):
 * still locked, the fitted period within a microsecond. */
static void test_jitter(void)
{
	struct rig *r = rig_open();
	uint32_t seed = 12345;
	int64_t prev_off = 0;
	for (int i = 0; i < 200; i++) {
		seed = seed * 1664525u + 1013904223u;
		int64_t off = (int64_t)(seed >> 8) % 200001 - 100000;
		tape_rising(&r->tape, PERIOD_NS + off - prev_off);
		prev_off = off;
	}
	CHECK_EQ(rig_play(r, 8), 200);
	CHECK(r->st->locked);
	CHECK_MSG(llabs(r->st->period_ns - PERIOD_NS) < 1000, "period %lld", (long long)r->st->period_ns);
	CHECK_MSG(fabs(r->st->rpm - RPM) < 1.0, "rpm %f", r->st->rpm);
	CHECK_MSG(r->st->jitter_ns > 20000 && r->st->jitter_ns < 200000, "jitter %lld", (long long)r->st->jitter_ns);
	CHECK(r->st->phase_err_ns > 0);
	CHECK_EQ(r->st->glitches, 0);
	CHECK_EQ(r->st->missed, 0);
	CHECK_EQ(rig_stats(r).lost, 0);
	rig_close(r);
}

/* The kernel's buffer overflowed three times (1, 3 and 1 index events
 * dropped): the sequence numbers count 5 lost, and the estimator, from
 * the gaps in time, 5 missed pulses; still locked. */
static void test_seqno_gaps(void)
{
	struct rig *r = rig_open();
	tape_steady(&r->tape, 30);
	tape_drop(&r->tape, 1);
	tape_rising(&r->tape, 2 * PERIOD_NS);
	tape_steady(&r->tape, 20);
	tape_drop(&r->tape, 3);
	tape_rising(&r->tape, 4 * PERIOD_NS);
	tape_steady(&r->tape, 20);
	tape_drop(&r->tape, 1);
	tape_rising(&r->tape, 2 * PERIOD_NS);
	tape_steady(&r->tape, 10);
	CHECK_EQ(rig_play(r, 8), 83);
	struct sync_gpiod_stats st = rig_stats(r);
	CHECK_EQ(st.lost, 5);
	CHECK_EQ(r->st->missed, st.lost);
	CHECK(r->st->locked);
	CHECK_EQ(r->st->period_ns, PERIOD_NS);
	CHECK_EQ(r->st->glitches, 0);
	CHECK_EQ(r->st->locks, 1);
	rig_close(r);
}

/* A glitch a third of a revolution after an index edge, and a bounce 20 us
 * after another: both read, both rejected by the estimator. Falling edges
 * (not asked for; a kernel sends none) are skipped and use up their
 * numbers without counting as lost. */
static void test_glitch(void)
{
	struct rig *r = rig_open();
	tape_steady(&r->tape, 20);
	tape_rising(&r->tape, PERIOD_NS / 3);
	tape_rising(&r->tape, PERIOD_NS - PERIOD_NS / 3);
	tape_steady(&r->tape, 10);
	tape_rising(&r->tape, 20000);
	tape_event(&r->tape, 1000000, GPIOD_EDGE_EVENT_FALLING_EDGE);
	tape_rising(&r->tape, PERIOD_NS - 1020000);
	tape_steady(&r->tape, 10);
	CHECK_EQ(rig_play(r, 8), 44);
	CHECK_EQ(r->st->glitches, 2);
	CHECK_EQ(r->st->missed, 0);
	CHECK_EQ(rig_stats(r).lost, 0);
	CHECK(r->st->locked);
	CHECK_EQ(r->st->period_ns, PERIOD_NS);
	CHECK_EQ(r->st->unlocks, 0);
	rig_close(r);
}

/* The rotor stops for 20 revolutions: the timeout unlocks (the daemon
 * blanks: it lights only while locked); when it turns again the gap is a
 * stall, not missed pulses, nothing was lost, and it locks again after its
 * consistent revolutions. */
static void test_stall(void)
{
	struct rig *r = rig_open();
	tape_steady(&r->tape, 20);
	size_t before = r->tape.n;
	tape_rising(&r->tape, 20 * PERIOD_NS);
	tape_steady(&r->tape, 10);
	tape_place(&r->tape);
	tape_push(&r->tape, 0, before);
	CHECK_EQ(rig_drain(r, 8), 20);
	check_clean_lock(r);
	int64_t last = r->st->edge_ns;
	CHECK_EQ(last, tape_time(&r->tape, before - 1));
	CHECK(!sync_estimator_check(r->est, last + PERIOD_NS * 14 / 10)); /* within 1.5 periods */
	CHECK(r->st->locked);
	CHECK(sync_estimator_check(r->est, last + 2 * PERIOD_NS));
	CHECK(!r->st->locked);
	CHECK_EQ(r->st->unlock_reason, SYNC_UNLOCK_TIMEOUT);
	tape_push(&r->tape, before, r->tape.n);
	CHECK_EQ(rig_drain(r, 8), 11);
	CHECK(r->st->locked);
	CHECK_EQ(r->st->locks, 2);
	CHECK_EQ(r->st->unlocks, 1);
	CHECK_EQ(r->st->missed, 0);
	CHECK_EQ(rig_stats(r).lost, 0);
	rig_close(r);
}

/* Events for another line (no kernel sends them on a one-line request):
 * ignored and counted, before the estimator (they would be glitches) and
 * before the sequence check (their line_seqno is their line's). */
static void test_other_line(void)
{
	struct rig *r = rig_open();
	for (int i = 0; i < 40; i++) {
		if (i % 4 == 1) {
			tape_other(&r->tape, PERIOD_NS / 10);
			tape_rising(&r->tape, PERIOD_NS - PERIOD_NS / 10);
		} else {
			tape_rising(&r->tape, PERIOD_NS);
		}
	}
	CHECK_EQ(rig_play(r, 8), 40);
	struct sync_gpiod_stats st = rig_stats(r);
	CHECK_EQ(st.other_line, 10);
	CHECK_EQ(st.lost, 0);
	CHECK_EQ(st.edges, 40);
	check_clean_lock(r);
	rig_close(r);
}

/* ---- records that are no kernel's ---- */

/* A short record, then EOF: an error, never a crash; edges read before an
 * error are returned first; a hang-up is -ENODEV every time. */
static void test_short_and_hangup(void)
{
	struct rig *r = rig_open();
	int64_t ts[8];
	fake_gpiod2_push_bytes("\1\2\3\4\5\6\7\10", 8);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -EIO);
	tape_steady(&r->tape, 2);
	CHECK_EQ(rig_play(r, 8), 2);
	tape_steady(&r->tape, 1);
	tape_place(&r->tape);
	tape_push(&r->tape, 2, 3);
	fake_gpiod2_hangup();
	CHECK_EQ(sync_read_edges(r->s, ts, 8), 1);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -ENODEV);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -ENODEV);
	rig_close(r);
}

/* Timestamps an edge cannot have, and sequence numbers that go back. */
static void test_bad_records(void)
{
	struct rig *r = rig_open();
	struct tape *tp = &r->tape;
	int64_t ts[8];
	tape_steady(tp, 3);
	tape_place(tp);
	tape_push(tp, 0, 2);
	struct fake_gpiod2_edge e = tp->e[1];
	e.ts_ns = (uint64_t)tape_time(tp, 1) + 1; /* the number again */
	fake_gpiod2_push(&e, 1);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), 2);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -EBADMSG); /* the error, next */
	tape_push(tp, 2, 3);                              /* good again */
	CHECK_EQ(sync_read_edges(r->s, ts, 8), 1);
	CHECK_EQ(ts[0], tape_time(tp, 2));
	e = tp->e[2];
	e.line_seqno = e.seqno = 4;
	e.ts_ns = UINT64_MAX; /* no time at all */
	fake_gpiod2_push(&e, 1);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -EBADMSG);
	e.line_seqno = e.seqno = 5;
	e.ts_ns = (uint64_t)(mono_ns() + 10 * NSEC); /* ahead of now */
	fake_gpiod2_push(&e, 1);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -EBADMSG);
	e.line_seqno = e.seqno = 6;
	e.ts_ns = (uint64_t)tape_time(tp, 1); /* before the last edge */
	fake_gpiod2_push(&e, 1);
	CHECK_EQ(sync_read_edges(r->s, ts, 8), -EBADMSG);
	CHECK_EQ(rig_stats(r).lost, 0);
	CHECK_EQ(rig_stats(r).edges, 3);
	rig_close(r);
}

/* Numbers are the uAPI's 32 bits: past 2^32 - 1 comes 0, not a gap of
 * 2^32 - 1; and events the kernel dropped before the first read count
 * too. */
static void test_seqno_wrap(void)
{
	struct rig *r = rig_open();
	struct tape *tp = &r->tape;
	tape_drop(tp, 2);
	tape_steady(tp, 1); /* 3: 2 lost before it */
	tape_drop(tp, 0x7ffffffbu);
	tape_steady(tp, 1); /* 0x7fffffff */
	tape_drop(tp, 0x7ffffffeu);
	tape_steady(tp, 4); /* 0xfffffffe (the largest step taken), 0xffffffff, 0, 1 */
	CHECK_EQ(tp->line_seq, 1);
	CHECK_EQ(rig_play(r, 8), 6);
	CHECK_EQ(rig_stats(r).lost, 2 + 0x7ffffffbull + 0x7ffffffeull);
	rig_close(r);
}

int main(void)
{
	int fds = count_fds();
	test_request();
	test_create_fails();
	test_more_than_max();
	test_steady();
	test_jitter();
	test_seqno_gaps();
	test_glitch();
	test_stall();
	test_other_line();
	test_short_and_hangup();
	test_bad_records();
	test_seqno_wrap();
	CHECK_EQ(fake_gpiod2_live(), 0);
	CHECK_EQ(count_fds(), fds);
	return check_done();
}
