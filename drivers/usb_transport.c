/* The USB projector's transport (usb_transport.h): libusb's fds, a tick
 * timer and hot-plug in one epoll set; finding, opening and claiming a
 * matching device, which the listener sets up; the bulk OUT stream and the
 * IN transfers; control requests; and dropping the device.
 *
 * Lifetime of a device: scan() finds and opens it, setup() sets it up, and
 * once its IN transfers are submitted it is present. A fault (unplug,
 * transfer error, usbt_set_fault()) starts fail(), which cancels every
 * transfer; once each transfer's callback has been seen, finish() releases
 * and closes it and reports gone(). While nothing is open the periodic
 * rescan and hot-plug arrivals look for a device again. */
#include "usb_transport.h"

#include <errno.h>
#include <libusb.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include "log.h"

#define OUT_XFERS 4
#define IN_XFERS 2
#define OUT_CHUNK (256 * 1024)
#define OUT_TIMEOUT_MS 5000 /* a bulk OUT stuck this long: the device is broken */
#define IN_SIZE 512
/* Control transfers are synchronous on the daemon's event loop. A device
 * answers EP0 within a few 1 ms frames; one that takes 100 ms is broken or
 * gone, so that bounds how long the loop can stall. */
#define CTRL_TIMEOUT_MS 100
#define TICK_NS 250000000LL
#define RESCAN_NS 500000000LL
#define DRAIN_NS 1000000000LL

struct usb_out {
	struct libusb_transfer *xfer;
	bool busy;
	uint64_t start; /* stream position of its first byte */
};

struct usb_in {
	struct libusb_transfer *xfer;
	bool busy;
};

struct usb_transport {
	struct usb_transport_config cfg;
	const struct usb_transport_listener *l;
	void *data;
	libusb_context *ctx;
	int epfd, timerfd;
	bool hotplug;
	libusb_hotplug_callback_handle hotplug_handle;
	int64_t next_scan;
	uint8_t refused_bus, refused_addr; /* a device refused; 0 = none */

	/* The device, while open (handle != NULL). */
	libusb_device_handle *handle;
	uint8_t iface, ep_out, ep_in, in_type;
	bool present; /* set up and usable */
	bool failing; /* torn down: waiting for every transfer's callback */

	/* Bulk OUT: bytes waiting (q), then chunks in flight. */
	uint8_t *q;
	size_t q_head, q_len, q_cap;
	uint64_t pos_queued, pos_submitted;
	struct usb_out out[OUT_XFERS];
	struct usb_in in[IN_XFERS];

	/* Noticed inside libusb callbacks, acted on by usbt_service(). */
	bool hp_arrived, hp_left;
	int fault; /* negative errno: the device must be dropped */

	struct usb_transport_debug dbg;
};

/* The negative errno for a LIBUSB_ERROR_* code. */
static int usb_errno(int r)
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

void usbt_set_fault(struct usb_transport *t, int err)
{
	if (!t->fault)
		t->fault = err;
}

/* ---- The bulk OUT stream ---- */

static uint64_t pos_done(const struct usb_transport *t)
{
	uint64_t done = t->pos_submitted;
	for (int i = 0; i < OUT_XFERS; i++)
		if (t->out[i].busy && t->out[i].start < done)
			done = t->out[i].start;
	return done;
}

static int out_in_flight(const struct usb_transport *t)
{
	int n = 0;
	for (int i = 0; i < OUT_XFERS; i++)
		n += t->out[i].busy;
	return n;
}

/* Moves queued bytes into free OUT transfers. Each transfer owns its
 * buffer, so the queue can move while transfers are in flight. */
static void pump(struct usb_transport *t)
{
	for (int i = 0; i < OUT_XFERS && t->q_len && !t->failing && !t->fault; i++) {
		struct usb_out *o = &t->out[i];
		if (o->busy)
			continue;
		size_t n = t->q_len < OUT_CHUNK ? t->q_len : OUT_CHUNK;
		memcpy(o->xfer->buffer, t->q + t->q_head, n);
		o->xfer->length = (int)n;
		int r = libusb_submit_transfer(o->xfer);
		if (r < 0) {
			usbt_set_fault(t, usb_errno(r));
			return;
		}
		o->busy = true;
		o->start = t->pos_submitted;
		t->dbg.live_transfers++;
		t->pos_submitted += n;
		t->q_head += n;
		t->q_len -= n;
		if (out_in_flight(t) > t->dbg.max_out_in_flight)
			t->dbg.max_out_in_flight = out_in_flight(t);
	}
	if (!t->q_len)
		t->q_head = 0;
}

/* Room for size more bytes at the queue's tail. The queue holds only bytes
 * not yet submitted, so it can move. */
uint8_t *usbt_out_reserve(struct usb_transport *t, size_t size)
{
	if (t->q_head + t->q_len + size > t->q_cap) {
		if (t->q_head)
			memmove(t->q, t->q + t->q_head, t->q_len);
		t->q_head = 0;
	}
	if (t->q_len + size > t->q_cap) {
		uint8_t *q = realloc(t->q, t->q_len + size);
		if (!q)
			return NULL;
		t->q = q;
		t->q_cap = t->q_len + size;
	}
	return t->q + t->q_head + t->q_len;
}

void usbt_out_commit(struct usb_transport *t, size_t len)
{
	t->pos_queued += len;
	t->q_len += len;
	pump(t);
}

uint64_t usbt_out_queued(const struct usb_transport *t)
{
	return t->pos_queued;
}

uint64_t usbt_out_done(const struct usb_transport *t)
{
	return pos_done(t);
}

/* ---- Transfers ---- */

static int xfer_fault(enum libusb_transfer_status st)
{
	return st == LIBUSB_TRANSFER_NO_DEVICE ? -ENODEV : st == LIBUSB_TRANSFER_TIMED_OUT ? -ETIMEDOUT : -EIO;
}

static void LIBUSB_CALL out_done(struct libusb_transfer *xfer)
{
	struct usb_transport *t = xfer->user_data;
	for (int i = 0; i < OUT_XFERS; i++)
		if (t->out[i].xfer == xfer)
			t->out[i].busy = false;
	t->dbg.live_transfers--;
	if (xfer->status == LIBUSB_TRANSFER_COMPLETED && xfer->actual_length == xfer->length) {
		if (t->l->sent)
			t->l->sent(t->data, (size_t)xfer->length);
		pump(t);
	} else if (xfer->status == LIBUSB_TRANSFER_COMPLETED) {
		usbt_set_fault(t, -EIO); /* a short write leaves the stream out of step */
	} else if (!(xfer->status == LIBUSB_TRANSFER_CANCELLED && t->failing)) {
		usbt_set_fault(t, xfer_fault(xfer->status));
	}
}

static void LIBUSB_CALL in_done(struct libusb_transfer *xfer)
{
	struct usb_transport *t = xfer->user_data;
	struct usb_in *in = NULL;
	for (int i = 0; i < IN_XFERS; i++)
		if (t->in[i].xfer == xfer)
			in = &t->in[i];
	in->busy = false;
	t->dbg.live_transfers--;
	if (xfer->status != LIBUSB_TRANSFER_COMPLETED) {
		if (!(xfer->status == LIBUSB_TRANSFER_CANCELLED && t->failing))
			usbt_set_fault(t, xfer_fault(xfer->status));
		return;
	}
	if (t->l->received)
		t->l->received(t->data, xfer->buffer, (size_t)xfer->actual_length);
	if (t->failing || t->fault)
		return;
	int r = libusb_submit_transfer(xfer);
	if (r < 0) {
		usbt_set_fault(t, usb_errno(r));
		return;
	}
	in->busy = true;
	t->dbg.live_transfers++;
}

static void free_transfers(struct usb_transport *t)
{
	for (int i = 0; i < OUT_XFERS; i++) {
		if (t->out[i].xfer)
			t->dbg.allocated_transfers--;
		libusb_free_transfer(t->out[i].xfer); /* frees its buffer too */
		t->out[i].xfer = NULL;
	}
	for (int i = 0; i < IN_XFERS; i++) {
		if (t->in[i].xfer)
			t->dbg.allocated_transfers--;
		libusb_free_transfer(t->in[i].xfer);
		t->in[i].xfer = NULL;
	}
}

static struct libusb_transfer *alloc_transfer(struct usb_transport *t, size_t size)
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
	t->dbg.allocated_transfers++;
	return x;
}

/* Allocates and fills every OUT and IN transfer for the open handle. */
static int alloc_transfers(struct usb_transport *t)
{
	for (int i = 0; i < OUT_XFERS; i++) {
		struct libusb_transfer *x = alloc_transfer(t, OUT_CHUNK);
		if (!(t->out[i].xfer = x))
			return -ENOMEM;
		libusb_fill_bulk_transfer(x, t->handle, t->ep_out, x->buffer, 0, out_done, t, OUT_TIMEOUT_MS);
	}
	for (int i = 0; i < IN_XFERS; i++) {
		struct libusb_transfer *x = alloc_transfer(t, IN_SIZE);
		if (!(t->in[i].xfer = x))
			return -ENOMEM;
		libusb_fill_bulk_transfer(x, t->handle, t->ep_in, x->buffer, IN_SIZE, in_done, t, 0);
		x->type = t->in_type; /* bulk or interrupt, as the endpoint is */
	}
	return 0;
}

static int submit_in(struct usb_transport *t)
{
	for (int i = 0; i < IN_XFERS; i++) {
		int r = libusb_submit_transfer(t->in[i].xfer);
		if (r < 0)
			return usb_errno(r);
		t->in[i].busy = true;
		t->dbg.live_transfers++;
	}
	return 0;
}

static void cancel_all(struct usb_transport *t)
{
	for (int i = 0; i < OUT_XFERS; i++)
		if (t->out[i].busy)
			libusb_cancel_transfer(t->out[i].xfer);
	for (int i = 0; i < IN_XFERS; i++)
		if (t->in[i].busy)
			libusb_cancel_transfer(t->in[i].xfer);
}

/* Runs libusb until every transfer's callback has been seen, for at most
 * DRAIN_NS: callbacks that never come mean transfers we must not free. */
static bool drain(struct usb_transport *t)
{
	int64_t deadline = now_ns() + DRAIN_NS;
	while (t->dbg.live_transfers > 0 && now_ns() < deadline) {
		struct timeval tv = { .tv_sec = 0, .tv_usec = 10000 };
		libusb_handle_events_timeout_completed(t->ctx, &tv, NULL);
	}
	return t->dbg.live_transfers == 0;
}

/* ---- Control requests ---- */

int usbt_control(struct usb_transport *t, uint8_t request_type, uint8_t request, uint16_t value, uint16_t index,
		 uint8_t *data, uint16_t length)
{
	if (!t->handle)
		return -ENODEV;
	int r = libusb_control_transfer(t->handle, request_type, request, value, index, data, length, CTRL_TIMEOUT_MS);
	return r < 0 ? usb_errno(r) : r;
}

uint8_t usbt_interface(const struct usb_transport *t)
{
	return t->iface;
}

/* ---- Dropping the device ---- */

/* Frees the transfers, releases and closes the handle, resets the device state. */
static void close_device(struct usb_transport *t)
{
	if (t->dbg.live_transfers)
		log_error("usb projector: %d transfers never completed; leaking them", t->dbg.live_transfers);
	else
		free_transfers(t);
	libusb_release_interface(t->handle, t->iface);
	libusb_close(t->handle);
	t->handle = NULL;
	t->present = t->failing = false;
	t->fault = 0;
	t->hp_left = false;
	t->q_head = t->q_len = 0;
}

/* Starts dropping the device: cancels everything in flight. */
static void fail(struct usb_transport *t, int err)
{
	if (t->failing)
		return;
	log_warn("usb projector: device lost (%s)", strerror(-err));
	t->failing = true;
	t->present = false;
	cancel_all(t);
}

/* Once every callback has been seen: closes and reports gone(). */
static void finish(struct usb_transport *t)
{
	if (t->dbg.live_transfers > 0)
		return;
	close_device(t);
	t->next_scan = now_ns() + RESCAN_NS;
	if (t->l->gone)
		t->l->gone(t->data, -ENODEV);
}

/* ---- Finding and opening the device ---- */

static bool interface_matches(const struct usb_transport *t, const struct libusb_interface_descriptor *d)
{
	return d->bInterfaceClass == t->cfg.iface_class && d->bInterfaceSubClass == t->cfg.iface_subclass &&
	       d->bInterfaceProtocol == t->cfg.iface_protocol;
}

static void find_endpoints(struct usb_transport *t, const struct libusb_interface_descriptor *d)
{
	t->ep_out = t->ep_in = 0;
	for (uint8_t e = 0; e < d->bNumEndpoints; e++) {
		const struct libusb_endpoint_descriptor *ep = &d->endpoint[e];
		uint8_t type = ep->bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
		bool in = ep->bEndpointAddress & LIBUSB_ENDPOINT_IN;
		if (!in && type == LIBUSB_TRANSFER_TYPE_BULK && !t->ep_out)
			t->ep_out = ep->bEndpointAddress;
		if (in && (type == LIBUSB_TRANSFER_TYPE_BULK || type == LIBUSB_TRANSFER_TYPE_INTERRUPT) && !t->ep_in) {
			t->ep_in = ep->bEndpointAddress;
			t->in_type = type;
		}
	}
}

/* The configured interface on dev, with its bulk OUT and IN endpoints. */
static int find_interface(struct usb_transport *t, libusb_device *dev)
{
	struct libusb_config_descriptor *cfg;
	if (libusb_get_active_config_descriptor(dev, &cfg) < 0)
		return -ENOENT;
	int r = -ENOENT;
	for (uint8_t i = 0; i < cfg->bNumInterfaces && r < 0; i++) {
		if (!cfg->interface[i].num_altsetting)
			continue;
		const struct libusb_interface_descriptor *d = &cfg->interface[i].altsetting[0];
		if (!interface_matches(t, d))
			continue;
		find_endpoints(t, d);
		if (t->ep_out && t->ep_in) {
			t->iface = d->bInterfaceNumber;
			r = 0;
		}
	}
	libusb_free_config_descriptor(cfg);
	return r;
}

/* "BUS-PORT.PORT...", as sysfs names a device. */
static void bus_path(libusb_device *dev, char *out, size_t cap)
{
	uint8_t ports[8];
	int n = libusb_get_port_numbers(dev, ports, (int)sizeof(ports));
	int len = snprintf(out, cap, "%u", (unsigned)libusb_get_bus_number(dev));
	for (int i = 0; i < n && len > 0 && (size_t)len < cap; i++)
		len += snprintf(out + len, cap - (size_t)len, "%c%u", i ? '.' : '-', (unsigned)ports[i]);
}

static bool device_matches(struct usb_transport *t, libusb_device *dev)
{
	struct libusb_device_descriptor desc;
	char path[64];
	if (libusb_get_device_descriptor(dev, &desc) < 0)
		return false;
	if ((t->cfg.vid && desc.idVendor != t->cfg.vid) || (t->cfg.pid && desc.idProduct != t->cfg.pid))
		return false;
	if (t->cfg.bus_path[0]) {
		bus_path(dev, path, sizeof(path));
		if (strcmp(path, t->cfg.bus_path))
			return false;
	}
	return find_interface(t, dev) == 0;
}

/* libusb_open and claim: 0, or negative errno with nothing open. */
static int claim_device(struct usb_transport *t, libusb_device *dev, const char *path)
{
	int r = libusb_open(dev, &t->handle);
	if (r < 0) {
		log_warn("usb projector %s: cannot open: %s", path, libusb_strerror(r));
		t->handle = NULL;
		return usb_errno(r);
	}
	libusb_set_auto_detach_kernel_driver(t->handle, 1); /* not supported: nothing to detach */
	r = libusb_claim_interface(t->handle, t->iface);
	if (r < 0) {
		log_warn("usb projector %s: cannot claim interface %u: %s", path, t->iface, libusb_strerror(r));
		libusb_close(t->handle);
		t->handle = NULL;
		return usb_errno(r);
	}
	return 0;
}

/* Opens, claims and sets up dev (already matched). 0, or negative errno
 * with everything undone. */
static int open_device(struct usb_transport *t, libusb_device *dev)
{
	char path[64];
	bus_path(dev, path, sizeof(path));
	int r = claim_device(t, dev, path);
	if (r < 0)
		return r;
	t->q_head = t->q_len = 0;
	t->pos_queued = t->pos_submitted = 0;
	t->fault = 0;
	r = alloc_transfers(t);
	if (r >= 0)
		r = t->l->setup ? t->l->setup(t->data, path) : 0;
	if (r >= 0 && (r = submit_in(t)) < 0) {
		cancel_all(t);
		drain(t);
	}
	if (r < 0 || t->fault) {
		close_device(t);
		return r < 0 ? r : -EIO;
	}
	t->present = true;
	if (t->l->opened)
		t->l->opened(t->data, path);
	return 0;
}

static bool is_refused(const struct usb_transport *t, libusb_device *dev)
{
	return t->refused_bus && libusb_get_bus_number(dev) == t->refused_bus &&
	       libusb_get_device_address(dev) == t->refused_addr;
}

/* Looks for a matching device and sets up the first that works. A device
 * once refused is skipped (and not logged again) while it stays. */
static int scan(struct usb_transport *t)
{
	libusb_device **list;
	ssize_t n = libusb_get_device_list(t->ctx, &list);
	if (n < 0)
		return usb_errno((int)n);
	bool refused_seen = false;
	int r = -ENODEV;
	for (ssize_t i = 0; i < n && r < 0; i++) {
		if (is_refused(t, list[i])) {
			refused_seen = true;
			continue;
		}
		if (!device_matches(t, list[i]))
			continue;
		r = open_device(t, list[i]);
		if (r == -EMEDIUMTYPE || r == -EPROTO || r == -EINVAL) {
			t->refused_bus = libusb_get_bus_number(list[i]);
			t->refused_addr = libusb_get_device_address(list[i]);
			refused_seen = true;
		}
	}
	if (!refused_seen)
		t->refused_bus = t->refused_addr = 0;
	libusb_free_device_list(list, 1);
	return r;
}

int usbt_scan(struct usb_transport *t)
{
	int r = scan(t);
	t->next_scan = now_ns() + RESCAN_NS;
	return r;
}

static void look_for_device(struct usb_transport *t)
{
	int64_t now = now_ns();
	if (!t->hp_arrived && now < t->next_scan)
		return;
	bool by_hotplug = t->hp_arrived;
	t->hp_arrived = false;
	t->next_scan = now + RESCAN_NS;
	if (scan(t) < 0)
		return;
	if (!by_hotplug)
		t->dbg.rescan_opens++;
	if (t->l->arrived)
		t->l->arrived(t->data);
}

/* ---- libusb's fds in our epoll set; hot-plug ---- */

static void LIBUSB_CALL pollfd_added(int fd, short events, void *data)
{
	struct usb_transport *t = data;
	struct epoll_event ev = { .data.fd = fd };
	ev.events = (events & POLLIN ? EPOLLIN : 0) | (events & POLLOUT ? EPOLLOUT : 0);
	if (epoll_ctl(t->epfd, EPOLL_CTL_ADD, fd, &ev) < 0 && errno == EEXIST)
		epoll_ctl(t->epfd, EPOLL_CTL_MOD, fd, &ev);
}

static void LIBUSB_CALL pollfd_removed(int fd, void *data)
{
	struct usb_transport *t = data;
	epoll_ctl(t->epfd, EPOLL_CTL_DEL, fd, NULL);
}

static int add_pollfds(struct usb_transport *t)
{
	const struct libusb_pollfd **fds = libusb_get_pollfds(t->ctx);
	if (!fds)
		return -EIO;
	for (int i = 0; fds[i]; i++)
		pollfd_added(fds[i]->fd, fds[i]->events, t);
	libusb_free_pollfds(fds);
	libusb_set_pollfd_notifiers(t->ctx, pollfd_added, pollfd_removed, t);
	return 0;
}

/* Runs inside libusb's event handling: only notes what happened. */
static int LIBUSB_CALL hotplug_event(libusb_context *ctx, libusb_device *dev, libusb_hotplug_event event, void *data)
{
	struct usb_transport *t = data;
	if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) {
		t->dbg.hotplug_arrivals++;
		t->hp_arrived = true;
		return 0;
	}
	t->dbg.hotplug_removals++;
	if (t->handle && libusb_get_device(t->handle) == dev)
		t->hp_left = true;
	if (is_refused(t, dev))
		t->refused_bus = t->refused_addr = 0; /* its address may come back as another device */
	return 0;
}

static int register_hotplug(struct usb_transport *t)
{
	if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG))
		return 0; /* the periodic rescan finds devices alone */
	int r = libusb_hotplug_register_callback(
		t->ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, 0,
		t->cfg.vid ? t->cfg.vid : LIBUSB_HOTPLUG_MATCH_ANY, t->cfg.pid ? t->cfg.pid : LIBUSB_HOTPLUG_MATCH_ANY,
		LIBUSB_HOTPLUG_MATCH_ANY, hotplug_event, t, &t->hotplug_handle);
	if (r < 0)
		return usb_errno(r);
	t->hotplug = t->dbg.hotplug = true;
	return 0;
}

static int start_timer(struct usb_transport *t)
{
	struct itimerspec its = {
		.it_interval = { .tv_nsec = TICK_NS },
		.it_value = { .tv_nsec = TICK_NS },
	};
	t->timerfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
	if (t->timerfd < 0 || timerfd_settime(t->timerfd, 0, &its, NULL) < 0)
		return -errno;
	struct epoll_event ev = { .events = EPOLLIN, .data.fd = t->timerfd };
	return epoll_ctl(t->epfd, EPOLL_CTL_ADD, t->timerfd, &ev) < 0 ? -errno : 0;
}

/* libusb, the epoll set, the tick timer and hot-plug; the caller undoes a failure. */
static int start(struct usb_transport *t)
{
	int r = libusb_init(&t->ctx);
	if (r < 0) {
		log_error("usb projector: libusb: %s", libusb_strerror(r));
		t->ctx = NULL;
		return usb_errno(r);
	}
	t->epfd = epoll_create1(EPOLL_CLOEXEC);
	if (t->epfd < 0)
		return -errno;
	if ((r = start_timer(t)) < 0 || (r = add_pollfds(t)) < 0)
		return r;
	return register_hotplug(t);
}

/* ---- The event loop ---- */

int usbt_get_fd(const struct usb_transport *t)
{
	return t->epfd;
}

int usbt_poll(struct usb_transport *t)
{
	struct timeval zero = { 0 };
	uint64_t ticks;
	if (read(t->timerfd, &ticks, sizeof(ticks)) < 0 && errno != EAGAIN)
		return -errno;
	int r = libusb_handle_events_timeout_completed(t->ctx, &zero, NULL);
	if (r < 0 && r != LIBUSB_ERROR_INTERRUPTED)
		log_warn("usb projector: libusb: %s", libusb_strerror(r));
	return 0;
}

void usbt_service(struct usb_transport *t)
{
	if (t->handle) {
		if (t->hp_left)
			usbt_set_fault(t, -ENODEV);
		if (t->fault)
			fail(t, t->fault);
		if (t->failing)
			finish(t);
	} else {
		t->hp_left = false; /* a removal of nothing we hold */
	}
	if (!t->handle)
		look_for_device(t);
}

bool usbt_is_open(const struct usb_transport *t)
{
	return t->handle != NULL;
}

bool usbt_is_ready(const struct usb_transport *t)
{
	return t->present;
}

bool usbt_is_healthy(const struct usb_transport *t)
{
	return t->handle && !t->failing && !t->fault && !t->hp_left;
}

int usbt_fault(const struct usb_transport *t)
{
	return t->fault;
}

void usbt_get_debug(const struct usb_transport *t, struct usb_transport_debug *out)
{
	*out = t->dbg;
}

/* ---- Creation ---- */

static void release(struct usb_transport *t)
{
	if (t->hotplug)
		libusb_hotplug_deregister_callback(t->ctx, t->hotplug_handle);
	if (t->ctx) {
		libusb_set_pollfd_notifiers(t->ctx, NULL, NULL, NULL);
		libusb_exit(t->ctx);
	}
	if (t->timerfd >= 0)
		close(t->timerfd);
	if (t->epfd >= 0)
		close(t->epfd);
	free(t->q);
	free(t);
}

struct usb_transport *usbt_create(const struct usb_transport_config *cfg, const struct usb_transport_listener *l,
				  void *data)
{
	struct usb_transport *t = calloc(1, sizeof(*t));
	if (!t)
		return NULL;
	t->cfg = *cfg;
	t->cfg.bus_path[sizeof(t->cfg.bus_path) - 1] = '\0';
	t->l = l;
	t->data = data;
	t->epfd = t->timerfd = -1;
	int r = start(t);
	if (r < 0) {
		release(t);
		errno = -r;
		return NULL;
	}
	return t;
}

void usbt_destroy(struct usb_transport *t)
{
	if (t->handle) {
		t->failing = true;
		t->present = false;
		cancel_all(t);
		drain(t);
		close_device(t);
	}
	release(t);
}
