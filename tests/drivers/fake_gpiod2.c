/* A fake of the libgpiod 2 calls drivers/sync_gpiod2.c makes (fake_gpiod2.h),
 * driven by a test through fake_gpiod2_ctl.h. Not libgpiod: it checks what
 * it is asked for as libgpiod 2 and the kernel would (enum ranges, offsets
 * on the chip, one holder of a line), keeps what it saw for the test, and
 * reads edge events from a real pipe in the kernel's uAPI v2 record format,
 * as libgpiod 2 reads its request fd. Methods called on NULL abort, as
 * libgpiod's do. */
#include <errno.h>
#include <fcntl.h>
#include <linux/gpio.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fake_gpiod2_ctl.h"

#define MAX_LINES 64
#define MAX_CONFIG 8
#define MAX_NAMES 16
#define BUFFER_DEFAULT 64 /* libgpiod 2: capacity 0 means 64 */
#define BUFFER_MAX 1024   /* and it caps it at 1024 */

struct gpiod_chip {
	int unused;
};

struct gpiod_chip_info {
	char label[GPIO_MAX_NAME_SIZE];
	size_t num_lines;
};

struct gpiod_line_settings {
	enum gpiod_line_direction direction;
	enum gpiod_line_edge edge;
	enum gpiod_line_clock clock;
	bool active_low;
	unsigned long debounce_us;
};

struct gpiod_line_config {
	size_t count;
	unsigned int offsets[MAX_CONFIG];
	struct gpiod_line_settings settings[MAX_CONFIG];
};

struct gpiod_request_config {
	char consumer[GPIO_MAX_NAME_SIZE];
};

struct gpiod_line_request {
	int fd; /* the pipe's read end */
};

struct gpiod_edge_event {
	enum gpiod_edge_event_type type;
	uint64_t ts_ns;
	unsigned int offset;
	unsigned long seqno, line_seqno;
};

struct gpiod_edge_event_buffer {
	size_t capacity, count;
	struct gpiod_edge_event *events;
};

static struct {
	char path[128], label[GPIO_MAX_NAME_SIZE];
	unsigned int num_lines;
	char names[MAX_NAMES][GPIO_MAX_NAME_SIZE];
	int fail_err;
	bool held;    /* a request holds the line(s) */
	int write_fd; /* the pipe's write end, -1 when none */
	int live;
	struct fake_gpiod2_seen seen;
} fake = { .write_fd = -1 };

static void *fake_new(size_t size)
{
	void *p = calloc(1, size);
	if (!p)
		abort();
	fake.live++;
	return p;
}

static void fake_free(void *p)
{
	if (!p)
		return;
	fake.live--;
	free(p);
}

static void need(const void *object)
{
	if (!object)
		abort();
}

/* ---- control ---- */

void fake_gpiod2_setup(const char *path, const char *label, unsigned int num_lines, const char *const *names)
{
	if (fake.write_fd >= 0)
		close(fake.write_fd);
	int live = fake.live;
	memset(&fake, 0, sizeof(fake));
	fake.live = live;
	fake.write_fd = -1;
	fake.seen.fd = -1;
	snprintf(fake.path, sizeof(fake.path), "%s", path);
	snprintf(fake.label, sizeof(fake.label), "%s", label);
	fake.num_lines = num_lines;
	for (int i = 0; names && names[i] && i < MAX_NAMES; i++)
		snprintf(fake.names[i], sizeof(fake.names[i]), "%s", names[i]);
}

void fake_gpiod2_fail_requests(int err)
{
	fake.fail_err = err;
}

const struct fake_gpiod2_seen *fake_gpiod2_seen(void)
{
	return &fake.seen;
}

static void write_all(const void *p, size_t n)
{
	if (fake.write_fd < 0 || write(fake.write_fd, p, n) != (ssize_t)n)
		abort(); /* the test pushes into no request, or too much at once */
}

void fake_gpiod2_push(const struct fake_gpiod2_edge *e, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		struct gpio_v2_line_event rec = {
			.timestamp_ns = e[i].ts_ns,
			.id = e[i].type == GPIOD_EDGE_EVENT_RISING_EDGE ? GPIO_V2_LINE_EVENT_RISING_EDGE
									: GPIO_V2_LINE_EVENT_FALLING_EDGE,
			.offset = e[i].offset,
			.seqno = e[i].seqno,
			.line_seqno = e[i].line_seqno,
		};
		write_all(&rec, sizeof(rec));
	}
}

void fake_gpiod2_push_bytes(const void *p, size_t n)
{
	write_all(p, n);
}

void fake_gpiod2_hangup(void)
{
	if (fake.write_fd >= 0)
		close(fake.write_fd);
	fake.write_fd = -1;
}

int fake_gpiod2_live(void)
{
	return fake.live;
}

/* ---- chips ---- */

struct gpiod_chip *gpiod_chip_open(const char *path)
{
	if (!path || !fake.path[0] || strcmp(path, fake.path) != 0) {
		errno = ENOENT;
		return NULL;
	}
	return fake_new(sizeof(struct gpiod_chip));
}

void gpiod_chip_close(struct gpiod_chip *chip)
{
	fake_free(chip);
}

struct gpiod_chip_info *gpiod_chip_get_info(struct gpiod_chip *chip)
{
	need(chip);
	struct gpiod_chip_info *info = fake_new(sizeof(*info));
	snprintf(info->label, sizeof(info->label), "%s", fake.label);
	info->num_lines = fake.num_lines;
	return info;
}

void gpiod_chip_info_free(struct gpiod_chip_info *info)
{
	fake_free(info);
}

const char *gpiod_chip_info_get_label(struct gpiod_chip_info *info)
{
	need(info);
	return info->label;
}

size_t gpiod_chip_info_get_num_lines(struct gpiod_chip_info *info)
{
	need(info);
	return info->num_lines;
}

int gpiod_chip_get_line_offset_from_name(struct gpiod_chip *chip, const char *name)
{
	need(chip);
	for (unsigned int i = 0; name && i < MAX_NAMES && i < fake.num_lines; i++)
		if (fake.names[i][0] && strcmp(fake.names[i], name) == 0)
			return (int)i;
	errno = ENOENT;
	return -1;
}

/* Whether cfg is a request the kernel takes: some offsets, all on the
 * chip. */
static bool config_ok(const struct gpiod_line_config *cfg)
{
	if (cfg->count == 0)
		return false;
	for (size_t i = 0; i < cfg->count; i++)
		if (cfg->offsets[i] >= fake.num_lines)
			return false;
	return true;
}

static void remember(const struct gpiod_request_config *req_cfg, const struct gpiod_line_config *cfg, int fd)
{
	const struct gpiod_line_settings *st = &cfg->settings[0];
	fake.seen.requests++;
	fake.seen.fd = fd;
	fake.seen.num_offsets = cfg->count;
	fake.seen.offset = cfg->offsets[0];
	fake.seen.direction = st->direction;
	fake.seen.edge = st->edge;
	fake.seen.clock = st->clock;
	fake.seen.active_low = st->active_low;
	fake.seen.debounce_us = st->debounce_us;
	snprintf(fake.seen.consumer, sizeof(fake.seen.consumer), "%s", req_cfg ? req_cfg->consumer : "");
}

struct gpiod_line_request *gpiod_chip_request_lines(struct gpiod_chip *chip, struct gpiod_request_config *req_cfg,
						    struct gpiod_line_config *line_cfg)
{
	need(chip);
	if (!line_cfg || !config_ok(line_cfg)) {
		errno = EINVAL;
		return NULL;
	}
	if (fake.fail_err || fake.held) {
		errno = fake.fail_err ? fake.fail_err : EBUSY;
		return NULL;
	}
	int p[2];
	if (pipe2(p, O_CLOEXEC) < 0)
		return NULL;
	struct gpiod_line_request *req = fake_new(sizeof(*req));
	req->fd = p[0];
	fake.write_fd = p[1];
	fake.held = true;
	remember(req_cfg, line_cfg, p[0]);
	return req;
}

/* ---- settings and configs ---- */

struct gpiod_line_settings *gpiod_line_settings_new(void)
{
	struct gpiod_line_settings *st = fake_new(sizeof(*st));
	/* libgpiod 2's defaults */
	st->direction = GPIOD_LINE_DIRECTION_AS_IS;
	st->edge = GPIOD_LINE_EDGE_NONE;
	st->clock = GPIOD_LINE_CLOCK_MONOTONIC;
	return st;
}

void gpiod_line_settings_free(struct gpiod_line_settings *settings)
{
	fake_free(settings);
}

static int in_range(int v, int lo, int hi)
{
	if (v >= lo && v <= hi)
		return 0;
	errno = EINVAL;
	return -1;
}

int gpiod_line_settings_set_direction(struct gpiod_line_settings *settings, enum gpiod_line_direction direction)
{
	need(settings);
	if (in_range(direction, GPIOD_LINE_DIRECTION_AS_IS, GPIOD_LINE_DIRECTION_OUTPUT) < 0)
		return -1;
	settings->direction = direction;
	return 0;
}

int gpiod_line_settings_set_edge_detection(struct gpiod_line_settings *settings, enum gpiod_line_edge edge)
{
	need(settings);
	if (in_range(edge, GPIOD_LINE_EDGE_NONE, GPIOD_LINE_EDGE_BOTH) < 0)
		return -1;
	settings->edge = edge;
	return 0;
}

void gpiod_line_settings_set_active_low(struct gpiod_line_settings *settings, bool active_low)
{
	need(settings);
	settings->active_low = active_low;
}

void gpiod_line_settings_set_debounce_period_us(struct gpiod_line_settings *settings, unsigned long period)
{
	need(settings);
	settings->debounce_us = period;
}

int gpiod_line_settings_set_event_clock(struct gpiod_line_settings *settings, enum gpiod_line_clock event_clock)
{
	need(settings);
	if (in_range(event_clock, GPIOD_LINE_CLOCK_MONOTONIC, GPIOD_LINE_CLOCK_HTE) < 0)
		return -1;
	settings->clock = event_clock;
	return 0;
}

struct gpiod_line_config *gpiod_line_config_new(void)
{
	return fake_new(sizeof(struct gpiod_line_config));
}

void gpiod_line_config_free(struct gpiod_line_config *config)
{
	fake_free(config);
}

int gpiod_line_config_add_line_settings(struct gpiod_line_config *config, const unsigned int *offsets,
					size_t num_offsets, struct gpiod_line_settings *settings)
{
	need(config);
	if (!offsets || !num_offsets || config->count + num_offsets > MAX_CONFIG) {
		errno = offsets && num_offsets ? E2BIG : EINVAL;
		return -1;
	}
	for (size_t i = 0; i < num_offsets; i++) {
		config->offsets[config->count] = offsets[i];
		if (settings)
			config->settings[config->count] = *settings;
		else
			config->settings[config->count] = (struct gpiod_line_settings){ 0 };
		config->count++;
	}
	return 0;
}

struct gpiod_request_config *gpiod_request_config_new(void)
{
	return fake_new(sizeof(struct gpiod_request_config));
}

void gpiod_request_config_free(struct gpiod_request_config *config)
{
	fake_free(config);
}

void gpiod_request_config_set_consumer(struct gpiod_request_config *config, const char *consumer)
{
	need(config);
	/* libgpiod 2 truncates to what the kernel keeps */
	snprintf(config->consumer, sizeof(config->consumer), "%s", consumer ? consumer : "");
}

/* ---- requests and events ---- */

void gpiod_line_request_release(struct gpiod_line_request *request)
{
	if (!request)
		return;
	close(request->fd);
	fake_gpiod2_hangup();
	fake.held = false;
	fake.seen.fd = -1;
	fake_free(request);
}

int gpiod_line_request_get_fd(struct gpiod_line_request *request)
{
	need(request);
	return request->fd;
}

static void event_from_record(struct gpiod_edge_event *ev, const struct gpio_v2_line_event *rec)
{
	ev->type = rec->id == GPIO_V2_LINE_EVENT_RISING_EDGE ? GPIOD_EDGE_EVENT_RISING_EDGE
							     : GPIOD_EDGE_EVENT_FALLING_EDGE;
	ev->ts_ns = rec->timestamp_ns;
	ev->offset = rec->offset;
	ev->seqno = rec->seqno;
	ev->line_seqno = rec->line_seqno;
}

/* As libgpiod 2: one read() of up to max_events records (at most the
 * buffer's capacity); fewer bytes than one record is EIO; blocks when
 * the fd does and none are pending. */
int gpiod_line_request_read_edge_events(struct gpiod_line_request *request, struct gpiod_edge_event_buffer *buffer,
					size_t max_events)
{
	need(request);
	need(buffer);
	struct gpio_v2_line_event rec[BUFFER_MAX];
	if (max_events > buffer->capacity)
		max_events = buffer->capacity;
	ssize_t got = read(request->fd, rec, max_events * sizeof(rec[0]));
	if (got < 0)
		return -1;
	if ((size_t)got < sizeof(rec[0])) {
		errno = EIO;
		return -1;
	}
	buffer->count = (size_t)got / sizeof(rec[0]);
	for (size_t i = 0; i < buffer->count; i++)
		event_from_record(&buffer->events[i], &rec[i]);
	return (int)buffer->count;
}

enum gpiod_edge_event_type gpiod_edge_event_get_event_type(struct gpiod_edge_event *event)
{
	need(event);
	return event->type;
}

uint64_t gpiod_edge_event_get_timestamp_ns(struct gpiod_edge_event *event)
{
	need(event);
	return event->ts_ns;
}

unsigned int gpiod_edge_event_get_line_offset(struct gpiod_edge_event *event)
{
	need(event);
	return event->offset;
}

unsigned long gpiod_edge_event_get_line_seqno(struct gpiod_edge_event *event)
{
	need(event);
	return event->line_seqno;
}

struct gpiod_edge_event_buffer *gpiod_edge_event_buffer_new(size_t capacity)
{
	struct gpiod_edge_event_buffer *buf = fake_new(sizeof(*buf));
	buf->capacity = capacity == 0 ? BUFFER_DEFAULT : capacity > BUFFER_MAX ? BUFFER_MAX : capacity;
	buf->events = calloc(buf->capacity, sizeof(buf->events[0]));
	if (!buf->events)
		abort();
	return buf;
}

void gpiod_edge_event_buffer_free(struct gpiod_edge_event_buffer *buffer)
{
	if (buffer)
		free(buffer->events);
	fake_free(buffer);
}

struct gpiod_edge_event *gpiod_edge_event_buffer_get_event(struct gpiod_edge_event_buffer *buffer, unsigned long index)
{
	need(buffer);
	if (index >= buffer->count) {
		errno = EINVAL;
		return NULL;
	}
	return &buffer->events[index];
}
