/* The USB projector's transport (usb_transport.c): libusb fitted into the
 * caller's event loop (its fds and a tick timer in one epoll set, hot-plug),
 * finding and opening a matching device, the bulk OUT stream and the IN
 * transfers, control requests, and dropping a device that faulted. It knows
 * nothing of the projector wire protocol: what it must tell the layer above
 * (proj_usb.c) goes through struct usb_transport_listener.
 *
 * Everything runs on the caller's event loop thread. libusb runs transfer
 * and hot-plug callbacks inside any libusb call that handles events (a
 * synchronous control request does), so the transport only records there
 * what happened, and usbt_service() acts on it. */
#ifndef SPINDLE_USB_TRANSPORT_H
#define SPINDLE_USB_TRANSPORT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct usb_transport;

struct usb_transport_config {
	uint16_t vid, pid;                                   /* 0 = any */
	uint8_t iface_class, iface_subclass, iface_protocol; /* the interface to claim */
	char bus_path[32];                                   /* "BUS-PORT.PORT..." as in sysfs, empty = any */
};

struct usb_transport_listener {
	/* A matching device is open, its interface claimed, its transfers
	 * allocated and none submitted: control requests work. Sets it up: 0
	 * keeps it; a negative errno closes it, and -EMEDIUMTYPE, -EPROTO or
	 * -EINVAL refuse it while it stays attached. path: "BUS-PORT.PORT...". */
	int (*setup)(void *data, const char *path);
	/* The device setup() kept is in use, its IN transfers submitted; from
	 * usbt_scan() and usbt_service(). */
	void (*opened)(void *data, const char *path);
	/* usbt_service() opened a device (hot-plug or the periodic rescan),
	 * after opened(). */
	void (*arrived)(void *data);
	/* The device held faulted (unplug, transfer error, usbt_set_fault())
	 * and is closed, every transfer's callback seen; from usbt_service(). */
	void (*gone)(void *data, int err);
	/* Inside libusb's event handling: record, act later. n bytes from the
	 * IN endpoint; n bytes of the OUT stream completed. */
	void (*received)(void *data, const uint8_t *bytes, size_t n);
	void (*sent)(void *data, size_t n);
};

/* What the transport's tests look at (proj_usb_priv.h). */
struct usb_transport_debug {
	int live_transfers;                          /* submitted, callback not yet seen */
	int allocated_transfers;                     /* libusb_alloc_transfer'd, not yet freed */
	int max_out_in_flight;                       /* most bulk OUT transfers in flight at once */
	bool hotplug;                                /* libusb delivers hot-plug events here */
	uint64_t hotplug_arrivals, hotplug_removals; /* events seen */
	uint64_t rescan_opens;                       /* devices found by the periodic rescan */
};

/* libusb, the epoll set, the tick timer and hot-plug; no device yet (see
 * usbt_scan()). NULL + errno when libusb cannot start. */
struct usb_transport *usbt_create(const struct usb_transport_config *cfg, const struct usb_transport_listener *l,
				  void *data);
/* Cancels whatever is in flight, closes the device and frees. */
void usbt_destroy(struct usb_transport *t);

/* Opens and sets up the first matching device that works: 0 or negative
 * errno. A device once refused is skipped while it stays. */
int usbt_scan(struct usb_transport *t);

/* The epoll fd for the caller's event loop; when it is readable, call
 * usbt_poll(), act on what the listener recorded, then usbt_service(). */
int usbt_get_fd(const struct usb_transport *t);
/* Handles libusb's events (running the transfer and hot-plug callbacks)
 * and the tick. 0 or negative errno. */
int usbt_poll(struct usb_transport *t);
/* Drops a device that faulted (gone() once its transfers are all seen), or
 * while none is held, looks for one (hot-plug arrivals, the periodic
 * rescan). */
void usbt_service(struct usb_transport *t);

/* A device is held (open, maybe being set up or dropped). */
bool usbt_is_open(const struct usb_transport *t);
/* A device is set up and in use: opened() reported, no fault yet. */
bool usbt_is_ready(const struct usb_transport *t);
/* Held, not faulted, not unplugged: the layer above may go on using it. */
bool usbt_is_healthy(const struct usb_transport *t);
/* The device's fault (negative errno) or 0. */
int usbt_fault(const struct usb_transport *t);
/* Records a fault; usbt_service() drops the device. The first reason wins. */
void usbt_set_fault(struct usb_transport *t, int err);

/* request_type's direction bit: device to host. */
#define USBT_REQUEST_IN 0x80

/* The claimed interface's number (the index of interface requests). */
uint8_t usbt_interface(const struct usb_transport *t);
/* One synchronous control request on the device held: the bytes
 * transferred, or a negative errno (-EPIPE: stalled; -ENODEV: no device). */
int usbt_control(struct usb_transport *t, uint8_t request_type, uint8_t request, uint16_t value, uint16_t index,
		 uint8_t *data, uint16_t length);

/* The bulk OUT stream. Room for size bytes at the tail of the send queue
 * (NULL: out of memory), valid until the next usbt_out_commit(); then len
 * of them written there are queued and sent in order. */
uint8_t *usbt_out_reserve(struct usb_transport *t, size_t size);
void usbt_out_commit(struct usb_transport *t, size_t len);
/* Stream positions since the device was opened: bytes queued, and bytes
 * before the first not yet completed. */
uint64_t usbt_out_queued(const struct usb_transport *t);
uint64_t usbt_out_done(const struct usb_transport *t);

void usbt_get_debug(const struct usb_transport *t, struct usb_transport_debug *out);

#endif
