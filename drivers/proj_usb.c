/* The USB projector: the projector vtable over the USB transport
 * (usb_transport.h), speaking the wire protocol of proto/projector.md
 * through projwire exactly as proj_sim.c does with the in-process device
 * model: setting a device up, control requests, uploads, swaps, events and
 * the keepalive.
 *
 * Threading and re-entrancy: everything runs on the caller's event loop
 * thread. The transport's received() and sent() callbacks run inside any
 * libusb call that handles events (a synchronous control request does), so
 * they only record what happened; dispatch() acts on it and is the only
 * place the projector listener's callbacks run from.
 *
 * Lifetime of a device: the transport finds and opens it and calls
 * setup_device() (transport_setup); a fault (unplug, transfer error,
 * malformed event) makes the transport drop it, and its gone() is passed
 * on. While nothing is open the transport looks for a device again. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "le.h"
#include "log.h"
#include "proj_usb_priv.h"
#include "projector.h"
#include "projwire.h"
#include "usb_transport.h"

#define KEEPALIVE_NS 500000000LL /* the device darkens after 2 s of silence */
#define STATUS_DARK_NS 1000000000LL
#define EVQ_SIZE 4096

struct proj_usb {
	struct projector base;
	struct proj_usb_config cfg;
	struct usb_transport *t;

	/* The device, while the transport holds one. */
	struct projwire_info info;
	struct projwire_status status; /* latest GET_STATUS */
	bool lit;
	int64_t next_status;

	/* Buffers as far as our requests and the device's events tell. */
	uint32_t shown, pending;
	bool pending_half; /* the pending swap is a SWAP_HALF one */
	bool swap_deferred;
	bool half_refused;                        /* the device stalled SWAP_HALF as unknown: SWAP only */
	uint64_t begin_end[PROJWIRE_MAX_BUFFERS]; /* stream position after its latest VOLUME_BEGIN */
	uint8_t evq[EVQ_SIZE];                    /* event bytes received, not yet handled */
	size_t evq_len;
	struct projwire_delta plan; /* the upload being written */

	uint64_t bytes_sent, device_errors, arrivals, gone;
};

static const struct projector_impl usb_impl;

/* ---- Control requests ---- */

static int ctrl_raw(struct proj_usb *u, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_setup s;
	projwire_ctrl_encode(c, usbt_interface(u->t), setup, data);
	projwire_setup_decode(setup, &s);
	bool in = s.request_type & USBT_REQUEST_IN;
	int r = usbt_control(u->t, s.request_type, s.request, s.value, s.index, in ? reply : data, s.length);
	if (r < 0)
		return r;
	return in ? r : 0; /* the reply length, or 0 as for requests without one */
}

/* One control request: the reply length or 0. A stall is turned into the
 * errno the device gives in GET_STATUS.last_error; any other failure is a
 * device fault. */
static int ctrl(struct proj_usb *u, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	if (!usbt_is_open(u->t))
		return -ENODEV;
	int r = ctrl_raw(u, c, reply ? reply : in);
	if (r != -EPIPE) {
		if (r < 0)
			usbt_set_fault(u->t, r);
		return r;
	}
	u->device_errors++;
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	r = ctrl_raw(u, &get, in);
	if (r < 0 || projwire_status_decode(in, (size_t)r, &st) < 0) {
		usbt_set_fault(u->t, r < 0 ? r : -EPROTO);
		return -EIO;
	}
	return projwire_error_to_errno(st.last_error);
}

static int get_status(struct proj_usb *u)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	int r = ctrl(u, &c, in);
	if (r < 0)
		return r;
	r = projwire_status_decode(in, (size_t)r, &st);
	if (r < 0) {
		usbt_set_fault(u->t, r);
		return r;
	}
	u->status = st;
	return 0;
}

/* ---- Setting a device up: the transport's listener ---- */

static void reset_state(struct proj_usb *u)
{
	u->shown = u->pending = PROJWIRE_NO_BUFFER;
	u->pending_half = u->swap_deferred = u->half_refused = false;
	memset(u->begin_end, 0, sizeof(u->begin_end));
	memset(&u->status, 0, sizeof(u->status));
	u->evq_len = 0;
	u->lit = false;
	u->next_status = now_ns() + STATUS_DARK_NS;
}

static bool geometry_same(const struct geometry *a, const struct geometry *b)
{
	return a->width == b->width && a->height == b->height && a->images_per_rev == b->images_per_rev &&
	       a->mirrored == b->mirrored;
}

/* GET_INFO and its checks. */
static int get_info(struct proj_usb *u, const char *path)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_INFO };
	int r = ctrl(u, &c, in);
	if (r < 0)
		return r;
	if ((r = projwire_info_decode(in, (size_t)r, &u->info)) < 0) {
		log_error("usb projector %s: bad GET_INFO reply (version %u.%u): %s", path, in[0], in[1], strerror(-r));
		return r;
	}
	struct geometry g;
	projwire_info_to_geometry(&u->info, &g);
	if (!geometry_same(&g, &u->cfg.geom)) {
		log_error("usb projector %s: refused: device is %ux%u, %u images/rev%s; configured %ux%u, %u%s", path,
			  g.width, g.height, g.images_per_rev, g.mirrored ? " mirrored" : "", u->cfg.geom.width,
			  u->cfg.geom.height, u->cfg.geom.images_per_rev, u->cfg.geom.mirrored ? " mirrored" : "");
		return -EMEDIUMTYPE;
	}
	return 0;
}

/* A device just opened: RESET_STREAM, GET_INFO and its checks, SET_BLANK 1. */
static int transport_setup(void *data, const char *path)
{
	struct proj_usb *u = data;
	reset_state(u);
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_RESET_STREAM };
	int r = ctrl(u, &c, NULL);
	if (r < 0 || (r = get_info(u, path)) < 0)
		return r;
	c = (struct projwire_ctrl){ .request = PROJWIRE_REQ_SET_BLANK, .blank = true };
	return ctrl(u, &c, NULL);
}

static void transport_opened(void *data, const char *path)
{
	struct proj_usb *u = data;
	u->arrivals++;
	log_info("usb projector %s: version %u.%u, %ux%u, %u images/rev, %u buffers, swaps at %s starts", path,
		 u->info.version_major, u->info.version_minor, u->info.width, u->info.height, u->info.images_per_rev,
		 u->info.buffers, projwire_info_half_turn_swaps(&u->info) ? "half-turn" : "revolution");
}

static void transport_arrived(void *data)
{
	struct proj_usb *u = data;
	const struct projector_listener *l = u->base.listener;
	if (l && l->arrived)
		l->arrived(u->base.listener_data);
}

static void transport_gone(void *data, int err)
{
	struct proj_usb *u = data;
	u->lit = false;
	u->evq_len = 0;
	u->gone++;
	const struct projector_listener *l = u->base.listener;
	if (l && l->gone)
		l->gone(u->base.listener_data, err);
}

/* Runs inside libusb's event handling: only queues the bytes. */
static void transport_received(void *data, const uint8_t *bytes, size_t n)
{
	struct proj_usb *u = data;
	if (u->evq_len + n > EVQ_SIZE) {
		log_warn("usb projector: event queue full, %zu bytes dropped", n);
		return;
	}
	memcpy(u->evq + u->evq_len, bytes, n);
	u->evq_len += n;
}

static void transport_sent(void *data, size_t n)
{
	((struct proj_usb *)data)->bytes_sent += (uint64_t)n;
}

static const struct usb_transport_listener transport_listener = {
	.setup = transport_setup,
	.opened = transport_opened,
	.arrived = transport_arrived,
	.gone = transport_gone,
	.received = transport_received,
	.sent = transport_sent,
};

/* ---- The projector interface ---- */

static int usb_get_info(struct projector *p, struct projector_info *out)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!usbt_is_ready(u->t))
		return -ENODEV;
	memset(out, 0, sizeof(*out));
	strcpy(out->name, "usb");
	projwire_info_to_geometry(&u->info, &out->geom);
	out->buffers = u->info.buffers;
	out->link_bytes_per_sec = u->info.link_bytes_per_sec;
	out->half_turn_swaps = projwire_info_half_turn_swaps(&u->info) && !u->half_refused;
	return 0;
}

static int usb_blank(struct projector *p, bool blank)
{
	struct proj_usb *u = (struct proj_usb *)p;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_BLANK, .blank = blank };
	if (!usbt_is_ready(u->t))
		return -ENODEV;
	int r = ctrl(u, &c, NULL);
	if (r < 0)
		return r;
	u->lit = !blank;
	if (u->lit && u->next_status > now_ns() + KEEPALIVE_NS)
		u->next_status = now_ns() + KEEPALIVE_NS;
	return 0;
}

static int usb_set_timing(struct projector *p, int64_t period_ns, int64_t index_ns)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!usbt_is_ready(u->t))
		return -ENODEV;
	if (period_ns <= 0)
		return -EINVAL;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_TIMING };
	c.timing = (struct projwire_timing){ (uint64_t)period_ns, index_ns, now_ns() };
	return ctrl(u, &c, NULL);
}

static bool volume_fits(const struct proj_usb *u, const struct volume *vol)
{
	return vol->geom.width == u->info.width && vol->geom.height == u->info.height &&
	       vol->image_count == u->info.images_per_volume;
}

static int usb_upload(struct projector *p, uint32_t buffer, const struct volume *vol, const struct volume *base,
		      const uint8_t *differ)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!usbt_is_ready(u->t))
		return -ENODEV;
	if (buffer >= u->info.buffers || !volume_fits(u, vol))
		return -EINVAL;
	/* Known without asking the device: we asked for the pending swap
	 * and its SWAPPED event told us what is shown. */
	if (buffer == u->shown || buffer == u->pending)
		return -EBUSY;
	if (u->info.version_minor < 1)
		base = NULL; /* a 1.0 device rejects delta records */
	size_t size;
	int r = projwire_upload_plan(vol, base, differ, &u->plan, &size);
	if (r < 0)
		return r;
	uint8_t *rec = usbt_out_reserve(u->t, size);
	if (!rec)
		return -ENOMEM;
	size_t len = projwire_upload_encode(vol, base, &u->plan, buffer, rec);
	/* Where its first record (VOLUME_BEGIN) ends: from then on the device
	 * holds the buffer as being written and accepts a swap to it. */
	u->begin_end[buffer] = usbt_out_queued(u->t) + PROJWIRE_HEADER_SIZE + le_get32(rec + 4);
	usbt_out_commit(u->t, len);
	return (int)len;
}

static int send_swap(struct proj_usb *u)
{
	struct projwire_ctrl c = { .request = u->pending_half ? PROJWIRE_REQ_SWAP_HALF : PROJWIRE_REQ_SWAP,
				   .buffer = u->pending };
	int r = ctrl(u, &c, NULL);
	if (r == -EOPNOTSUPP && u->pending_half) {
		/* A device that says 1.2 and mirrored must take it; one that
		 * does not gets revolution swaps from now on. */
		log_warn("usb projector: device refused SWAP_HALF; swapping at revolution starts only");
		u->half_refused = true;
		u->pending_half = false;
		c.request = PROJWIRE_REQ_SWAP;
		r = ctrl(u, &c, NULL);
	}
	if (r < 0)
		u->pending = PROJWIRE_NO_BUFFER;
	return r;
}

/* A SWAP may overtake the bulk data of its volume, but not the
 * VOLUME_BEGIN: before that the device holds the buffer's old contents and
 * would show those. So the request waits until that record is through. */
static int swap(struct proj_usb *u, uint32_t buffer, bool half)
{
	if (!usbt_is_ready(u->t))
		return -ENODEV;
	if (buffer >= u->info.buffers)
		return -EINVAL;
	if (buffer == u->shown || u->pending != PROJWIRE_NO_BUFFER)
		return -EBUSY;
	u->pending = buffer;
	u->pending_half = half;
	if (usbt_out_done(u->t) >= u->begin_end[buffer])
		return send_swap(u);
	u->swap_deferred = true;
	return 0;
}

static int usb_swap(struct projector *p, uint32_t buffer)
{
	return swap((struct proj_usb *)p, buffer, false);
}

/* SWAP_HALF only to a device of 1.2 or later with mirrored geometry; to
 * any other, SWAP as usb_swap() sends it. */
static int usb_swap_half(struct projector *p, uint32_t buffer)
{
	struct proj_usb *u = (struct proj_usb *)p;
	return swap(u, buffer, projwire_info_half_turn_swaps(&u->info) && !u->half_refused);
}

static int usb_get_fd(struct projector *p)
{
	return usbt_get_fd(((struct proj_usb *)p)->t);
}

static void handle_event(struct proj_usb *u, const struct projwire_event *ev)
{
	const struct projector_listener *l = u->base.listener;
	if (ev->type == PROJWIRE_EV_SWAPPED) {
		u->shown = ev->buffer;
		if (u->pending == ev->buffer)
			u->pending = PROJWIRE_NO_BUFFER;
		bool half = ev->boundary & PROJWIRE_SWAPPED_HALF_TURN;
		if (l && l->swapped_at)
			l->swapped_at(u->base.listener_data, ev->buffer, ev->time_ns, ev->seq, half);
		else if (l && l->swapped)
			l->swapped(u->base.listener_data, ev->buffer, ev->time_ns, ev->seq);
		return;
	}
	u->device_errors++;
	if (ev->buffer != PROJWIRE_NO_BUFFER && ev->buffer == u->pending) {
		u->pending = PROJWIRE_NO_BUFFER; /* the device dropped it */
		u->swap_deferred = false;
	}
	log_warn("usb projector: device error %u on buffer %d (volume %llu)", (unsigned)ev->error,
		 ev->buffer == PROJWIRE_NO_BUFFER ? -1 : (int)ev->buffer, (unsigned long long)ev->seq);
	if (l && l->error)
		l->error(u->base.listener_data, ev->buffer, projwire_error_to_errno(ev->error));
}

/* Whole events from the IN queue; a malformed one is a device fault. */
static void handle_events(struct proj_usb *u)
{
	size_t off = 0;
	struct projwire_event ev;
	while (off < u->evq_len && !usbt_fault(u->t)) {
		int r = projwire_event_decode(u->evq + off, u->evq_len - off, &ev);
		if (r == -EAGAIN)
			break;
		if (r < 0) {
			log_error("usb projector: malformed event from the device");
			usbt_set_fault(u->t, -EPROTO);
			off = u->evq_len;
			break;
		}
		off += (size_t)r;
		handle_event(u, &ev);
	}
	memmove(u->evq, u->evq + off, u->evq_len - off);
	u->evq_len -= off;
}

static void run_deferred_swap(struct proj_usb *u)
{
	if (!u->swap_deferred || usbt_out_done(u->t) < u->begin_end[u->pending])
		return;
	u->swap_deferred = false;
	uint32_t buffer = u->pending;
	int r = send_swap(u);
	const struct projector_listener *l = u->base.listener;
	if (r < 0 && !usbt_fault(u->t) && l && l->error)
		l->error(u->base.listener_data, buffer, r);
}

static void keepalive(struct proj_usb *u, int64_t now)
{
	if (now < u->next_status)
		return;
	u->next_status = now + (u->lit ? KEEPALIVE_NS : STATUS_DARK_NS);
	get_status(u);
}

/* The transport's events first (transfer and hot-plug callbacks), then
 * what they recorded for the device we hold, then the transport drops a
 * faulted device or looks for one. */
static int usb_dispatch(struct projector *p)
{
	struct proj_usb *u = (struct proj_usb *)p;
	int r = usbt_poll(u->t);
	if (r < 0)
		return r;
	if (usbt_is_open(u->t)) {
		handle_events(u);
		if (usbt_is_healthy(u->t)) {
			run_deferred_swap(u);
			keepalive(u, now_ns());
		}
	}
	usbt_service(u->t);
	return 0;
}

static const struct volume *usb_shown(struct projector *p)
{
	return NULL; /* a real device cannot hand its buffers back */
}

static void usb_get_stats(struct projector *p, struct projector_stats *out)
{
	struct proj_usb *u = (struct proj_usb *)p;
	*out = (struct projector_stats){
		.present = usbt_is_ready(u->t),
		.revolutions = u->status.revolutions,
		.swaps = u->status.swaps,
		.underruns = u->status.underruns,
		.bytes_sent = u->bytes_sent,
		.device_errors = u->device_errors,
		.arrivals = u->arrivals,
		.angle_err_p50 = -1, /* a real device cannot know its true angle */
		.angle_err_p99 = -1,
		.angle_err_max = -1,
	};
}

static void usb_destroy(struct projector *p)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (usbt_is_ready(u->t))
		usb_blank(p, true); /* dark on every exit */
	usbt_destroy(u->t);
	projwire_delta_free(&u->plan);
	free(u);
}

static const struct projector_impl usb_impl = {
	.name = "usb",
	.get_info = usb_get_info,
	.blank = usb_blank,
	.set_timing = usb_set_timing,
	.upload = usb_upload,
	.swap = usb_swap,
	.swap_half = usb_swap_half,
	.get_fd = usb_get_fd,
	.dispatch = usb_dispatch,
	.shown = usb_shown,
	.get_stats = usb_get_stats,
	.destroy = usb_destroy,
};

struct projector *proj_usb_create(const struct proj_usb_config *cfg, const struct projector_listener *listener,
				  void *data)
{
	struct proj_usb *u = calloc(1, sizeof(*u));
	if (!u)
		return NULL;
	u->base.impl = &usb_impl;
	u->base.listener = listener;
	u->base.listener_data = data;
	u->cfg = *cfg;
	u->cfg.bus_path[sizeof(u->cfg.bus_path) - 1] = '\0';
	struct usb_transport_config tc = {
		.vid = cfg->vid,
		.pid = cfg->pid,
		.iface_class = PROJWIRE_USB_CLASS,
		.iface_subclass = PROJWIRE_USB_SUBCLASS,
		.iface_protocol = PROJWIRE_USB_PROTOCOL,
	};
	_Static_assert(sizeof(tc.bus_path) == sizeof(u->cfg.bus_path), "the same bus path");
	memcpy(tc.bus_path, u->cfg.bus_path, sizeof(tc.bus_path));
	u->t = usbt_create(&tc, &transport_listener, u);
	if (!u->t) {
		int e = errno;
		free(u);
		errno = e;
		return NULL;
	}
	/* A device present now is set up here (counted by transport_opened)
	 * and not reported by arrived(). */
	usbt_scan(u->t);
	return &u->base;
}

void proj_usb_get_debug(struct projector *p, struct proj_usb_debug *out)
{
	memset(out, 0, sizeof(*out));
	if (p->impl != &usb_impl)
		return;
	struct proj_usb *u = (struct proj_usb *)p;
	usbt_get_debug(u->t, &out->usb);
	out->gone = u->gone;
}
