/* The index pulse from a real GPIO line, through libgpiod 1.6 (the GPIO
 * character device's v1 uAPI).
 *
 * Timestamps: every edge carries the kernel's timestamp, taken in the
 * interrupt, so scheduling latency never shows up as jitter. Since Linux 5.7
 * the v1 line event timestamp is CLOCK_MONOTONIC; before, it was
 * CLOCK_REALTIME. Kernel versions lie (vendor backports), so the clock is
 * found from the events themselves: a timestamp lies shortly before "now" on
 * the clock that took it, and far from the other one (see
 * sync_gpiod_pick_clock()). REALTIME stamps are moved to MONOTONIC with the
 * offset between the clocks read at each batch, so a clock step (NTP at boot)
 * costs at most the batch read across it.
 *
 * Debounce: the v1 uAPI has none, and there is no point asking the kernel
 * for it: rejecting glitches is the estimator's job (sync_estimator.h), and
 * a noisy sensor wants a Schmitt trigger (docs/hardware.md). A libgpiod 2
 * backend would request debounce_period_us = 0 explicitly, so that no
 * default ever delays the edges.
 *
 * Everything libgpiod-specific is in the "libgpiod v1" section at the end:
 * the request, the record read, the release. A libgpiod 2 variant replaces
 * that section only. */
#include <errno.h>
#include <fcntl.h>
#include <gpiod.h>
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
#define GPIOD_CONSUMER "spindled"
#define READ_BATCH 16 /* libgpiod 1.6 reads at most 16 records a call */
/* Clocks further apart than this are told apart by any edge younger. */
#define CLOCKS_FAR_APART_NS (3600 * NSEC)
/* Only an edge younger than this settles the clock. */
#define SURE_MAX_AGE_NS (60 * NSEC)
/* How far a REALTIME edge, moved to MONOTONIC, may land after now: the two
 * clocks are not read at the same instant. */
#define CONVERT_SLACK_NS 1000000LL

/* One event record as read, before any clock handling. */
struct raw_edge {
	int64_t ts; /* ns, the kernel's clock; -1 when not representable */
	bool rising;
};

struct sync_gpiod {
	struct sync_source base;
	int fd;
	struct gpiod_chip *chip; /* NULL when made from a bare fd */
	struct gpiod_line *line;
	enum sync_gpiod_clock clock; /* UNKNOWN until sure */
	int64_t last;                /* the latest edge returned, 0 before any */
	int pending_err;             /* met after edges were read: returned next */
	char name[160];
};

static int v1_request(const struct sync_gpiod_config *cfg, struct sync_gpiod *s, const char **why);
static int v1_read(int fd, struct raw_edge *raw, int max);
static void v1_release(struct sync_gpiod *s);

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

/* Moves the rising edges among raw to CLOCK_MONOTONIC and appends them to
 * ts[*n], checking each is a time an edge can have: not ahead of now, not
 * before the edge before it. -EBADMSG at the first that is not; the edges
 * before it are kept. The clocks are read after the records, so every
 * true edge lies before now. */
static int take_edges(struct sync_gpiod *s, const struct raw_edge *raw, int count, int64_t *ts, int *n)
{
	int64_t mono_now, real_now;
	read_clocks(&mono_now, &real_now);
	for (int i = 0; i < count; i++) {
		if (!raw[i].rising)
			continue;
		enum sync_gpiod_clock c = edge_clock(s, raw[i].ts, mono_now, real_now);
		int64_t t = raw[i].ts + (c == SYNC_GPIOD_CLOCK_REALTIME ? mono_now - real_now : 0);
		if (c == SYNC_GPIOD_CLOCK_UNKNOWN || raw[i].ts <= 0 || t <= 0 || t > mono_now + CONVERT_SLACK_NS ||
		    t < s->last) {
			log_error("%s: edge timestamp %lld ns is no time an edge can have "
				  "(now %lld, last edge %lld): not a GPIO event record",
				  s->name, (long long)raw[i].ts, (long long)mono_now, (long long)s->last);
			return -EBADMSG;
		}
		ts[(*n)++] = t;
		s->last = t;
	}
	return 0;
}

/* Up to max raw records; 0 when none are pending, without blocking. Polls
 * first: a hang-up (the chip went away; EOF on a pipe) shows there, not in
 * read(), which libgpiod would turn into the same EIO as a short record. */
static int read_batch(struct sync_gpiod *s, struct raw_edge *raw, int max)
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
	int r = v1_read(s->fd, raw, max);
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
		struct raw_edge raw[READ_BATCH];
		/* Falling edges come out of the count: read again for them. */
		int got = read_batch(s, raw, max - n < READ_BATCH ? max - n : READ_BATCH);
		if (got <= 0) {
			r = got;
			break;
		}
		r = take_edges(s, raw, got, ts, &n);
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
	v1_release(s);
	free(s);
}

static const struct sync_impl gpio_impl = {
	.name = "gpiod",
	.get_fd = gpio_get_fd,
	.read_edges = gpio_read_edges,
	.destroy = gpio_destroy,
};

static struct sync_gpiod *gpio_alloc(int fd, const char *name)
{
	struct sync_gpiod *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &gpio_impl;
	s->fd = fd;
	snprintf(s->name, sizeof(s->name), "%s", name);
	return s;
}

struct sync_source *sync_gpiod_from_fd(int fd, const char *name)
{
	int flags = fcntl(fd, F_GETFL);
	/* Never block the event loop, even if poll() and read() disagree. */
	if (flags < 0 || fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0)
		return NULL;
	struct sync_gpiod *s = gpio_alloc(fd, name);
	return s ? &s->base : NULL;
}

enum sync_gpiod_clock sync_gpiod_clock(struct sync_source *base)
{
	struct sync_gpiod *s = (struct sync_gpiod *)base;
	return s->clock;
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
	struct sync_gpiod *s = gpio_alloc(-1, name);
	if (!s)
		return NULL;
	const char *why = "";
	int r = v1_request(cfg, s, &why);
	if (r < 0) {
		log_error("sync gpiod: chip %s line %s: %s: %s", cfg->chip, cfg->line, why, strerror(-r));
		free(s);
		errno = -r;
		return NULL;
	}
	log_info("%s: index pulse on the %s edge", s->name, cfg->active_low ? "falling (active low)" : "rising");
	return &s->base;
}

/* ---- libgpiod v1 ----
 * The request, the record read and the release; the only code that knows
 * libgpiod. */

/* An offset when line is all digits, else -1: a name. */
static long line_offset(const char *line)
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

/* Opens cfg's chip, requests rising-edge events on its line into s (chip,
 * line, fd made non-blocking). 0, or -errno with *why saying which step. */
static int v1_request(const struct sync_gpiod_config *cfg, struct sync_gpiod *s, const char **why)
{
	int err;
	*why = "cannot open the GPIO chip";
	s->chip = gpiod_chip_open_lookup(cfg->chip);
	if (!s->chip)
		return errno ? -errno : -ENOENT;
	long off = line_offset(cfg->line);
	*why = off < 0 ? "no line of that name on the chip" : "no line at that offset on the chip";
	s->line = off < 0 ? gpiod_chip_find_line(s->chip, cfg->line) : gpiod_chip_get_line(s->chip, (unsigned int)off);
	if (!s->line)
		goto err_close_chip;
	*why = "cannot request rising-edge events (is another consumer holding the line?)";
	int flags = cfg->active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
	if (gpiod_line_request_rising_edge_events_flags(s->line, GPIOD_CONSUMER, flags) < 0)
		goto err_close_chip;
	*why = "cannot make the event fd non-blocking";
	s->fd = gpiod_line_event_get_fd(s->line);
	int fl = s->fd < 0 ? -1 : fcntl(s->fd, F_GETFL);
	if (fl < 0 || fcntl(s->fd, F_SETFL, fl | O_NONBLOCK) < 0)
		goto err_close_chip;
	return 0;

err_close_chip:
	err = errno ? errno : ENOENT;
	gpiod_chip_close(s->chip); /* releases the line too */
	s->chip = NULL;
	s->line = NULL;
	return -err;
}

static int64_t timespec_ns(const struct timespec *t)
{
	if (t->tv_sec < 0 || t->tv_sec >= INT64_MAX / NSEC - 1)
		return -1; /* garbage; u64 ns does not fit int64_t */
	return (int64_t)t->tv_sec * NSEC + t->tv_nsec;
}

/* Up to max (<= READ_BATCH) records from a v1 line event fd: libgpiod reads
 * the kernel's struct gpioevent_data. The count, or -errno (EIO: a short
 * record, EOF included; EAGAIN: none). */
static int v1_read(int fd, struct raw_edge *raw, int max)
{
	struct gpiod_line_event ev[READ_BATCH];
	int n = gpiod_line_event_read_fd_multiple(fd, ev, (unsigned int)max);
	if (n < 0)
		return -errno;
	for (int i = 0; i < n; i++) {
		raw[i].ts = timespec_ns(&ev[i].ts);
		raw[i].rising = ev[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE;
	}
	return n;
}

static void v1_release(struct sync_gpiod *s)
{
	if (!s->chip)
		return;
	gpiod_line_release(s->line);
	gpiod_chip_close(s->chip);
}
