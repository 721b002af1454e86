/* The index pulse from a real GPIO line: everything but the libgpiod calls,
 * shared by the libgpiod 1 backend (sync_gpiod.c) and the libgpiod 2 one
 * (sync_gpiod2.c); sync_gpiod_priv.h is the interface between them.
 *
 * Timestamps: every edge carries the kernel's timestamp, taken in the
 * interrupt, so scheduling latency never shows up as jitter. The v2 uAPI
 * stamps with the clock the request asks for, CLOCK_MONOTONIC. Since Linux
 * 5.7 the v1 line event timestamp is CLOCK_MONOTONIC too; before, it was
 * CLOCK_REALTIME. Kernel versions lie (vendor backports), so on v1 the clock
 * is found from the events themselves: a timestamp lies shortly before "now"
 * on the clock that took it, and far from the other one (see
 * sync_gpiod_pick_clock()). REALTIME stamps are moved to MONOTONIC with the
 * offset between the clocks read at each batch, so a clock step (NTP at boot)
 * costs at most the batch read across it.
 *
 * Checks: whatever the clock, an edge's time must lie before now and not
 * before the edge before it. On v2 each event also names its line and
 * carries the line's sequence number: an event for a line not requested is
 * ignored and counted, and a gap in the numbers counts the events the kernel
 * dropped when its buffer was full (the daemon fell behind); the estimator
 * sees the same gap in time and counts the pulses in it as missed.
 *
 * Debounce: none. v1 has none; v2 asks for a debounce period of 0, so that
 * no default ever delays the edges. Rejecting glitches is the estimator's
 * job (sync_estimator.h), and a noisy sensor wants a Schmitt trigger
 * (docs/hardware.md). */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "log.h"
#include "sync.h"
#include "sync_gpiod_priv.h"

#define NSEC 1000000000LL
/* Clocks further apart than this are told apart by any edge younger. */
#define CLOCKS_FAR_APART_NS (3600 * NSEC)
/* Only an edge younger than this settles the clock. */
#define SURE_MAX_AGE_NS (60 * NSEC)
/* How far a REALTIME edge, moved to MONOTONIC, may land after now: the two
 * clocks are not read at the same instant. */
#define CONVERT_SLACK_NS 1000000LL
/* Events for a line not requested are logged at most this often. */
#define OTHER_LINE_LOG_NS (10 * NSEC)

struct sync_gpiod {
	struct sync_source base;
	int fd;
	struct sync_gpiod_line *line; /* NULL when made from a bare fd */
	enum sync_gpiod_clock clock;  /* UNKNOWN until sure */
	int64_t last;                 /* the latest edge returned, 0 before any */
	uint32_t seqno;               /* v2: the latest event's line seqno, 0 before any */
	int pending_err;              /* met after edges were read: returned next */
	struct sync_gpiod_stats stats;
	struct log_ratelimit other_log;
	char name[160];
};

static int64_t clock_ns(clockid_t id)
{
	struct timespec ts;
	clock_gettime(id, &ts);
	return (int64_t)ts.tv_sec * NSEC + ts.tv_nsec;
}

/* Both clocks at one instant, as near as can be: REALTIME read between two
 * MONOTONIC reads, the tightest of three tries, so that a preemption
 * between the reads does not go into the offset between the clocks. */
static void read_clocks(int64_t *mono, int64_t *real)
{
	int64_t best = INT64_MAX;
	*mono = *real = 0;
	for (int i = 0; i < 3; i++) {
		int64_t m0 = clock_ns(CLOCK_MONOTONIC), r = clock_ns(CLOCK_REALTIME);
		int64_t m1 = clock_ns(CLOCK_MONOTONIC);
		if (m1 - m0 < best) {
			best = m1 - m0;
			*mono = m0 + (m1 - m0) / 2;
			*real = r;
		}
	}
}

enum sync_gpiod_clock sync_gpiod_pick_clock(int64_t ts, int64_t mono_now, int64_t real_now, bool *sure)
{
	/* Ages on either clock; a negative one rules that clock out, since
	 * an edge is stamped before it is read. */
	int64_t mono_age = mono_now - ts, real_age = real_now - ts;
	bool mono_ok = ts >= 0 && mono_age >= 0, real_ok = ts >= 0 && real_age >= 0;
	int64_t apart = mono_now > real_now ? mono_now - real_now : real_now - mono_now;
	enum sync_gpiod_clock c = SYNC_GPIOD_CLOCK_REALTIME;
	if (!mono_ok && !real_ok)
		c = SYNC_GPIOD_CLOCK_UNKNOWN;
	else if (mono_ok && (!real_ok || mono_age <= real_age))
		c = SYNC_GPIOD_CLOCK_MONOTONIC;
	/* An old winner may be garbage that only looks like an old edge. */
	int64_t age = c == SYNC_GPIOD_CLOCK_MONOTONIC ? mono_age : real_age;
	*sure = c != SYNC_GPIOD_CLOCK_UNKNOWN && age <= SURE_MAX_AGE_NS &&
		(mono_ok != real_ok || apart > CLOCKS_FAR_APART_NS);
	return c;
}

/* The clock that stamped ts: the settled one, or a pick from ts, settled on
 * when sure. Picked per edge: a garbage record beside a good one must not
 * decide for it. */
static enum sync_gpiod_clock edge_clock(struct sync_gpiod *s, int64_t ts, int64_t mono_now, int64_t real_now)
{
	if (s->clock != SYNC_GPIOD_CLOCK_UNKNOWN)
		return s->clock;
	bool sure;
	enum sync_gpiod_clock c = sync_gpiod_pick_clock(ts, mono_now, real_now, &sure);
	if (!sure)
		return c;
	s->clock = c;
	if (c == SYNC_GPIOD_CLOCK_REALTIME)
		log_info("%s: the kernel stamps edges with CLOCK_REALTIME (Linux < 5.7): "
			 "moving them to CLOCK_MONOTONIC",
			 s->name);
	else
		log_debug("%s: the kernel stamps edges with CLOCK_MONOTONIC", s->name);
	return c;
}

/* The v2 checks, before an event's time: an event for another line is
 * skipped (1); a gap in the line's sequence numbers counts the events the
 * kernel dropped (0, as for the next number); a number that does not move
 * on is no kernel's (-EBADMSG). The numbers are the uAPI's 32 bits and
 * wrap. */
static int check_line_seqno(struct sync_gpiod *s, const struct sync_gpiod_event *ev)
{
	if (ev->other_line) {
		s->stats.other_line++;
		if (log_ratelimit_ok(&s->other_log))
			log_error("%s: an event for line %u, which was not requested: ignored (%llu so far)", s->name,
				  ev->offset, (unsigned long long)s->stats.other_line);
		return 1;
	}
	if (!ev->has_seqno)
		return 0;
	uint32_t step = ev->seqno - s->seqno;
	if (step == 0 || step > UINT32_MAX / 2) {
		log_error("%s: event sequence number %lu after %lu: not a GPIO event record", s->name,
			  (unsigned long)ev->seqno, (unsigned long)s->seqno);
		return -EBADMSG;
	}
	if (step > 1) {
		s->stats.lost += step - 1;
		log_warn("%s: the kernel dropped %lu edge event(s): its buffer was full (%llu so far)", s->name,
			 (unsigned long)(step - 1), (unsigned long long)s->stats.lost);
	}
	s->seqno = ev->seqno;
	return 0;
}

/* One rising edge moved to CLOCK_MONOTONIC and appended to ts[*n], checked
 * to be a time an edge can have: not ahead of now, not before the edge
 * before it (-EBADMSG). */
static int take_edge(struct sync_gpiod *s, const struct sync_gpiod_event *ev, const int64_t now[2], int64_t *ts, int *n)
{
	enum sync_gpiod_clock c = edge_clock(s, ev->ts, now[0], now[1]);
	int64_t t = ev->ts + (c == SYNC_GPIOD_CLOCK_REALTIME ? now[0] - now[1] : 0);
	if (c == SYNC_GPIOD_CLOCK_UNKNOWN || ev->ts <= 0 || t <= 0 || t > now[0] + CONVERT_SLACK_NS || t < s->last) {
		log_error("%s: edge timestamp %lld ns is no time an edge can have "
			  "(now %lld, last edge %lld): not a GPIO event record",
			  s->name, (long long)ev->ts, (long long)now[0], (long long)s->last);
		return -EBADMSG;
	}
	ts[(*n)++] = t;
	s->last = t;
	s->stats.edges++;
	return 0;
}

/* Takes the rising edges among ev into ts[*n]. -EBADMSG at the first event
 * that is no kernel's; the edges before it are kept. The clocks are read
 * after the events, so every true edge lies before now. */
static int take_edges(struct sync_gpiod *s, const struct sync_gpiod_event *ev, int count, int64_t *ts, int *n)
{
	int64_t now[2]; /* MONOTONIC, REALTIME */
	read_clocks(&now[0], &now[1]);
	for (int i = 0; i < count; i++) {
		int r = check_line_seqno(s, &ev[i]);
		if (r == 0 && ev[i].rising)
			r = take_edge(s, &ev[i], now, ts, n);
		if (r < 0)
			return r;
	}
	return 0;
}

/* Up to max events; 0 when none are pending, without blocking. Polls
 * first: a hang-up (the chip went away; EOF on a pipe) shows there, not in
 * read(), which libgpiod would turn into the same EIO as a short record. */
static int read_batch(struct sync_gpiod *s, struct sync_gpiod_event *ev, int max)
{
	struct pollfd pfd = { .fd = s->fd, .events = POLLIN };
	if (poll(&pfd, 1, 0) < 0)
		return -errno;
	if (pfd.revents & POLLNVAL)
		return -EBADF;
	if (!(pfd.revents & POLLIN)) {
		if (!(pfd.revents & (POLLHUP | POLLERR)))
			return 0;
		log_error("%s: the event fd hung up: the GPIO chip is gone", s->name);
		return -ENODEV;
	}
	int r = sync_gpiod_line_read(s->line, s->fd, ev, max);
	if (r == -EAGAIN)
		return 0; /* another reader was faster */
	if (r == -EIO)
		log_error("%s: a short read: not a whole GPIO event record", s->name);
	return r;
}

static int gpio_get_fd(struct sync_source *base)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	return s->fd;
}

static int gpio_read_edges(struct sync_source *base, int64_t *ts, int max)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	int n = 0, r = s->pending_err;
	s->pending_err = 0;
	while (r == 0 && n < max) {
		struct sync_gpiod_event ev[SYNC_GPIOD_READ_BATCH];
		/* Falling edges and skipped events come out of the count:
		 * read again for them. */
		int got = read_batch(s, ev, max - n < SYNC_GPIOD_READ_BATCH ? max - n : SYNC_GPIOD_READ_BATCH);
		if (got <= 0) {
			r = got;
			break;
		}
		r = take_edges(s, ev, got, ts, &n);
	}
	/* Edges already read are worth more than the error: it waits. */
	if (r < 0 && n > 0) {
		s->pending_err = r;
		return n;
	}
	return r < 0 ? r : n;
}

static void gpio_destroy(struct sync_source *base)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	if (s->line)
		sync_gpiod_line_release(s->line);
	free(s);
}

static const struct sync_impl gpio_impl = {
	.name = "gpiod",
	.get_fd = gpio_get_fd,
	.read_edges = gpio_read_edges,
	.destroy = gpio_destroy,
};

struct sync_source *sync_gpiod_wrap(const struct sync_gpiod_request *req, const char *name)
{
	struct sync_gpiod *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &gpio_impl;
	s->fd = req->fd;
	s->line = req->line;
	s->clock = req->clock;
	s->other_log.interval_ns = OTHER_LINE_LOG_NS;
	snprintf(s->name, sizeof(s->name), "%s", name);
	return &s->base;
}

int sync_gpiod_set_nonblock(int fd)
{
	int flags = fd < 0 ? -1 : fcntl(fd, F_GETFL);
	if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
		return fd < 0 ? -EBADF : -errno;
	return 0;
}

enum sync_gpiod_clock sync_gpiod_clock(struct sync_source *base)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	return s->clock;
}

void sync_gpiod_get_stats(struct sync_source *base, struct sync_gpiod_stats *out)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	*out = s->stats;
}

long sync_gpiod_parse_offset(const char *line)
{
	char *end;
	if (line[0] < '0' || line[0] > '9')
		return -1;
	errno = 0;
	unsigned long v = strtoul(line, &end, 10);
	if (*end || errno || v > UINT_MAX)
		return -1;
	return (long)v;
}

static bool config_valid(const struct sync_gpiod_config *cfg)
{
	return cfg && cfg->chip[0] && cfg->line[0] && memchr(cfg->chip, 0, sizeof(cfg->chip)) &&
	       memchr(cfg->line, 0, sizeof(cfg->line));
}

struct sync_source *sync_gpiod_create(const struct sync_gpiod_config *cfg)
{
	if (!config_valid(cfg)) {
		log_error("sync gpiod: the chip and the line must both be named");
		errno = EINVAL;
		return NULL;
	}
	char name[160];
	snprintf(name, sizeof(name), "gpio %s line %s", cfg->chip, cfg->line);
	struct sync_gpiod_request req = { .fd = -1 };
	const char *why = "";
	int r = sync_gpiod_line_request(cfg, &req, &why);
	if (r < 0) {
		log_error("sync gpiod: chip %s line %s: %s: %s", cfg->chip, cfg->line, why, strerror(-r));
		errno = -r;
		return NULL;
	}
	struct sync_source *s = sync_gpiod_wrap(&req, name);
	if (!s) {
		sync_gpiod_line_release(req.line);
		errno = ENOMEM;
		return NULL;
	}
	log_info("%s: index pulse on the %s edge", name, cfg->active_low ? "falling (active low)" : "rising");
	return s;
}
