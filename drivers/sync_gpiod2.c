/* The index pulse from a real GPIO line: the libgpiod 2.x backend (the GPIO
 * character device's v2 uAPI, Linux >= 5.10). Built when pkg-config finds
 * libgpiod 2 or later (drivers/meson.build); sync_gpiod.c is the libgpiod 1
 * one. Only the request, the event read and the release are here: the rest,
 * clocks and checks included, is sync_gpiod_common.c.
 *
 * The request asks for what the v1 backend gets: an input, rising-edge
 * events, active low when configured (the kernel then reports the physical
 * falling edge as the rising one, as v1 does), as consumer "spindled", the
 * bias left as it is. It also asks for what v1 could not: timestamps from
 * CLOCK_MONOTONIC (no clock to guess), and a debounce period of 0, so that
 * no default ever delays an edge.
 *
 * Each v2 event names its line and carries the line's sequence number: the
 * common code ignores events for any line but ours and counts a gap in the
 * numbers as events the kernel dropped.
 *
 * libgpiod 2 opens a chip by path only: a chip named by number, name or
 * label (as libgpiod 1's gpiod_chip_open_lookup() took them) is looked up
 * here. Only run against the fake of tests/drivers/fake_gpiod2.c so far
 * (docs/hardware.md, "libgpiod versions"). */
#include <dirent.h>
#include <errno.h>
#include <gpiod.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sync.h"
#include "sync_gpiod_priv.h"

struct sync_gpiod_line {
	struct gpiod_chip *chip;
	struct gpiod_line_request *request;     /* NULL until requested */
	struct gpiod_edge_event_buffer *buffer; /* NULL until requested */
	unsigned int offset;
};

/* Whether chip's label is label. */
static bool chip_has_label(struct gpiod_chip *chip, const char *label)
{
	struct gpiod_chip_info *info = gpiod_chip_get_info(chip);
	if (!info)
		return false;
	const char *have = gpiod_chip_info_get_label(info);
	bool same = have && strcmp(have, label) == 0;
	gpiod_chip_info_free(info);
	return same;
}

/* The chip of that label: each /dev/gpiochip* opened in turn. */
static struct gpiod_chip *open_chip_by_label(const char *label)
{
	DIR *dir = opendir("/dev");
	struct gpiod_chip *found = NULL;
	struct dirent *e;
	while (dir && !found && (e = readdir(dir))) {
		char path[300];
		if (strncmp(e->d_name, "gpiochip", 8) != 0)
			continue;
		snprintf(path, sizeof(path), "/dev/%s", e->d_name);
		struct gpiod_chip *chip = gpiod_chip_open(path);
		if (chip && chip_has_label(chip, label))
			found = chip;
		else if (chip)
			gpiod_chip_close(chip);
	}
	if (dir)
		closedir(dir);
	if (!found)
		errno = ENOENT;
	return found;
}

/* The chip named by spec: a path ("/dev/gpiochip0"), a number ("0"), a
 * name under /dev ("gpiochip0"), else a label ("pinctrl-bcm2711"). */
static struct gpiod_chip *open_chip(const char *spec)
{
	char path[128];
	if (spec[0] == '/')
		return gpiod_chip_open(spec);
	bool number = sync_gpiod_parse_offset(spec) >= 0;
	if (number)
		snprintf(path, sizeof(path), "/dev/gpiochip%ld", sync_gpiod_parse_offset(spec));
	else
		snprintf(path, sizeof(path), "/dev/%s", spec);
	struct gpiod_chip *chip = gpiod_chip_open(path);
	if (chip || number || errno != ENOENT)
		return chip;
	return open_chip_by_label(spec);
}

/* The offset of line on the chip: all digits, below the chip's count of
 * lines; else a line name. 0, or -errno (ENOENT: no such line). */
static int find_offset(struct gpiod_chip *chip, const char *line, unsigned int *offset, const char **why)
{
	long off = sync_gpiod_parse_offset(line);
	if (off < 0) {
		*why = "no line of that name on the chip";
		errno = 0;
		int r = gpiod_chip_get_line_offset_from_name(chip, line);
		if (r < 0)
			return errno ? -errno : -ENOENT;
		*offset = (unsigned int)r;
		return 0;
	}
	*why = "cannot read the chip's line count";
	struct gpiod_chip_info *info = gpiod_chip_get_info(chip);
	if (!info)
		return errno ? -errno : -EIO;
	size_t lines = gpiod_chip_info_get_num_lines(info);
	gpiod_chip_info_free(info);
	*why = "no line at that offset on the chip";
	if ((unsigned long)off >= lines)
		return -ENOENT;
	*offset = (unsigned int)off;
	return 0;
}

/* An input with rising-edge events (physically falling when active low),
 * stamped with CLOCK_MONOTONIC, not debounced. NULL + errno. */
static struct gpiod_line_settings *index_settings(bool active_low)
{
	struct gpiod_line_settings *st = gpiod_line_settings_new();
	if (!st)
		return NULL;
	if (gpiod_line_settings_set_direction(st, GPIOD_LINE_DIRECTION_INPUT) < 0 ||
	    gpiod_line_settings_set_edge_detection(st, GPIOD_LINE_EDGE_RISING) < 0 ||
	    gpiod_line_settings_set_event_clock(st, GPIOD_LINE_CLOCK_MONOTONIC) < 0) {
		int err = errno;
		gpiod_line_settings_free(st);
		errno = err;
		return NULL;
	}
	gpiod_line_settings_set_active_low(st, active_low);
	gpiod_line_settings_set_debounce_period_us(st, 0);
	return st;
}

/* The line at offset requested with index_settings(). NULL + errno. */
static struct gpiod_line_request *request_line(struct gpiod_chip *chip, unsigned int offset, bool active_low)
{
	struct gpiod_line_settings *st = index_settings(active_low);
	struct gpiod_line_config *lc = st ? gpiod_line_config_new() : NULL;
	struct gpiod_request_config *rc = lc ? gpiod_request_config_new() : NULL;
	struct gpiod_line_request *req = NULL;
	if (rc && gpiod_line_config_add_line_settings(lc, &offset, 1, st) == 0) {
		gpiod_request_config_set_consumer(rc, SYNC_GPIOD_CONSUMER);
		req = gpiod_chip_request_lines(chip, rc, lc);
	}
	int err = errno;
	if (rc)
		gpiod_request_config_free(rc);
	if (lc)
		gpiod_line_config_free(lc);
	if (st)
		gpiod_line_settings_free(st);
	errno = err;
	return req;
}

/* l's line requested, its event buffer made, its fd non-blocking. */
static int request_events(struct sync_gpiod_line *l, bool active_low, const char **why)
{
	*why = "cannot request rising-edge events (is another consumer holding the line?)";
	errno = 0;
	l->request = request_line(l->chip, l->offset, active_low);
	if (!l->request)
		return errno ? -errno : -EIO;
	*why = "cannot make an edge event buffer";
	l->buffer = gpiod_edge_event_buffer_new(SYNC_GPIOD_READ_BATCH);
	if (!l->buffer)
		return errno ? -errno : -ENOMEM;
	*why = "cannot make the event fd non-blocking";
	return sync_gpiod_set_nonblock(gpiod_line_request_get_fd(l->request));
}

int sync_gpiod_line_request(const struct sync_gpiod_config *cfg, struct sync_gpiod_request *out, const char **why)
{
	struct sync_gpiod_line *l = calloc(1, sizeof(*l));
	if (!l)
		return -ENOMEM;
	*why = "cannot open the GPIO chip";
	errno = 0;
	l->chip = open_chip(cfg->chip);
	if (!l->chip) {
		int err = errno ? errno : ENOENT;
		free(l);
		return -err;
	}
	int r = find_offset(l->chip, cfg->line, &l->offset, why);
	if (r == 0)
		r = request_events(l, cfg->active_low, why);
	if (r < 0) {
		sync_gpiod_line_release(l);
		return r;
	}
	out->line = l;
	out->fd = gpiod_line_request_get_fd(l->request);
	out->clock = SYNC_GPIOD_CLOCK_MONOTONIC; /* asked for */
	return 0;
}

/* libgpiod reads the kernel's struct gpio_v2_line_event records from the
 * request's fd into the buffer. */
int sync_gpiod_line_read(struct sync_gpiod_line *l, int fd, struct sync_gpiod_event *ev, int max)
{
	(void)fd; /* the request's */
	if (max > SYNC_GPIOD_READ_BATCH)
		max = SYNC_GPIOD_READ_BATCH;
	errno = 0;
	int n = gpiod_line_request_read_edge_events(l->request, l->buffer, (size_t)max);
	if (n < 0)
		return errno ? -errno : -EIO;
	for (int i = 0; i < n && i < max; i++) {
		struct gpiod_edge_event *e = gpiod_edge_event_buffer_get_event(l->buffer, (unsigned long)i);
		if (!e)
			return -EIO;
		uint64_t ts = gpiod_edge_event_get_timestamp_ns(e);
		unsigned int off = gpiod_edge_event_get_line_offset(e);
		ev[i] = (struct sync_gpiod_event){
			.ts = ts > INT64_MAX ? -1 : (int64_t)ts,
			.rising = gpiod_edge_event_get_event_type(e) == GPIOD_EDGE_EVENT_RISING_EDGE,
			.other_line = off != l->offset,
			.offset = off,
			.has_seqno = true,
			.seqno = (uint32_t)gpiod_edge_event_get_line_seqno(e),
		};
	}
	return n < max ? n : max;
}

void sync_gpiod_line_release(struct sync_gpiod_line *l)
{
	if (l->buffer)
		gpiod_edge_event_buffer_free(l->buffer);
	if (l->request)
		gpiod_line_request_release(l->request);
	gpiod_chip_close(l->chip);
	free(l);
}
