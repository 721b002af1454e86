/* The USB projector's device discovery: finding a matching device,
 * opening, claiming and setting it up (usbp_scan), and fitting libusb into
 * the caller's event loop: its fds and a tick timer in our epoll set, and
 * hot-plug events (usbp_start). The projector interface, control requests
 * and transfers are in proj_usb.c; the state they share in proj_usb_int.h. */
#include <errno.h>
#include <libusb.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/timerfd.h>

#include "log.h"
#include "proj_usb_int.h"

#define TICK_NS 250000000LL

/* ---- Finding and opening the device ---- */

/* Spindle's interface on dev, with its bulk OUT and IN endpoints. */
static int find_interface(struct proj_usb *u, libusb_device *dev)
{
	struct libusb_config_descriptor *cfg;
	if (libusb_get_active_config_descriptor(dev, &cfg) < 0)
		return -ENOENT;
	int r = -ENOENT;
	for (uint8_t i = 0; i < cfg->bNumInterfaces && r < 0; i++) {
		if (!cfg->interface[i].num_altsetting)
			continue;
		const struct libusb_interface_descriptor *d = &cfg->interface[i].altsetting[0];
		if (d->bInterfaceClass != PROJWIRE_USB_CLASS || d->bInterfaceSubClass != PROJWIRE_USB_SUBCLASS ||
		    d->bInterfaceProtocol != PROJWIRE_USB_PROTOCOL)
			continue;
		u->ep_out = u->ep_in = 0;
		for (uint8_t e = 0; e < d->bNumEndpoints; e++) {
			const struct libusb_endpoint_descriptor *ep = &d->endpoint[e];
			uint8_t type = ep->bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
			bool in = ep->bEndpointAddress & LIBUSB_ENDPOINT_IN;
			if (!in && type == LIBUSB_TRANSFER_TYPE_BULK && !u->ep_out)
				u->ep_out = ep->bEndpointAddress;
			if (in && (type == LIBUSB_TRANSFER_TYPE_BULK || type == LIBUSB_TRANSFER_TYPE_INTERRUPT) &&
			    !u->ep_in) {
				u->ep_in = ep->bEndpointAddress;
				u->in_type = type;
			}
		}
		if (u->ep_out && u->ep_in) {
			u->iface = d->bInterfaceNumber;
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

static bool device_matches(struct proj_usb *u, libusb_device *dev)
{
	struct libusb_device_descriptor desc;
	char path[64];
	if (libusb_get_device_descriptor(dev, &desc) < 0)
		return false;
	if ((u->cfg.vid && desc.idVendor != u->cfg.vid) || (u->cfg.pid && desc.idProduct != u->cfg.pid))
		return false;
	if (u->cfg.bus_path[0]) {
		bus_path(dev, path, sizeof(path));
		if (strcmp(path, u->cfg.bus_path))
			return false;
	}
	return find_interface(u, dev) == 0;
}

static bool geometry_same(const struct geometry *a, const struct geometry *b)
{
	return a->width == b->width && a->height == b->height && a->images_per_rev == b->images_per_rev &&
	       a->mirrored == b->mirrored;
}

/* RESET_STREAM, GET_INFO and its checks, SET_BLANK 1. */
static int setup_device(struct proj_usb *u, const char *path)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_RESET_STREAM };
	int r = usbp_ctrl(u, &c, NULL);
	if (r < 0)
		return r;
	c.request = PROJWIRE_REQ_GET_INFO;
	if ((r = usbp_ctrl(u, &c, in)) < 0)
		return r;
	if ((r = projwire_info_decode(in, (size_t)r, &u->info)) < 0) {
		log_error("usb projector %s: bad GET_INFO reply (version %u.%u): %s", path, in[0], in[1],
			  strerror(-r));
		return r;
	}
	struct geometry g;
	projwire_info_to_geometry(&u->info, &g);
	if (!geometry_same(&g, &u->cfg.geom)) {
		log_error("usb projector %s: refused: device is %ux%u, %u images/rev%s; configured %ux%u, %u%s",
			  path, g.width, g.height, g.images_per_rev, g.mirrored ? " mirrored" : "",
			  u->cfg.geom.width, u->cfg.geom.height, u->cfg.geom.images_per_rev,
			  u->cfg.geom.mirrored ? " mirrored" : "");
		return -EMEDIUMTYPE;
	}
	c = (struct projwire_ctrl){ .request = PROJWIRE_REQ_SET_BLANK, .blank = true };
	return usbp_ctrl(u, &c, NULL);
}

static int submit_in(struct proj_usb *u)
{
	for (int i = 0; i < IN_XFERS; i++) {
		int r = libusb_submit_transfer(u->in[i].xfer);
		if (r < 0)
			return usbp_errno(r);
		u->in[i].busy = true;
		u->dbg.live_transfers++;
	}
	return 0;
}

static void reset_state(struct proj_usb *u)
{
	u->shown = u->pending = PROJWIRE_NO_BUFFER;
	u->swap_deferred = false;
	memset(u->begin_end, 0, sizeof(u->begin_end));
	memset(&u->status, 0, sizeof(u->status));
	u->q_head = u->q_len = u->evq_len = 0;
	u->pos_queued = u->pos_submitted = 0;
	u->lit = false;
	u->fault = 0;
	u->next_status = now_ns() + STATUS_DARK_NS;
}

/* Opens, claims and sets up dev (already matched). 0, or negative errno
 * with everything undone. */
static int open_device(struct proj_usb *u, libusb_device *dev)
{
	char path[64];
	bus_path(dev, path, sizeof(path));
	int r = libusb_open(dev, &u->handle);
	if (r < 0) {
		log_warn("usb projector %s: cannot open: %s", path, libusb_strerror(r));
		u->handle = NULL;
		return usbp_errno(r);
	}
	libusb_set_auto_detach_kernel_driver(u->handle, 1); /* not supported: nothing to detach */
	r = libusb_claim_interface(u->handle, u->iface);
	if (r < 0) {
		log_warn("usb projector %s: cannot claim interface %u: %s", path, u->iface, libusb_strerror(r));
		libusb_close(u->handle);
		u->handle = NULL;
		return usbp_errno(r);
	}
	reset_state(u);
	r = usbp_alloc_transfers(u);
	if (r >= 0)
		r = setup_device(u, path);
	if (r >= 0 && (r = submit_in(u)) < 0) {
		usbp_cancel_all(u);
		usbp_drain(u);
	}
	if (r < 0 || u->fault) {
		usbp_close_device(u);
		return r < 0 ? r : -EIO;
	}
	u->present = true;
	log_info("usb projector %s: version %u.%u, %ux%u, %u images/rev, %u buffers", path,
		 u->info.version_major, u->info.version_minor, u->info.width, u->info.height,
		 u->info.images_per_rev, u->info.buffers);
	return 0;
}

static bool is_refused(const struct proj_usb *u, libusb_device *dev)
{
	return u->refused_bus && libusb_get_bus_number(dev) == u->refused_bus &&
	       libusb_get_device_address(dev) == u->refused_addr;
}

/* Looks for a matching device and sets up the first that works. A device
 * once refused is skipped (and not logged again) while it stays. */
int usbp_scan(struct proj_usb *u)
{
	libusb_device **list;
	ssize_t n = libusb_get_device_list(u->ctx, &list);
	if (n < 0)
		return usbp_errno((int)n);
	bool refused_seen = false;
	int r = -ENODEV;
	for (ssize_t i = 0; i < n && r < 0; i++) {
		if (is_refused(u, list[i])) {
			refused_seen = true;
			continue;
		}
		if (!device_matches(u, list[i]))
			continue;
		r = open_device(u, list[i]);
		if (r == -EMEDIUMTYPE || r == -EPROTO || r == -EINVAL) {
			u->refused_bus = libusb_get_bus_number(list[i]);
			u->refused_addr = libusb_get_device_address(list[i]);
			refused_seen = true;
		}
	}
	if (!refused_seen)
		u->refused_bus = u->refused_addr = 0;
	libusb_free_device_list(list, 1);
	return r;
}

/* ---- libusb's fds in our epoll set; hot-plug ---- */

static void LIBUSB_CALL pollfd_added(int fd, short events, void *data)
{
	struct proj_usb *u = data;
	struct epoll_event ev = { .data.fd = fd };
	ev.events = (events & POLLIN ? EPOLLIN : 0) | (events & POLLOUT ? EPOLLOUT : 0);
	if (epoll_ctl(u->epfd, EPOLL_CTL_ADD, fd, &ev) < 0 && errno == EEXIST)
		epoll_ctl(u->epfd, EPOLL_CTL_MOD, fd, &ev);
}

static void LIBUSB_CALL pollfd_removed(int fd, void *data)
{
	struct proj_usb *u = data;
	epoll_ctl(u->epfd, EPOLL_CTL_DEL, fd, NULL);
}

static int add_pollfds(struct proj_usb *u)
{
	const struct libusb_pollfd **fds = libusb_get_pollfds(u->ctx);
	if (!fds)
		return -EIO;
	for (int i = 0; fds[i]; i++)
		pollfd_added(fds[i]->fd, fds[i]->events, u);
	libusb_free_pollfds(fds);
	libusb_set_pollfd_notifiers(u->ctx, pollfd_added, pollfd_removed, u);
	return 0;
}

/* Runs inside libusb's event handling: only notes what happened. */
static int LIBUSB_CALL hotplug_event(libusb_context *ctx, libusb_device *dev, libusb_hotplug_event event,
				     void *data)
{
	struct proj_usb *u = data;
	if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) {
		u->dbg.hotplug_arrivals++;
		u->hp_arrived = true;
		return 0;
	}
	u->dbg.hotplug_removals++;
	if (u->handle && libusb_get_device(u->handle) == dev)
		u->hp_left = true;
	if (is_refused(u, dev))
		u->refused_bus = u->refused_addr = 0; /* its address may come back as another device */
	return 0;
}

static int register_hotplug(struct proj_usb *u)
{
	if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG))
		return 0; /* the periodic rescan finds devices alone */
	int r = libusb_hotplug_register_callback(
		u->ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, 0,
		u->cfg.vid ? u->cfg.vid : LIBUSB_HOTPLUG_MATCH_ANY, u->cfg.pid ? u->cfg.pid : LIBUSB_HOTPLUG_MATCH_ANY,
		LIBUSB_HOTPLUG_MATCH_ANY, hotplug_event, u, &u->hotplug_handle);
	if (r < 0)
		return usbp_errno(r);
	u->hotplug = u->dbg.hotplug = true;
	return 0;
}

static int start_timer(struct proj_usb *u)
{
	struct itimerspec its = {
		.it_interval = { .tv_nsec = TICK_NS },
		.it_value = { .tv_nsec = TICK_NS },
	};
	u->timerfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
	if (u->timerfd < 0 || timerfd_settime(u->timerfd, 0, &its, NULL) < 0)
		return -errno;
	struct epoll_event ev = { .events = EPOLLIN, .data.fd = u->timerfd };
	return epoll_ctl(u->epfd, EPOLL_CTL_ADD, u->timerfd, &ev) < 0 ? -errno : 0;
}

int usbp_start(struct proj_usb *u)
{
	int r = libusb_init(&u->ctx);
	if (r < 0) {
		log_error("usb projector: libusb: %s", libusb_strerror(r));
		u->ctx = NULL;
		return usbp_errno(r);
	}
	u->epfd = epoll_create1(EPOLL_CLOEXEC);
	if (u->epfd < 0)
		return -errno;
	if ((r = start_timer(u)) < 0 || (r = add_pollfds(u)) < 0)
		return r;
	return register_hotplug(u);
}
