/* The simulated projector's device model (see proj_sim_dev.h).
 *
 * Time is the rotor's: a swap takes effect at a true revolution start (a
 * SWAP_HALF one at a true half-turn start: a revolution start or the time
 * the rotor is half a turn past one), the first one after the request at
 * which the buffer's data has fully crossed the modelled link. Work is
 * done lazily at dispatch, at the exact boundary times, so a late dispatch
 * changes no outcome. */
#include "proj_sim_dev.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "log.h"
#include "sim_rotor.h"

#define EVENT_QUEUE (64 * PROJWIRE_EVENT_MAX)
#define WATCHDOG_NS 2000000000LL /* dark without a control request this long */

struct simdev_buffer {
	struct volume *vol;
	enum projwire_buffer_state state;
	int64_t ready_ns; /* READY: when its last byte crossed the link */
};

struct proj_simdev {
	struct sim_rotor *rotor;
	struct geometry geom;
	uint32_t nbuf;
	uint8_t minor; /* the protocol version 1.minor it speaks */
	uint64_t link_rate;
	struct simdev_buffer buf[PROJWIRE_MAX_BUFFERS];
	struct projwire_decoder *dec;
	int fd;

	bool blanked, timing_set;
	struct projwire_timing timing;
	uint32_t shown, pending;
	bool pending_half;    /* SWAP_HALF: half-turn starts count as well */
	int64_t pending_from; /* the next boundary to consider is at or after this */
	bool pending_missed;  /* this swap already counted an underrun */
	int64_t link_free;    /* when the link is done with the bytes sent so far */

	int64_t rev0;      /* rotor revolution at creation */
	int64_t last_ctrl; /* when the last control request came */
	struct proj_meter *meter;
	uint64_t watchdog_blanks;
	uint64_t swaps, underruns, bytes;
	uint32_t last_error;
	uint64_t events_dropped;

	uint8_t events[EVENT_QUEUE];
	size_t events_len;
};

static void queue_event(struct proj_simdev *dev, const struct projwire_event *ev)
{
	if (dev->events_len + PROJWIRE_EVENT_MAX > EVENT_QUEUE) {
		dev->events_dropped++; /* a host that never reads loses events, as on USB */
		return;
	}
	dev->events_len += projwire_event_encode(ev, dev->events + dev->events_len);
}

static void report_error(struct proj_simdev *dev, int err, uint32_t buffer)
{
	dev->last_error = projwire_error_from_errno(err);
	struct projwire_event ev = { .type = PROJWIRE_EV_ERROR, .buffer = buffer, .error = dev->last_error };
	if (buffer != PROJWIRE_NO_BUFFER)
		ev.seq = dev->buf[buffer].vol->seq;
	queue_event(dev, &ev);
}

static struct volume *sink_begin(void *data, uint32_t buffer, uint64_t seq, const uint64_t *base_seq, int *err)
{
	struct proj_simdev *dev = data;
	*err = 0;
	if (buffer == dev->shown || buffer == dev->pending)
		*err = -EBUSY;
	else if (base_seq && (dev->buf[buffer].state != PROJWIRE_BUF_READY || dev->buf[buffer].vol->seq != *base_seq))
		*err = -ENODATA; /* a delta on content the buffer does not hold */
	if (*err) {
		report_error(dev, *err, buffer);
		return NULL;
	}
	dev->buf[buffer].state = PROJWIRE_BUF_WRITING;
	return dev->buf[buffer].vol;
}

static void sink_end(void *data, uint32_t buffer, int err)
{
	struct proj_simdev *dev = data;
	if (buffer == PROJWIRE_NO_BUFFER) {
		report_error(dev, err, buffer);
		return;
	}
	struct simdev_buffer *b = &dev->buf[buffer];
	if (!err) {
		b->state = PROJWIRE_BUF_READY;
		b->ready_ns = dev->link_free;
		b->vol->shown_ns = 0;
		return;
	}
	b->state = PROJWIRE_BUF_INVALID;
	if (dev->pending == buffer)
		dev->pending = PROJWIRE_NO_BUFFER; /* never show a broken volume */
	report_error(dev, err, buffer);
}

static const struct projwire_sink sink_impl = { .begin = sink_begin, .end = sink_end };

static int arm(struct proj_simdev *dev, int64_t when)
{
	/* 0 disarms; any other time in the past fires at once. */
	struct itimerspec its = {
		.it_value = { .tv_sec = when / 1000000000, .tv_nsec = when % 1000000000 },
	};
	return timerfd_settime(dev->fd, TFD_TIMER_ABSTIME, &its, NULL) < 0 ? -errno : 0;
}

/* The first boundary the pending swap may take at or after t: a revolution
 * start, or for SWAP_HALF also the middle of a revolution (*half). */
static int64_t next_boundary(const struct proj_simdev *dev, int64_t t, bool *half)
{
	*half = false;
	if (dev->pending_half)
		return sim_rotor_next_half_turn(dev->rotor, t, half);
	return sim_rotor_next_index(dev->rotor, t);
}

/* The next time dispatch has work: the boundary a pending swap can first
 * use, or at once when events wait. */
static int rearm(struct proj_simdev *dev)
{
	if (dev->events_len)
		return arm(dev, 1);
	if (dev->pending == PROJWIRE_NO_BUFFER)
		return arm(dev, 0);
	const struct simdev_buffer *b = &dev->buf[dev->pending];
	int64_t from = dev->pending_from;
	if (b->state == PROJWIRE_BUF_READY && b->ready_ns > from)
		from = b->ready_ns;
	bool half;
	return arm(dev, next_boundary(dev, from, &half));
}

struct proj_simdev *proj_simdev_create(struct sim_rotor *rotor, const struct geometry *geom, uint32_t buffers,
				       uint64_t link_bytes_per_sec)
{
	if (geometry_validate(geom) < 0 || buffers < 2 || buffers > PROJWIRE_MAX_BUFFERS) {
		errno = EINVAL;
		return NULL;
	}
	struct proj_simdev *dev = calloc(1, sizeof(*dev));
	if (!dev)
		return NULL;
	dev->rotor = rotor;
	dev->geom = *geom;
	dev->nbuf = buffers;
	dev->minor = PROJWIRE_VERSION_MINOR;
	dev->link_rate = link_bytes_per_sec;
	dev->blanked = true; /* dark until told otherwise */
	dev->shown = dev->pending = PROJWIRE_NO_BUFFER;
	int64_t now = sim_rotor_now(rotor);
	dev->rev0 = sim_rotor_revolution(rotor, now);
	dev->last_ctrl = now;
	dev->fd = -1;
	for (uint32_t i = 0; i < buffers; i++)
		if (!(dev->buf[i].vol = volume_create(geom)))
			goto err_volumes;
	dev->dec = projwire_decoder_create(geom, buffers, 0, &sink_impl, dev);
	if (!dev->dec)
		goto err_volumes;
	dev->meter = proj_meter_create(rotor, geom->images_per_rev, geom->rpm, now);
	if (!dev->meter)
		goto err_volumes;
	dev->fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
	if (dev->fd < 0)
		goto err_volumes;
	return dev;

err_volumes:
	proj_simdev_destroy(dev); /* takes partial state; keeps errno */
	return NULL;
}

void proj_simdev_destroy(struct proj_simdev *dev)
{
	if (!dev)
		return;
	int saved = errno;
	if (dev->fd >= 0)
		close(dev->fd);
	projwire_decoder_destroy(dev->dec);
	proj_meter_destroy(dev->meter);
	for (uint32_t i = 0; i < dev->nbuf; i++)
		volume_destroy(dev->buf[i].vol);
	free(dev);
	errno = saved;
}

/* The meter over the time since its last run, up to t, in the device's
 * present state. */
static void meter_to(struct proj_simdev *dev, int64_t t)
{
	bool lit = !dev->blanked && dev->shown != PROJWIRE_NO_BUFFER;
	proj_meter_run(dev->meter, t, lit, dev->timing_set ? &dev->timing : NULL);
}

/* Brings the watchdog and the meter up to until. Called before anything
 * changes what the device shows, so the meter sees each state over
 * exactly the time it held. */
static void advance(struct proj_simdev *dev, int64_t until)
{
	int64_t dog = dev->last_ctrl + WATCHDOG_NS;
	if (!dev->blanked && dog <= until) {
		meter_to(dev, dog);
		dev->blanked = true; /* the host is gone or hung: dark (section 7) */
		dev->watchdog_blanks++;
	}
	meter_to(dev, until);
}

static void run_pending(struct proj_simdev *dev, int64_t now);

/* Swaps due and watchdog and meter, up to now. */
static void catch_up(struct proj_simdev *dev, int64_t now)
{
	run_pending(dev, now);
	advance(dev, now);
}

static void fill_status(const struct proj_simdev *dev, struct projwire_status *st)
{
	memset(st, 0, sizeof(*st));
	st->flags = (dev->blanked ? PROJWIRE_STATUS_BLANKED : 0) | (dev->timing_set ? PROJWIRE_STATUS_TIMING : 0);
	if (dev->pending != PROJWIRE_NO_BUFFER)
		st->flags |= PROJWIRE_STATUS_PENDING | (dev->pending_half ? PROJWIRE_STATUS_PENDING_HALF : 0);
	st->shown = dev->shown;
	st->pending = dev->pending;
	st->revolutions = (uint64_t)(sim_rotor_revolution(dev->rotor, sim_rotor_now(dev->rotor)) - dev->rev0);
	st->swaps = dev->swaps;
	st->underruns = dev->underruns;
	st->bytes = dev->bytes;
	st->last_error = dev->last_error;
	struct projwire_decoder_stats ds;
	projwire_decoder_get_stats(dev->dec, &ds);
	st->decode_errors = (uint32_t)ds.errors;
	for (uint32_t i = 0; i < dev->nbuf; i++)
		st->buffer_state[i] = (uint8_t)dev->buf[i].state;
}

static int do_swap(struct proj_simdev *dev, uint32_t buffer, bool half)
{
	if (buffer >= dev->nbuf)
		return -EINVAL;
	if (buffer == dev->shown || dev->pending != PROJWIRE_NO_BUFFER)
		return -EBUSY;
	enum projwire_buffer_state s = dev->buf[buffer].state;
	/* WRITING is fine: on USB the request can overtake its bulk data. */
	if (s != PROJWIRE_BUF_READY && s != PROJWIRE_BUF_WRITING)
		return -ENODATA;
	dev->pending = buffer;
	dev->pending_half = half;
	dev->pending_from = sim_rotor_now(dev->rotor);
	dev->pending_missed = false;
	return rearm(dev);
}

/* Carries out a request; returns the reply length or negative errno. */
static int handle_request(struct proj_simdev *dev, const struct projwire_ctrl *c, uint8_t *in, size_t in_cap)
{
	struct projwire_info info;
	struct projwire_status st;
	switch (c->request) {
	case PROJWIRE_REQ_GET_INFO:
		if (in_cap < PROJWIRE_INFO_SIZE)
			return -EINVAL;
		projwire_info_from_geometry(&info, &dev->geom, dev->nbuf, dev->link_rate);
		info.version_minor = dev->minor;
		projwire_info_encode(&info, in);
		return PROJWIRE_INFO_SIZE;
	case PROJWIRE_REQ_GET_STATUS:
		if (in_cap < PROJWIRE_STATUS_SIZE)
			return -EINVAL;
		fill_status(dev, &st);
		projwire_status_encode(&st, in);
		return PROJWIRE_STATUS_SIZE;
	case PROJWIRE_REQ_SET_BLANK:
		dev->blanked = c->blank;
		return 0;
	case PROJWIRE_REQ_SET_TIMING:
		/* Slices are placed by it (the meter); swaps still happen at
		 * the rotor's true revolution starts. */
		dev->timing = c->timing;
		dev->timing_set = true;
		return 0;
	case PROJWIRE_REQ_SWAP:
		return do_swap(dev, c->buffer, false);
	case PROJWIRE_REQ_RESET_STREAM:
		projwire_decoder_reset(dev->dec);
		return 0;
	case PROJWIRE_REQ_SWAP_HALF:
		/* Meaningless without a mirrored half turn. */
		if (!dev->geom.mirrored)
			return -EOPNOTSUPP;
		return do_swap(dev, c->buffer, true);
	}
	return -EOPNOTSUPP;
}

int proj_simdev_control(struct proj_simdev *dev, const uint8_t setup[PROJWIRE_SETUP_SIZE], const uint8_t *out,
			size_t out_len, uint8_t *in, size_t in_cap)
{
	struct projwire_ctrl c;
	int64_t now = sim_rotor_now(dev->rotor);
	catch_up(dev, now);
	dev->last_ctrl = now; /* even a bad request shows the host is alive */
	/* A request of a later minor version is unknown, however it is
	 * formed, as to a device of that age. */
	int r = setup[1] == PROJWIRE_REQ_SWAP_HALF && dev->minor < 2
			? -EOPNOTSUPP
			: projwire_ctrl_decode(setup, out, out_len, &c);
	if (r >= 0)
		r = handle_request(dev, &c, in, in_cap);
	if (r < 0) {
		dev->last_error = projwire_error_from_errno(r);
		return -EPIPE;
	}
	/* Reading the status is how a host learns why the last request
	 * stalled, so it must not clear that. */
	return r;
}

void proj_simdev_bulk_out(struct proj_simdev *dev, const uint8_t *buf, size_t len)
{
	int64_t now = sim_rotor_now(dev->rotor);
	if (dev->link_free < now)
		dev->link_free = now;
	if (dev->link_rate)
		dev->link_free += (int64_t)((double)len * 1e9 / (double)dev->link_rate);
	dev->bytes += len;
	projwire_decoder_feed(dev->dec, buf, len);
	rearm(dev);
}

size_t proj_simdev_bulk_in(struct proj_simdev *dev, uint8_t *buf, size_t cap)
{
	size_t n = 0;
	struct projwire_event ev;
	/* Whole events only, as a device packs them into IN transfers. */
	for (;;) {
		int r = projwire_event_decode(dev->events + n, dev->events_len - n, &ev);
		if (r <= 0 || n + (size_t)r > cap)
			break;
		n += (size_t)r;
	}
	memcpy(buf, dev->events, n);
	memmove(dev->events, dev->events + n, dev->events_len - n);
	dev->events_len -= n;
	return n;
}

void proj_simdev_set_minor(struct proj_simdev *dev, uint8_t minor)
{
	dev->minor = minor;
}

int proj_simdev_get_fd(struct proj_simdev *dev)
{
	return dev->fd;
}

static void show(struct proj_simdev *dev, uint32_t buffer, int64_t start, bool half)
{
	struct volume *vol = dev->buf[buffer].vol;
	dev->shown = buffer;
	dev->pending = PROJWIRE_NO_BUFFER;
	dev->swaps++;
	if (!vol->shown_ns)
		vol->shown_ns = (uint64_t)start;
	struct projwire_event ev = {
		.type = PROJWIRE_EV_SWAPPED,
		.buffer = buffer,
		.time_ns = start,
		.seq = vol->seq,
		.boundary = half ? PROJWIRE_SWAPPED_HALF_TURN : 0,
	};
	queue_event(dev, &ev);
}

/* Walks the boundaries (revolution starts; half-turn starts for SWAP_HALF)
 * since the swap request up to now. */
static void run_pending(struct proj_simdev *dev, int64_t now)
{
	while (dev->pending != PROJWIRE_NO_BUFFER) {
		const struct simdev_buffer *b = &dev->buf[dev->pending];
		bool half;
		int64_t start = next_boundary(dev, dev->pending_from, &half);
		if (start > now)
			return;
		if (b->state == PROJWIRE_BUF_READY && b->ready_ns <= start) {
			advance(dev, start);
			show(dev, dev->pending, start, half);
			return;
		}
		if (!dev->pending_missed) {
			dev->pending_missed = true;
			dev->underruns++;
		}
		/* Skip straight to the first start the data can make. */
		dev->pending_from = start + 1;
		if (b->state == PROJWIRE_BUF_READY && b->ready_ns > dev->pending_from)
			dev->pending_from = b->ready_ns;
	}
}

int proj_simdev_dispatch(struct proj_simdev *dev)
{
	uint64_t expirations;
	if (read(dev->fd, &expirations, sizeof(expirations)) < 0 && errno != EAGAIN)
		return -errno;
	catch_up(dev, sim_rotor_now(dev->rotor));
	return rearm(dev);
}

const struct volume *proj_simdev_shown(struct proj_simdev *dev)
{
	catch_up(dev, sim_rotor_now(dev->rotor));
	if (dev->blanked || dev->shown == PROJWIRE_NO_BUFFER)
		return NULL;
	return dev->buf[dev->shown].vol;
}

void proj_simdev_get_stats(struct proj_simdev *dev, struct proj_simdev_stats *out)
{
	catch_up(dev, sim_rotor_now(dev->rotor));
	out->watchdog_blanks = dev->watchdog_blanks;
	proj_meter_get(dev->meter, out);
}
