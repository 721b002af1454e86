/* The USB projector: the projector vtable over libusb, speaking the wire
 * protocol of proto/projector.md through projwire exactly as proj_sim.c
 * does with the in-process device model.
 *
 * Threading and re-entrancy: everything runs on the caller's event loop
 * thread. libusb may run our transfer and hot-plug callbacks inside any
 * libusb call that handles events (a synchronous control transfer does),
 * so those callbacks only record what happened; dispatch() acts on it and
 * is the only place listener callbacks run from.
 *
 * Lifetime of a device: usbp_scan() finds and sets it up (present); a fault
 * (unplug, transfer error, malformed event) starts fail(), which cancels
 * every transfer; once each transfer's callback has been seen, finish()
 * releases and closes it and reports gone(). While nothing is open the
 * periodic rescan and hot-plug arrivals look for it again.
 *
 * Finding and opening a device (usbp_scan), and fitting libusb's fds and
 * hot-plug into our epoll set (usbp_start), are in proj_usb_dev.c. */
#include <errno.h>
#include <libusb.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "log.h"
#include "proj_usb_int.h"
#include "wire_le.h"

#define OUT_CHUNK (256 * 1024)
#define OUT_TIMEOUT_MS 5000 /* a bulk OUT stuck this long: the device is broken */
#define IN_SIZE 512
/* Control transfers are synchronous on the daemon's event loop. A device
 * answers EP0 within a few 1 ms frames; one that takes 100 ms is broken or
 * gone, so that bounds how long the loop can stall. */
#define CTRL_TIMEOUT_MS 100
#define KEEPALIVE_NS 500000000LL /* the device darkens after 2 s of silence */
#define RESCAN_NS 500000000LL
#define DRAIN_NS 1000000000LL

static const struct projector_impl usb_impl;

int usbp_errno(int r)
{
	switch (r) {
	case LIBUSB_ERROR_NO_DEVICE:
		return -ENODEV;
	case LIBUSB_ERROR_TIMEOUT:
		return -ETIMEDOUT;
	case LIBUSB_ERROR_PIPE:
		return -EPIPE;
	case LIBUSB_ERROR_NO_MEM:
		return -ENOMEM;
	case LIBUSB_ERROR_ACCESS:
		return -EACCES;
	case LIBUSB_ERROR_BUSY:
		return -EBUSY;
	case LIBUSB_ERROR_NOT_FOUND:
		return -ENOENT;
	default:
		return -EIO;
	}
}

/* Records a fault; dispatch drops the device. The first reason wins. */
static void set_fault(struct proj_usb *u, int err)
{
	if (!u->fault)
		u->fault = err;
}

/* ---- Control requests ---- */

static int ctrl_raw(struct proj_usb *u, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_setup s;
	projwire_ctrl_encode(c, u->iface, setup, data);
	projwire_setup_decode(setup, &s);
	bool in = s.request_type & LIBUSB_ENDPOINT_IN;
	int r = libusb_control_transfer(u->handle, s.request_type, s.request, s.value, s.index, in ? reply : data,
					s.length, CTRL_TIMEOUT_MS);
	if (r < 0)
		return usbp_errno(r);
	return in ? r : 0; /* the reply length, or 0 as for requests without one */
}

/* One control request; a stall is turned into the errno the device gives
 * in GET_STATUS.last_error. Any other failure is a device fault. */
int usbp_ctrl(struct proj_usb *u, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	if (!u->present && !u->handle)
		return -ENODEV;
	int r = ctrl_raw(u, c, reply ? reply : in);
	if (r != -EPIPE) {
		if (r < 0)
			set_fault(u, r);
		return r;
	}
	u->device_errors++;
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	r = ctrl_raw(u, &get, in);
	if (r < 0 || projwire_status_decode(in, (size_t)r, &st) < 0) {
		set_fault(u, r < 0 ? r : -EPROTO);
		return -EIO;
	}
	return projwire_error_to_errno(st.last_error);
}

static int get_status(struct proj_usb *u)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	int r = usbp_ctrl(u, &c, in);
	if (r < 0)
		return r;
	r = projwire_status_decode(in, (size_t)r, &st);
	if (r < 0) {
		set_fault(u, r);
		return r;
	}
	u->status = st;
	return 0;
}

/* ---- Transfers ---- */

static uint64_t pos_done(const struct proj_usb *u)
{
	uint64_t done = u->pos_submitted;
	for (int i = 0; i < OUT_XFERS; i++)
		if (u->out[i].busy && u->out[i].start < done)
			done = u->out[i].start;
	return done;
}

static int out_in_flight(const struct proj_usb *u)
{
	int n = 0;
	for (int i = 0; i < OUT_XFERS; i++)
		n += u->out[i].busy;
	return n;
}

/* Moves queued upload bytes into free OUT transfers. Each transfer owns
 * its buffer, so the queue can move while transfers are in flight. */
static void pump(struct proj_usb *u)
{
	for (int i = 0; i < OUT_XFERS && u->q_len && !u->failing && !u->fault; i++) {
		struct usb_out *o = &u->out[i];
		if (o->busy)
			continue;
		size_t n = u->q_len < OUT_CHUNK ? u->q_len : OUT_CHUNK;
		memcpy(o->xfer->buffer, u->q + u->q_head, n);
		o->xfer->length = (int)n;
		int r = libusb_submit_transfer(o->xfer);
		if (r < 0) {
			set_fault(u, usbp_errno(r));
			return;
		}
		o->busy = true;
		o->start = u->pos_submitted;
		u->dbg.live_transfers++;
		u->pos_submitted += n;
		u->q_head += n;
		u->q_len -= n;
		if (out_in_flight(u) > u->dbg.max_out_in_flight)
			u->dbg.max_out_in_flight = out_in_flight(u);
	}
	if (!u->q_len)
		u->q_head = 0;
}

static int xfer_fault(enum libusb_transfer_status st)
{
	return st == LIBUSB_TRANSFER_NO_DEVICE ? -ENODEV : st == LIBUSB_TRANSFER_TIMED_OUT ? -ETIMEDOUT : -EIO;
}

static void LIBUSB_CALL out_done(struct libusb_transfer *xfer)
{
	struct proj_usb *u = xfer->user_data;
	for (int i = 0; i < OUT_XFERS; i++)
		if (u->out[i].xfer == xfer)
			u->out[i].busy = false;
	u->dbg.live_transfers--;
	if (xfer->status == LIBUSB_TRANSFER_COMPLETED && xfer->actual_length == xfer->length) {
		u->bytes_sent += (uint64_t)xfer->length;
		pump(u);
	} else if (xfer->status == LIBUSB_TRANSFER_COMPLETED) {
		set_fault(u, -EIO); /* a short write leaves the stream out of step */
	} else if (!(xfer->status == LIBUSB_TRANSFER_CANCELLED && u->failing)) {
		set_fault(u, xfer_fault(xfer->status));
	}
}

static void LIBUSB_CALL in_done(struct libusb_transfer *xfer)
{
	struct proj_usb *u = xfer->user_data;
	struct usb_in *in = NULL;
	for (int i = 0; i < IN_XFERS; i++)
		if (u->in[i].xfer == xfer)
			in = &u->in[i];
	in->busy = false;
	u->dbg.live_transfers--;
	if (xfer->status != LIBUSB_TRANSFER_COMPLETED) {
		if (!(xfer->status == LIBUSB_TRANSFER_CANCELLED && u->failing))
			set_fault(u, xfer_fault(xfer->status));
		return;
	}
	size_t n = (size_t)xfer->actual_length;
	if (u->evq_len + n <= EVQ_SIZE) {
		memcpy(u->evq + u->evq_len, xfer->buffer, n);
		u->evq_len += n;
	} else {
		log_warn("usb projector: event queue full, %zu bytes dropped", n);
	}
	if (u->failing || u->fault)
		return;
	int r = libusb_submit_transfer(xfer);
	if (r < 0) {
		set_fault(u, usbp_errno(r));
		return;
	}
	in->busy = true;
	u->dbg.live_transfers++;
}

static void free_transfers(struct proj_usb *u)
{
	for (int i = 0; i < OUT_XFERS; i++) {
		if (u->out[i].xfer)
			u->dbg.allocated_transfers--;
		libusb_free_transfer(u->out[i].xfer); /* frees its buffer too */
		u->out[i].xfer = NULL;
	}
	for (int i = 0; i < IN_XFERS; i++) {
		if (u->in[i].xfer)
			u->dbg.allocated_transfers--;
		libusb_free_transfer(u->in[i].xfer);
		u->in[i].xfer = NULL;
	}
}

static struct libusb_transfer *alloc_transfer(struct proj_usb *u, size_t size)
{
	struct libusb_transfer *x = libusb_alloc_transfer(0);
	if (!x)
		return NULL;
	x->buffer = malloc(size);
	if (!x->buffer) {
		libusb_free_transfer(x);
		return NULL;
	}
	x->flags = LIBUSB_TRANSFER_FREE_BUFFER;
	u->dbg.allocated_transfers++;
	return x;
}

int usbp_alloc_transfers(struct proj_usb *u)
{
	for (int i = 0; i < OUT_XFERS; i++) {
		struct libusb_transfer *x = alloc_transfer(u, OUT_CHUNK);
		if (!(u->out[i].xfer = x))
			return -ENOMEM;
		libusb_fill_bulk_transfer(x, u->handle, u->ep_out, x->buffer, 0, out_done, u, OUT_TIMEOUT_MS);
	}
	for (int i = 0; i < IN_XFERS; i++) {
		struct libusb_transfer *x = alloc_transfer(u, IN_SIZE);
		if (!(u->in[i].xfer = x))
			return -ENOMEM;
		libusb_fill_bulk_transfer(x, u->handle, u->ep_in, x->buffer, IN_SIZE, in_done, u, 0);
		x->type = u->in_type; /* bulk or interrupt, as the endpoint is */
	}
	return 0;
}

void usbp_cancel_all(struct proj_usb *u)
{
	for (int i = 0; i < OUT_XFERS; i++)
		if (u->out[i].busy)
			libusb_cancel_transfer(u->out[i].xfer);
	for (int i = 0; i < IN_XFERS; i++)
		if (u->in[i].busy)
			libusb_cancel_transfer(u->in[i].xfer);
}

/* Runs libusb until every transfer's callback has been seen, for at most
 * DRAIN_NS: callbacks that never come mean transfers we must not free. */
bool usbp_drain(struct proj_usb *u)
{
	int64_t deadline = now_ns() + DRAIN_NS;
	while (u->dbg.live_transfers > 0 && now_ns() < deadline) {
		struct timeval tv = { .tv_sec = 0, .tv_usec = 10000 };
		libusb_handle_events_timeout_completed(u->ctx, &tv, NULL);
	}
	return u->dbg.live_transfers == 0;
}

/* ---- Dropping the device ---- */

void usbp_close_device(struct proj_usb *u)
{
	if (u->dbg.live_transfers)
		log_error("usb projector: %d transfers never completed; leaking them", u->dbg.live_transfers);
	else
		free_transfers(u);
	libusb_release_interface(u->handle, u->iface);
	libusb_close(u->handle);
	u->handle = NULL;
	u->present = u->failing = u->lit = false;
	u->fault = 0;
	u->hp_left = false;
	u->q_head = u->q_len = 0;
	u->evq_len = 0;
}

/* Starts dropping the device: cancels everything in flight. */
static void fail(struct proj_usb *u, int err)
{
	if (u->failing)
		return;
	log_warn("usb projector: device lost (%s)", strerror(-err));
	u->failing = true;
	u->present = false;
	usbp_cancel_all(u);
}

/* Once every callback has been seen: closes and reports gone(). */
static void finish(struct proj_usb *u)
{
	if (u->dbg.live_transfers > 0)
		return;
	usbp_close_device(u);
	u->dbg.gone++;
	u->next_scan = now_ns() + RESCAN_NS;
	const struct projector_listener *l = u->base.listener;
	if (l && l->gone)
		l->gone(u->base.listener_data, -ENODEV);
}

/* ---- The projector interface ---- */

static int usb_get_info(struct projector *p, struct projector_info *out)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!u->present)
		return -ENODEV;
	memset(out, 0, sizeof(*out));
	strcpy(out->name, "usb");
	projwire_info_to_geometry(&u->info, &out->geom);
	out->buffers = u->info.buffers;
	out->link_bytes_per_sec = u->info.link_bytes_per_sec;
	return 0;
}

static int usb_blank(struct projector *p, bool blank)
{
	struct proj_usb *u = (struct proj_usb *)p;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_BLANK, .blank = blank };
	if (!u->present)
		return -ENODEV;
	int r = usbp_ctrl(u, &c, NULL);
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
	if (!u->present)
		return -ENODEV;
	if (period_ns <= 0)
		return -EINVAL;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_TIMING };
	c.timing = (struct projwire_timing){ (uint64_t)period_ns, index_ns, now_ns() };
	return usbp_ctrl(u, &c, NULL);
}

static bool volume_fits(const struct proj_usb *u, const struct volume *vol)
{
	return vol->geom.width == u->info.width && vol->geom.height == u->info.height &&
	       vol->image_count == u->info.images_per_volume;
}

/* Room for size more bytes at the queue's tail. The queue holds only bytes
 * not yet submitted, so it can move. */
static int queue_reserve(struct proj_usb *u, size_t size)
{
	if (u->q_head + u->q_len + size <= u->q_cap)
		return 0;
	if (u->q_head)
		memmove(u->q, u->q + u->q_head, u->q_len);
	u->q_head = 0;
	if (u->q_len + size <= u->q_cap)
		return 0;
	uint8_t *q = realloc(u->q, u->q_len + size);
	if (!q)
		return -ENOMEM;
	u->q = q;
	u->q_cap = u->q_len + size;
	return 0;
}

static int usb_upload(struct projector *p, uint32_t buffer, const struct volume *vol, const struct volume *base)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!u->present)
		return -ENODEV;
	if (buffer >= u->info.buffers || !volume_fits(u, vol))
		return -EINVAL;
	/* Known without asking the device: we asked for the pending swap
	 * and its SWAPPED event told us what is shown. */
	if (buffer == u->shown || buffer == u->pending)
		return -EBUSY;
	if (u->info.version_minor < 1)
		base = NULL; /* a 1.0 device rejects delta records */
	bool delta;
	size_t size = projwire_upload_size(vol, base, &delta);
	int r = queue_reserve(u, size);
	if (r < 0)
		return r;
	uint8_t *rec = u->q + u->q_head + u->q_len;
	size_t len = projwire_upload_encode(vol, delta ? base : NULL, buffer, rec);
	/* Where its first record (VOLUME_BEGIN) ends: from then on the device
	 * holds the buffer as being written and accepts a swap to it. */
	u->begin_end[buffer] = u->pos_queued + PROJWIRE_HEADER_SIZE + le_get32(rec + 4);
	u->pos_queued += len;
	u->q_len += len;
	pump(u);
	return (int)len;
}

static int send_swap(struct proj_usb *u)
{
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SWAP, .buffer = u->pending };
	int r = usbp_ctrl(u, &c, NULL);
	if (r < 0)
		u->pending = PROJWIRE_NO_BUFFER;
	return r;
}

/* A SWAP may overtake the bulk data of its volume, but not the
 * VOLUME_BEGIN: before that the device holds the buffer's old contents and
 * would show those. So the request waits until that record is through. */
static int usb_swap(struct projector *p, uint32_t buffer)
{
	struct proj_usb *u = (struct proj_usb *)p;
	if (!u->present)
		return -ENODEV;
	if (buffer >= u->info.buffers)
		return -EINVAL;
	if (buffer == u->shown || u->pending != PROJWIRE_NO_BUFFER)
		return -EBUSY;
	u->pending = buffer;
	if (pos_done(u) >= u->begin_end[buffer])
		return send_swap(u);
	u->swap_deferred = true;
	return 0;
}

static int usb_get_fd(struct projector *p)
{
	return ((struct proj_usb *)p)->epfd;
}

static void handle_event(struct proj_usb *u, const struct projwire_event *ev)
{
	const struct projector_listener *l = u->base.listener;
	if (ev->type == PROJWIRE_EV_SWAPPED) {
		u->shown = ev->buffer;
		if (u->pending == ev->buffer)
			u->pending = PROJWIRE_NO_BUFFER;
		if (l && l->swapped)
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
	while (off < u->evq_len && !u->fault) {
		int r = projwire_event_decode(u->evq + off, u->evq_len - off, &ev);
		if (r == -EAGAIN)
			break;
		if (r < 0) {
			log_error("usb projector: malformed event from the device");
			set_fault(u, -EPROTO);
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
	if (!u->swap_deferred || pos_done(u) < u->begin_end[u->pending])
		return;
	u->swap_deferred = false;
	uint32_t buffer = u->pending;
	int r = send_swap(u);
	const struct projector_listener *l = u->base.listener;
	if (r < 0 && !u->fault && l && l->error)
		l->error(u->base.listener_data, buffer, r);
}

static void keepalive(struct proj_usb *u, int64_t now)
{
	if (now < u->next_status)
		return;
	u->next_status = now + (u->lit ? KEEPALIVE_NS : STATUS_DARK_NS);
	get_status(u);
}

/* Acts on what the callbacks recorded, for the device we hold. */
static void service_device(struct proj_usb *u)
{
	handle_events(u);
	if (u->hp_left)
		set_fault(u, -ENODEV);
	if (!u->failing && !u->fault) {
		run_deferred_swap(u);
		keepalive(u, now_ns());
	}
	if (u->fault)
		fail(u, u->fault);
	if (u->failing)
		finish(u);
}

static void look_for_device(struct proj_usb *u)
{
	int64_t now = now_ns();
	if (!u->hp_arrived && now < u->next_scan)
		return;
	bool by_hotplug = u->hp_arrived;
	u->hp_arrived = false;
	u->next_scan = now + RESCAN_NS;
	if (usbp_scan(u) < 0)
		return;
	if (!by_hotplug)
		u->dbg.rescan_opens++;
	u->arrivals++;
	const struct projector_listener *l = u->base.listener;
	if (l && l->arrived)
		l->arrived(u->base.listener_data);
}

static int usb_dispatch(struct projector *p)
{
	struct proj_usb *u = (struct proj_usb *)p;
	struct timeval zero = { 0 };
	uint64_t ticks;
	if (read(u->timerfd, &ticks, sizeof(ticks)) < 0 && errno != EAGAIN)
		return -errno;
	int r = libusb_handle_events_timeout_completed(u->ctx, &zero, NULL);
	if (r < 0 && r != LIBUSB_ERROR_INTERRUPTED)
		log_warn("usb projector: libusb: %s", libusb_strerror(r));
	if (u->handle)
		service_device(u);
	else
		u->hp_left = false; /* a removal of nothing we hold */
	if (!u->handle)
		look_for_device(u);
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
		.present = u->present,
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
	if (u->present)
		usb_blank(p, true); /* dark on every exit */
	if (u->handle) {
		u->failing = true;
		u->present = false;
		usbp_cancel_all(u);
		usbp_drain(u);
		usbp_close_device(u);
	}
	if (u->hotplug)
		libusb_hotplug_deregister_callback(u->ctx, u->hotplug_handle);
	libusb_set_pollfd_notifiers(u->ctx, NULL, NULL, NULL);
	libusb_exit(u->ctx);
	close(u->timerfd);
	close(u->epfd);
	free(u->q);
	free(u);
}

static const struct projector_impl usb_impl = {
	.name = "usb",
	.get_info = usb_get_info,
	.blank = usb_blank,
	.set_timing = usb_set_timing,
	.upload = usb_upload,
	.swap = usb_swap,
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
	u->epfd = u->timerfd = -1;
	int r = usbp_start(u);
	if (r < 0) {
		if (u->hotplug)
			libusb_hotplug_deregister_callback(u->ctx, u->hotplug_handle);
		if (u->ctx)
			libusb_exit(u->ctx);
		if (u->timerfd >= 0)
			close(u->timerfd);
		if (u->epfd >= 0)
			close(u->epfd);
		free(u);
		errno = -r;
		return NULL;
	}
	/* A device present now is set up here and not reported by arrived(). */
	if (usbp_scan(u) == 0)
		u->arrivals++;
	u->next_scan = now_ns() + RESCAN_NS;
	return &u->base;
}

void proj_usb_get_debug(struct projector *p, struct proj_usb_debug *out)
{
	memset(out, 0, sizeof(*out));
	if (p->impl == &usb_impl)
		*out = ((struct proj_usb *)p)->dbg;
}
