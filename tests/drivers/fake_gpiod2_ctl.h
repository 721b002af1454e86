/* How a test drives the libgpiod 2 fake (fake_gpiod2.c).
 *
 * The fake has one GPIO chip, set up by the test: a path, a label, a number
 * of lines and their names. A line request on it gets a real pipe: its read
 * end is the request's fd, and the test writes recorded edge events into
 * the other end as the kernel's uAPI v2 records (struct gpio_v2_line_event),
 * which gpiod_line_request_read_edge_events() reads back as libgpiod 2
 * does. So the code under test polls and reads a real fd, sees a hang-up as
 * it would when the chip goes away, and gets every field of every event
 * (timestamp, type, line offset, sequence numbers) as recorded, gaps and
 * all. */
#ifndef SPINDLE_FAKE_GPIOD2_CTL_H
#define SPINDLE_FAKE_GPIOD2_CTL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fake_gpiod2.h"

/* Resets the fake to one chip at path (opened by that path only) with
 * label and num_lines lines; names (NULL: none) names the first of them,
 * up to a NULL. No request is open; requests succeed. */
void fake_gpiod2_setup(const char *path, const char *label, unsigned int num_lines, const char *const *names);

/* Makes the next requests fail with errno err (0: succeed again). */
void fake_gpiod2_fail_requests(int err);

/* What the latest request asked for. */
struct fake_gpiod2_seen {
	int requests; /* made since setup */
	int fd;       /* the latest request's fd, -1 once released */
	size_t num_offsets;
	unsigned int offset; /* the first */
	enum gpiod_line_direction direction;
	enum gpiod_line_edge edge;
	enum gpiod_line_clock clock;
	bool active_low;
	unsigned long debounce_us;
	char consumer[32];
};
const struct fake_gpiod2_seen *fake_gpiod2_seen(void);

/* One recorded edge event: what the kernel puts in a record. */
struct fake_gpiod2_edge {
	uint64_t ts_ns;
	enum gpiod_edge_event_type type;
	unsigned int offset;
	uint32_t line_seqno; /* on its line, from 1 */
	uint32_t seqno;      /* in the request, from 1 */
};

/* Writes n events into the open request's fd as the kernel's records. */
void fake_gpiod2_push(const struct fake_gpiod2_edge *e, size_t n);

/* Writes raw bytes into it (a short record). */
void fake_gpiod2_push_bytes(const void *p, size_t n);

/* Closes the writing end: the fd hangs up once drained, as when the chip
 * goes away. */
void fake_gpiod2_hangup(void);

/* Objects made and not yet freed: chips, chip infos, settings, configs,
 * requests and buffers. */
int fake_gpiod2_live(void);

#endif
