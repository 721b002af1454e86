/* An emulated Spindle projector on USB, for tests running under umockdev's
 * preload library: a usbdevfs device node whose ioctls (URB submit, reap,
 * discard, claim, ...) are answered by the real device model of
 * drivers/proj_sim_dev.c. libusb, and so proj_usb.c, drive it through
 * their real code paths; only the kernel is replaced.
 *
 * umockdev answers ioctls on a thread of its own, so every call here takes
 * the emulator's lock. The device node polls writable at all times (it is
 * a socket), so a driver's fd is always ready while a device is open. */
#ifndef SPINDLE_TEST_USB_EMUL_H
#define SPINDLE_TEST_USB_EMUL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "volume.h"

struct usb_emul;

struct usb_emul_stats {
	int max_out_in_flight;   /* bulk OUT URBs submitted and not yet completed, at most */
	int urbs_outstanding;    /* submitted and not yet reaped, now */
	uint64_t bulk_bytes;     /* bulk OUT bytes the device took since plugged */
	uint64_t controls;       /* control requests since plugged */
	int64_t max_ctrl_gap_ns; /* longest silence on EP0 while lit */
	int watchdog_darkened;   /* times the 2 s watchdog darkened the device */
	int unknown_ioctls;
};

/* A testbed with no device. Returns NULL when umockdev is not preloaded
 * (the caller skips). */
struct usb_emul *usb_emul_create(void);
/* Unplugs what is plugged and frees. */
void usb_emul_destroy(struct usb_emul *e);

/* Plugs a projector of geom with buffers volume buffers reporting version
 * 1.minor (the model itself speaks 1.0; minor only changes GET_INFO), at
 * bus path "1-2". Dark, every buffer empty. Returns 0 or negative errno. */
int usb_emul_plug(struct usb_emul *e, const struct geometry *geom, uint32_t buffers, uint8_t minor);
/* Pulls it out: URBs in flight complete with -ENODEV, later ioctls fail
 * with ENODEV, and a remove uevent goes out. */
void usb_emul_unplug(struct usb_emul *e);

/* Announces the device again ("add") without touching it: a duplicate
 * hot-plug arrival. */
void usb_emul_announce_again(struct usb_emul *e);

/* Whether the device shows (lit) exactly vol. */
bool usb_emul_shows(struct usb_emul *e, const struct volume *vol);
/* Whether the device is lit at all. */
bool usb_emul_lit(struct usb_emul *e);
/* Raw bytes the device sends on its events IN endpoint next. */
void usb_emul_inject_event(struct usb_emul *e, const uint8_t *bytes, size_t len);
void usb_emul_get_stats(struct usb_emul *e, struct usb_emul_stats *out);
/* Waits up to ms for umockdev to close its end of every device node the
 * client closed (its worker thread does that a little later). Returns how
 * many opens it still serves. */
int usb_emul_wait_closed(struct usb_emul *e, int ms);

#endif
