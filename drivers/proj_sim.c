/* The simulated projector, host side: the projector vtable implemented the
 * way the USB driver will, by encoding control requests and bulk records
 * with projwire, except that the bytes go to the in-process device model of
 * proj_sim_dev.c instead of libusb.
 *
 * Unplug faults (sim_faults "unplug=T+R") take the device model away at T,
 * buffers and all, and put a new one (dark, empty) in its place R seconds
 * later, reported through gone() and arrived() as the USB driver reports a
 * real unplug. One epoll fd holds the device's fd and the plug timer. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "log.h"
#include "proj_sim_dev.h"
#include "projector.h"
#include "projwire.h"
#include "sim_rotor.h"

/* Bulk OUT transfer size: what the USB driver will submit per transfer. */
#define BULK_CHUNK (64 * 1024)

struct plug_event {
	int64_t at; /* rotor clock */
	bool in;    /* plugged in, else unplugged */
};

struct proj_sim {
	struct projector base;
	struct sim_rotor *rotor;
	struct proj_sim_config cfg;
	struct proj_simdev *dev; /* NULL while unplugged */
	struct projwire_info info;
	uint8_t *wire; /* encode buffer, grown as needed */
	size_t wire_cap;
	struct projwire_delta plan; /* the upload being written */
	uint64_t bytes_sent, device_errors, arrivals;
	int epfd, plug_fd;
	struct plug_event plugs[2 * SIM_FAULTS_MAX_EVENTS];
	uint32_t nplugs, next_plug;
};

static const struct projector_impl sim_impl;

/* One control transfer; a stalled request is turned back into the errno
 * the device gives in GET_STATUS.last_error. */
static int control(struct proj_sim *s, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX], in[PROJWIRE_CTRL_DATA_MAX];
	if (!s->dev)
		return -ENODEV;
	size_t len = projwire_ctrl_encode(c, 0, setup, data);
	int r = proj_simdev_control(s->dev, setup, data, len, reply ? reply : in, sizeof(in));
	if (r != -EPIPE)
		return r;
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	projwire_ctrl_encode(&get, 0, setup, data);
	r = proj_simdev_control(s->dev, setup, NULL, 0, in, sizeof(in));
	if (r < 0 || projwire_status_decode(in, (size_t)r, &st) < 0)
		return -EIO;
	return projwire_error_to_errno(st.last_error);
}

static int get_status(struct proj_sim *s, struct projwire_status *st)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_STATUS };
	int r = control(s, &c, in);
	if (r < 0)
		return r;
	return projwire_status_decode(in, (size_t)r, st);
}

static int sim_get_info(struct projector *p, struct projector_info *out)
{
	struct proj_sim *s = (struct proj_sim *)p;
	memset(out, 0, sizeof(*out));
	if (!s->dev)
		return -ENODEV;
	strcpy(out->name, "sim");
	projwire_info_to_geometry(&s->info, &out->geom);
	out->buffers = s->info.buffers;
	out->link_bytes_per_sec = s->info.link_bytes_per_sec;
	out->half_turn_swaps = projwire_info_half_turn_swaps(&s->info);
	return 0;
}

static int sim_blank(struct projector *p, bool blank)
{
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_BLANK, .blank = blank };
	return control((struct proj_sim *)p, &c, NULL);
}

static int sim_set_timing(struct projector *p, int64_t period_ns, int64_t index_ns)
{
	if (period_ns <= 0)
		return -EINVAL;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_TIMING };
	c.timing = (struct projwire_timing){ (uint64_t)period_ns, index_ns, now_ns() };
	return control((struct proj_sim *)p, &c, NULL);
}

static bool volume_fits(const struct proj_sim *s, const struct volume *vol)
{
	struct geometry g;
	projwire_info_to_geometry(&s->info, &g);
	return vol->geom.width == g.width && vol->geom.height == g.height &&
	       vol->image_count == s->info.images_per_volume;
}

static int sim_upload(struct projector *p, uint32_t buffer, const struct volume *vol, const struct volume *base,
		      const uint8_t *differ)
{
	struct proj_sim *s = (struct proj_sim *)p;
	struct projwire_status st;
	if (!s->dev)
		return -ENODEV;
	if (buffer >= s->info.buffers || !volume_fits(s, vol))
		return -EINVAL;
	/* The device would refuse too, but only by an event after the bytes
	 * went out; asking first gives the caller a synchronous answer. */
	int r = get_status(s, &st);
	if (r < 0)
		return r;
	if (buffer == st.shown || buffer == st.pending)
		return -EBUSY;
	size_t size;
	if ((r = projwire_upload_plan(vol, base, differ, &s->plan, &size)) < 0)
		return r;
	if (size > s->wire_cap) {
		uint8_t *w = realloc(s->wire, size);
		if (!w)
			return -ENOMEM;
		s->wire = w;
		s->wire_cap = size;
	}
	size_t len = projwire_upload_encode(vol, base, &s->plan, buffer, s->wire);
	for (size_t off = 0; off < len; off += BULK_CHUNK)
		proj_simdev_bulk_out(s->dev, s->wire + off, len - off < BULK_CHUNK ? len - off : BULK_CHUNK);
	s->bytes_sent += len;
	return (int)len;
}

static int swap(struct proj_sim *s, uint32_t buffer, bool half)
{
	struct projwire_ctrl c = { .request = half ? PROJWIRE_REQ_SWAP_HALF : PROJWIRE_REQ_SWAP, .buffer = buffer };
	if (!s->dev)
		return -ENODEV;
	if (buffer >= s->info.buffers)
		return -EINVAL;
	return control(s, &c, NULL);
}

static int sim_swap(struct projector *p, uint32_t buffer)
{
	return swap((struct proj_sim *)p, buffer, false);
}

/* SWAP_HALF only to a device that takes it (section 1 of the protocol). */
static int sim_swap_half(struct projector *p, uint32_t buffer)
{
	struct proj_sim *s = (struct proj_sim *)p;
	return swap(s, buffer, s->dev && projwire_info_half_turn_swaps(&s->info));
}

static int sim_get_fd(struct projector *p)
{
	return ((struct proj_sim *)p)->epfd;
}

static void handle_event(struct proj_sim *s, const struct projwire_event *ev)
{
	const struct projector_listener *l = s->base.listener;
	if (ev->type == PROJWIRE_EV_SWAPPED) {
		bool half = ev->boundary & PROJWIRE_SWAPPED_HALF_TURN;
		if (l && l->swapped_at)
			l->swapped_at(s->base.listener_data, ev->buffer, ev->time_ns, ev->seq, half);
		else if (l && l->swapped)
			l->swapped(s->base.listener_data, ev->buffer, ev->time_ns, ev->seq);
		return;
	}
	s->device_errors++;
	if (l && l->error)
		l->error(s->base.listener_data, ev->buffer, projwire_error_to_errno(ev->error));
	log_warn("sim projector: device error %u on buffer %d (volume %llu)", (unsigned)ev->error,
		 ev->buffer == PROJWIRE_NO_BUFFER ? -1 : (int)ev->buffer, (unsigned long long)ev->seq);
}

static int attach(struct proj_sim *s);
static void detach(struct proj_sim *s);

/* The plug timer: the next plug event, or off. */
static int arm_plug(struct proj_sim *s)
{
	struct itimerspec its = { 0 };
	if (s->next_plug < s->nplugs) {
		int64_t at = s->plugs[s->next_plug].at;
		at = at > 0 ? at : 1; /* 0 would disarm */
		its.it_value = (struct timespec){ at / 1000000000, at % 1000000000 };
	}
	return timerfd_settime(s->plug_fd, TFD_TIMER_ABSTIME, &its, NULL) < 0 ? -errno : 0;
}

/* Carries out the plug events that are due; the listener hears of them. */
static int handle_plugs(struct proj_sim *s)
{
	uint64_t n;
	if (read(s->plug_fd, &n, sizeof(n)) < 0 && errno != EAGAIN)
		return -errno;
	const struct projector_listener *l = s->base.listener;
	int64_t now = sim_rotor_now(s->rotor);
	for (; s->next_plug < s->nplugs && s->plugs[s->next_plug].at <= now; s->next_plug++) {
		bool in = s->plugs[s->next_plug].in;
		if (in == (s->dev != NULL))
			continue;
		if (!in) {
			detach(s);
			log_warn("sim projector: unplugged");
			if (l && l->gone)
				l->gone(s->base.listener_data, -ENODEV);
			continue;
		}
		int r = attach(s);
		if (r < 0)
			return r;
		log_info("sim projector: plugged in");
		if (l && l->arrived)
			l->arrived(s->base.listener_data);
	}
	return arm_plug(s);
}

static int sim_dispatch(struct projector *p)
{
	struct proj_sim *s = (struct proj_sim *)p;
	int r = handle_plugs(s);
	if (r < 0 || !s->dev)
		return r;
	r = proj_simdev_dispatch(s->dev);
	if (r < 0)
		return r;
	uint8_t in[16 * PROJWIRE_EVENT_MAX];
	size_t len;
	/* Like an IN transfer completing: several whole events at a time. */
	while ((len = proj_simdev_bulk_in(s->dev, in, sizeof(in))) > 0) {
		size_t off = 0;
		struct projwire_event ev;
		while (off < len && (r = projwire_event_decode(in + off, len - off, &ev)) > 0) {
			handle_event(s, &ev);
			off += (size_t)r;
		}
		if (off != len)
			return -EPROTO; /* a device speaking nonsense */
	}
	return 0;
}

static const struct volume *sim_shown(struct projector *p)
{
	struct proj_sim *s = (struct proj_sim *)p;
	return s->dev ? proj_simdev_shown(s->dev) : NULL;
}

static void sim_get_stats(struct projector *p, struct projector_stats *out)
{
	struct proj_sim *s = (struct proj_sim *)p;
	struct projwire_status st;
	*out = (struct projector_stats){
		.present = s->dev != NULL,
		.bytes_sent = s->bytes_sent,
		.device_errors = s->device_errors,
		.arrivals = s->arrivals,
		.angle_err_p50 = -1,
		.angle_err_p99 = -1,
		.angle_err_max = -1,
	};
	if (!s->dev)
		return;
	struct proj_simdev_stats ds;
	proj_simdev_get_stats(s->dev, &ds);
	out->angle_err_p50 = ds.angle_err_p50;
	out->angle_err_p99 = ds.angle_err_p99;
	out->angle_err_max = ds.angle_err_max;
	if (get_status(s, &st) < 0)
		return;
	out->revolutions = st.revolutions;
	out->swaps = st.swaps;
	out->underruns = st.underruns;
}

static void sim_destroy(struct projector *p)
{
	struct proj_sim *s = (struct proj_sim *)p;
	sim_blank(p, true); /* dark on every exit */
	proj_simdev_destroy(s->dev);
	if (s->epfd >= 0)
		close(s->epfd);
	if (s->plug_fd >= 0)
		close(s->plug_fd);
	free(s->wire);
	projwire_delta_free(&s->plan);
	free(s);
}

static const struct projector_impl sim_impl = {
	.name = "sim",
	.get_info = sim_get_info,
	.blank = sim_blank,
	.set_timing = sim_set_timing,
	.upload = sim_upload,
	.swap = sim_swap,
	.swap_half = sim_swap_half,
	.get_fd = sim_get_fd,
	.dispatch = sim_dispatch,
	.shown = sim_shown,
	.get_stats = sim_get_stats,
	.destroy = sim_destroy,
};

/* A new device model, learnt as the USB driver learns one: from
 * GET_INFO. */
static int attach(struct proj_sim *s)
{
	const struct proj_sim_config *cfg = &s->cfg;
	s->dev = proj_simdev_create(s->rotor, &cfg->geom, cfg->buffers, cfg->link_bytes_per_sec);
	if (!s->dev)
		return -errno;
	if (cfg->version_minor)
		proj_simdev_set_minor(s->dev, cfg->version_minor);
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_INFO };
	int r = control(s, &c, in);
	if (r >= 0)
		r = projwire_info_decode(in, (size_t)r, &s->info);
	struct epoll_event ev = { .events = EPOLLIN };
	if (r >= 0 && epoll_ctl(s->epfd, EPOLL_CTL_ADD, proj_simdev_get_fd(s->dev), &ev) < 0)
		r = -errno;
	if (r < 0) {
		proj_simdev_destroy(s->dev);
		s->dev = NULL;
		return r;
	}
	s->arrivals++;
	return 0;
}

static void detach(struct proj_sim *s)
{
	epoll_ctl(s->epfd, EPOLL_CTL_DEL, proj_simdev_get_fd(s->dev), NULL);
	proj_simdev_destroy(s->dev);
	s->dev = NULL;
}

/* The unplug faults of cfg as plug events on the rotor's clock. */
static void plan_plugs(struct proj_sim *s, const struct sim_faults *f)
{
	for (uint32_t i = 0; f && i < f->nevents && i < SIM_FAULTS_MAX_EVENTS; i++) {
		const struct sim_fault_event *ev = &f->events[i];
		if (ev->kind != SIM_FAULT_UNPLUG)
			continue;
		int64_t at = sim_rotor_start(s->rotor) + llround(ev->at * 1e9);
		s->plugs[s->nplugs++] = (struct plug_event){ at, false };
		if (ev->restart >= 0)
			s->plugs[s->nplugs++] = (struct plug_event){ at + llround(ev->restart * 1e9), true };
	}
	for (uint32_t i = 1; i < s->nplugs; i++) /* insertion sort by time, stable */
		for (uint32_t j = i; j > 0 && s->plugs[j].at < s->plugs[j - 1].at; j--) {
			struct plug_event t = s->plugs[j];
			s->plugs[j] = s->plugs[j - 1];
			s->plugs[j - 1] = t;
		}
}

static int sim_setup(struct proj_sim *s)
{
	s->epfd = epoll_create1(EPOLL_CLOEXEC);
	s->plug_fd = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC | TFD_NONBLOCK);
	if (s->epfd < 0 || s->plug_fd < 0)
		return -errno;
	struct epoll_event ev = { .events = EPOLLIN };
	if (epoll_ctl(s->epfd, EPOLL_CTL_ADD, s->plug_fd, &ev) < 0)
		return -errno;
	plan_plugs(s, s->cfg.faults);
	int r = attach(s);
	if (r < 0)
		return r;
	/* "unplug=0...": no projector at start, and nobody to tell. */
	for (; s->next_plug < s->nplugs && s->plugs[s->next_plug].at <= sim_rotor_start(s->rotor); s->next_plug++)
		if (!s->plugs[s->next_plug].in && s->dev)
			detach(s);
	return arm_plug(s);
}

struct projector *proj_sim_create(struct sim_rotor *rotor, const struct proj_sim_config *cfg,
				  const struct projector_listener *listener, void *data)
{
	struct proj_sim *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &sim_impl;
	s->base.listener = listener;
	s->base.listener_data = data;
	s->rotor = rotor;
	s->cfg = *cfg;
	s->epfd = s->plug_fd = -1;
	int r = cfg->version_minor > PROJWIRE_VERSION_MINOR ? -EINVAL : sim_setup(s);
	if (r < 0) {
		s->cfg.faults = NULL;
		sim_destroy(&s->base);
		errno = -r;
		return NULL;
	}
	s->cfg.faults = NULL; /* the caller's, not needed after planning */
	return &s->base;
}

void proj_sim_get_stats(struct projector *p, struct proj_sim_stats *out)
{
	struct projwire_status st;
	memset(out, 0, sizeof(*out));
	if (p->impl != &sim_impl || get_status((struct proj_sim *)p, &st) < 0)
		return;
	out->revolutions = st.revolutions;
	out->swaps = st.swaps;
	out->underruns = st.underruns;
	out->bytes = st.bytes;
	struct proj_simdev_stats ds;
	proj_simdev_get_stats(((struct proj_sim *)p)->dev, &ds);
	out->angle_err_p50 = ds.angle_err_p50;
	out->angle_err_p99 = ds.angle_err_p99;
	out->angle_err_max = ds.angle_err_max;
	out->stalls = ds.stalls;
	out->max_dark_delay_ns = ds.max_dark_delay_ns;
	out->lit_stopped_ns = ds.lit_stopped_ns;
	out->lit_untimed_ns = ds.lit_untimed_ns;
	out->watchdog_blanks = ds.watchdog_blanks;
}
