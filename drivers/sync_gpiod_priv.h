/* The inside of the gpiod sync source, for its files and their tests only.
 *
 * sync_gpiod_common.c is everything that does not know libgpiod: the clock
 * the kernel stamped an edge with, the checks on each event, the read loop,
 * the sync_source and its log lines. One backend file holds the libgpiod
 * calls, picked at build time by the version of libgpiod pkg-config reports
 * (drivers/meson.build): sync_gpiod.c for libgpiod 1.5 and 1.6 (the GPIO
 * uAPI v1), sync_gpiod2.c for libgpiod 2.x (the uAPI v2). Each implements
 * the three sync_gpiod_line_* functions below, and nothing else differs.
 *
 * The v1 backend also has sync_gpiod_from_fd(): an edge source on a bare v1
 * line event fd, so that a test feeds a pipe with kernel-format struct
 * gpioevent_data records and runs the same code as a real line. The v2
 * backend is tested against a fake of the libgpiod 2 calls it makes
 * (tests/drivers/fake_gpiod2.c). */
#ifndef SPINDLE_SYNC_GPIOD_PRIV_H
#define SPINDLE_SYNC_GPIOD_PRIV_H

#include <stdbool.h>
#include <stdint.h>

#include "sync.h"

/* The clock an event timestamp was taken with. */
enum sync_gpiod_clock {
	SYNC_GPIOD_CLOCK_UNKNOWN = 0, /* none yet; or, from the picker: in both clocks' future */
	SYNC_GPIOD_CLOCK_MONOTONIC,   /* v1: kernels >= 5.7; v2: always, as requested */
	SYNC_GPIOD_CLOCK_REALTIME,    /* v1: kernels < 5.7 */
};

/* Which clock stamped ts (ns), given both clocks read just after it was
 * read: the one whose now is closest at or after ts. UNKNOWN when ts lies
 * ahead of both: not a timestamp. Sets *sure when ts is under a minute old
 * on the picked clock and the other clock is ruled out: ts lies in its
 * future, or the clocks are over an hour apart. When they are close (a board
 * without an RTC, before NTP) a pick that is not sure is right while the edge
 * is younger than the distance between the clocks. */
enum sync_gpiod_clock sync_gpiod_pick_clock(int64_t ts, int64_t mono_now, int64_t real_now, bool *sure);

/* ---- the backend interface ---- */

/* One edge event as a backend read it, before any clock handling. */
struct sync_gpiod_event {
	int64_t ts;          /* ns on the kernel's clock; -1 when no int64_t holds it */
	bool rising;         /* else falling */
	bool other_line;     /* v2: its line_offset is not the requested line's */
	unsigned int offset; /* v2: its line_offset (for the log) */
	bool has_seqno;      /* v2: seqno is set (the v1 uAPI has none) */
	/* v2: the event's sequence number on its line, from 1; 32 bits, as
	 * in the uAPI: they wrap. */
	uint32_t seqno;
};

/* The backend's own state: chip, request, buffers. */
struct sync_gpiod_line;

/* What a backend's request hands the common code. */
struct sync_gpiod_request {
	struct sync_gpiod_line *line; /* owned by the source from then on */
	int fd;                       /* pollable, non-blocking; the line's */
	/* The clock the kernel stamps with when the request fixed it (v2:
	 * MONOTONIC, asked for); UNKNOWN: found from the edges (v1). */
	enum sync_gpiod_clock clock;
};

/* Opens cfg's chip and requests its line (cfg checked: both named, both
 * terminated) for index edges: rising ones, physically falling with
 * cfg->active_low, as consumer SYNC_GPIOD_CONSUMER. 0 and *out, or -errno
 * with *why saying which step failed. */
int sync_gpiod_line_request(const struct sync_gpiod_config *cfg, struct sync_gpiod_request *out, const char **why);

/* Up to max (<= SYNC_GPIOD_READ_BATCH) events, oldest first, from line (v2)
 * or fd (v1; line is NULL for a source from sync_gpiod_from_fd()). The
 * count, or -errno: EAGAIN none pending, EIO a short record (EOF
 * included). */
int sync_gpiod_line_read(struct sync_gpiod_line *line, int fd, struct sync_gpiod_event *ev, int max);

/* Releases the line and closes its chip. */
void sync_gpiod_line_release(struct sync_gpiod_line *line);

#define SYNC_GPIOD_CONSUMER "spindled"
#define SYNC_GPIOD_READ_BATCH 16 /* libgpiod 1.6 reads at most 16 records a call */

/* ---- the common code, for the backends ---- */

/* An offset when line is all digits, else -1: a line name. */
long sync_gpiod_parse_offset(const char *line);

/* Makes fd non-blocking: 0 or -errno. */
int sync_gpiod_set_nonblock(int fd);

/* A source reading req (it takes req->line; NULL: a bare fd, which stays
 * the caller's). name labels log lines; it is copied. NULL + errno. */
struct sync_source *sync_gpiod_wrap(const struct sync_gpiod_request *req, const char *name);

/* ---- for tests ---- */

/* v1 backend only: an edge source on fd, a GPIO uAPI v1 line event fd (or
 * anything giving the same records). fd is made non-blocking and stays the
 * caller's: destroy does not close it. name labels log lines ("gpiochip0:17");
 * it is copied. NULL + errno on failure. */
struct sync_source *sync_gpiod_from_fd(int fd, const char *name);

/* The clock the source has settled on, UNKNOWN until it is sure. */
enum sync_gpiod_clock sync_gpiod_clock(struct sync_source *s);

/* What the source met besides its edges. */
struct sync_gpiod_stats {
	uint64_t edges;      /* rising edges returned */
	uint64_t lost;       /* v2: events the kernel dropped (its buffer was full), from gaps in seqno */
	uint64_t other_line; /* v2: events for a line not requested: ignored */
};
void sync_gpiod_get_stats(struct sync_source *s, struct sync_gpiod_stats *out);

#endif
