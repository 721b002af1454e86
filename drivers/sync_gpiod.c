/* The index pulse from a real GPIO line: the libgpiod 1.5/1.6 backend (the
 * GPIO character device's v1 uAPI). Built when pkg-config finds libgpiod
 * older than 2 (drivers/meson.build); sync_gpiod2.c is the libgpiod 2 one.
 * Only the request, the record read and the release are here: the rest,
 * clocks and checks included, is sync_gpiod_common.c.
 *
 * The v1 uAPI has no line offset or sequence number in its event records:
 * a record is a timestamp and an edge, and the clock of the timestamp is
 * found from the edges (CLOCK_REALTIME before Linux 5.7). */
#include <errno.h>
#include <gpiod.h>
#include <stdint.h>
#include <stdlib.h>
#include <time.h>

#include "sync.h"
#include "sync_gpiod_priv.h"

#define NSEC 1000000000LL

struct sync_gpiod_line {
	struct gpiod_chip *chip;
	struct gpiod_line *line;
};

struct sync_source *sync_gpiod_from_fd(int fd, const char *name)
{
	/* Never block the event loop, even if poll() and read() disagree. */
	int r = sync_gpiod_set_nonblock(fd);
	if (r < 0) {
		errno = -r;
		return NULL;
	}
	struct sync_gpiod_request req = { .line = NULL, .fd = fd, .clock = SYNC_GPIOD_CLOCK_UNKNOWN };
	return sync_gpiod_wrap(&req, name);
}

/* cfg's line on the chip: by offset when all digits, else by name. */
static struct gpiod_line *find_line(struct gpiod_chip *chip, const char *line, const char **why)
{
	long off = sync_gpiod_parse_offset(line);
	*why = off < 0 ? "no line of that name on the chip" : "no line at that offset on the chip";
	return off < 0 ? gpiod_chip_find_line(chip, line) : gpiod_chip_get_line(chip, (unsigned int)off);
}

int sync_gpiod_line_request(const struct sync_gpiod_config *cfg, struct sync_gpiod_request *out, const char **why)
{
	int err;
	struct sync_gpiod_line *l = calloc(1, sizeof(*l));
	if (!l)
		return -ENOMEM;
	*why = "cannot open the GPIO chip";
	errno = 0;
	l->chip = gpiod_chip_open_lookup(cfg->chip);
	if (!l->chip) {
		err = errno ? errno : ENOENT;
		free(l);
		return -err;
	}
	l->line = find_line(l->chip, cfg->line, why);
	if (!l->line)
		goto err_close_chip;
	*why = "cannot request rising-edge events (is another consumer holding the line?)";
	int flags = cfg->active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
	if (gpiod_line_request_rising_edge_events_flags(l->line, SYNC_GPIOD_CONSUMER, flags) < 0)
		goto err_close_chip;
	*why = "cannot make the event fd non-blocking";
	out->fd = gpiod_line_event_get_fd(l->line);
	int r = sync_gpiod_set_nonblock(out->fd);
	if (r < 0) {
		errno = -r;
		goto err_close_chip;
	}
	out->line = l;
	out->clock = SYNC_GPIOD_CLOCK_UNKNOWN; /* found from the edges */
	return 0;

err_close_chip:
	err = errno ? errno : ENOENT;
	gpiod_chip_close(l->chip); /* releases the line too */
	free(l);
	return -err;
}

static int64_t timespec_ns(const struct timespec *t)
{
	if (t->tv_sec < 0 || t->tv_sec >= INT64_MAX / NSEC - 1)
		return -1; /* garbage; u64 ns does not fit int64_t */
	return (int64_t)t->tv_sec * NSEC + t->tv_nsec;
}

/* libgpiod reads the kernel's struct gpioevent_data records from the fd. */
int sync_gpiod_line_read(struct sync_gpiod_line *line, int fd, struct sync_gpiod_event *ev, int max)
{
	(void)line;
	struct gpiod_line_event rec[SYNC_GPIOD_READ_BATCH];
	if (max > SYNC_GPIOD_READ_BATCH)
		max = SYNC_GPIOD_READ_BATCH;
	int n = gpiod_line_event_read_fd_multiple(fd, rec, (unsigned int)max);
	if (n < 0)
		return -errno;
	for (int i = 0; i < n; i++)
		ev[i] = (struct sync_gpiod_event){
			.ts = timespec_ns(&rec[i].ts),
			.rising = rec[i].event_type == GPIOD_LINE_EVENT_RISING_EDGE,
		};
	return n;
}

void sync_gpiod_line_release(struct sync_gpiod_line *line)
{
	gpiod_line_release(line->line);
	gpiod_chip_close(line->chip);
	free(line);
}
