/* The inside of the gpiod sync source, for sync_gpiod.c and its test only.
 *
 * sync_gpiod_create() requests the line and hands its event fd to
 * sync_gpiod_from_fd(); everything after the request (reading GPIO uAPI v1
 * event records through libgpiod, the clock the kernel stamped them with,
 * checks) lives behind that fd, so a test feeds a pipe with kernel-format
 * struct gpioevent_data records and runs the same code as a real line. */
#ifndef SPINDLE_SYNC_GPIOD_PRIV_H
#define SPINDLE_SYNC_GPIOD_PRIV_H

#include <stdbool.h>
#include <stdint.h>

#include "sync.h"

/* The clock an event timestamp was taken with. */
enum sync_gpiod_clock {
	SYNC_GPIOD_CLOCK_UNKNOWN = 0, /* none yet; or, from the picker: in both clocks' future */
	SYNC_GPIOD_CLOCK_MONOTONIC,   /* kernels >= 5.7 */
	SYNC_GPIOD_CLOCK_REALTIME,    /* kernels < 5.7 */
};

/* Which clock stamped ts (ns), given both clocks read just after it was
 * read: the one whose now is closest at or after ts. UNKNOWN when ts lies
 * ahead of both: not a timestamp. Sets *sure when ts is under a minute old
 * on the picked clock and the other clock is ruled out: ts lies in its
 * future, or the clocks are over an hour apart. When they are close (a board
 * without an RTC, before NTP) a pick that is not sure is right while the edge
 * is younger than the distance between the clocks. */
enum sync_gpiod_clock sync_gpiod_pick_clock(int64_t ts, int64_t mono_now, int64_t real_now, bool *sure);

/* An edge source on fd, a GPIO uAPI v1 line event fd (or anything giving
 * the same records). fd is made non-blocking and stays the caller's: destroy
 * does not close it. name labels log lines ("gpiochip0:17"); it is copied.
 * NULL + errno on failure. */
struct sync_source *sync_gpiod_from_fd(int fd, const char *name);

/* The clock the source has settled on, UNKNOWN until it is sure. */
enum sync_gpiod_clock sync_gpiod_clock(struct sync_source *s);

#endif
