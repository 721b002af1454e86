/* The USB projector's state and the functions its two files call of each
 * other: proj_usb.c (the projector interface, control requests, transfers)
 * and proj_usb_dev.c (finding and opening a device; libusb's fds and
 * hot-plug in our epoll set). Private to those two files. */
#ifndef SPINDLE_PROJ_USB_INT_H
#define SPINDLE_PROJ_USB_INT_H

#include <libusb.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "proj_usb_priv.h"
#include "projector.h"
#include "projwire.h"

#define OUT_XFERS 4
#define IN_XFERS 2
#define STATUS_DARK_NS 1000000000LL
#define EVQ_SIZE 4096

struct usb_out {
	struct libusb_transfer *xfer;
	bool busy;
	uint64_t start; /* stream position of its first byte */
};

struct usb_in {
	struct libusb_transfer *xfer;
	bool busy;
};

struct proj_usb {
	struct projector base;
	struct proj_usb_config cfg;
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
	struct projwire_info info;
	struct projwire_status status; /* latest GET_STATUS */
	bool lit;
	int64_t next_status;

	/* Buffers as far as our requests and the device's events tell. */
	uint32_t shown, pending;
	bool swap_deferred;
	uint64_t begin_end[PROJWIRE_MAX_BUFFERS]; /* stream position after its latest VOLUME_BEGIN */

	/* Bulk OUT: encoded uploads waiting (q), then chunks in flight. */
	uint8_t *q;
	size_t q_head, q_len, q_cap;
	uint64_t pos_queued, pos_submitted;
	struct usb_out out[OUT_XFERS];
	struct usb_in in[IN_XFERS];
	uint8_t evq[EVQ_SIZE]; /* event bytes received, not yet handled */
	size_t evq_len;

	/* Noticed inside libusb callbacks, acted on by dispatch. */
	bool hp_arrived, hp_left;
	int fault; /* negative errno: the device must be dropped */

	uint64_t bytes_sent, device_errors, arrivals;
	struct proj_usb_debug dbg;
};
/* proj_usb.c */

/* The negative errno for a LIBUSB_ERROR_* code. */
int usbp_errno(int r);
/* One control request: the reply length or 0; a stall gives the device's errno. */
int usbp_ctrl(struct proj_usb *u, const struct projwire_ctrl *c, uint8_t *reply);
/* Allocates and fills every OUT and IN transfer for the open handle. */
int usbp_alloc_transfers(struct proj_usb *u);
/* Cancels every transfer in flight. */
void usbp_cancel_all(struct proj_usb *u);
/* Runs libusb until every transfer's callback is seen (true) or DRAIN_NS passes. */
bool usbp_drain(struct proj_usb *u);
/* Frees the transfers, releases and closes the handle, resets the device state. */
void usbp_close_device(struct proj_usb *u);

/* proj_usb_dev.c */

/* Opens and sets up the first matching device that works: 0 or negative errno. */
int usbp_scan(struct proj_usb *u);
/* libusb, the epoll set, the tick timer and hot-plug; the caller undoes a failure. */
int usbp_start(struct proj_usb *u);

#endif
