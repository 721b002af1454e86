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
#include <sys/types.h>

#include "geometry.h"
#include "volume.h"

struct usb_emul;

struct usb_emul_stats {
	int max_out_in_flight;   /* bulk OUT URBs submitted and not yet completed, at most */
	int urbs_outstanding;    /* submitted and not yet reaped, now */
	uint64_t bulk_bytes;     /* bulk OUT bytes the device took since plugged */
	uint64_t controls;       /* control requests since plugged */
	uint64_t swaps;          /* ... of them SWAP */
	uint64_t swap_halves;    /* ... of them SWAP_HALF (1.2) */
	uint64_t stalls;         /* ... of them stalled */
	int64_t max_ctrl_gap_ns; /* longest silence on EP0 while lit */
	int watchdog_darkened;   /* times the 2 s watchdog darkened the device */
	int unknown_ioctls;
};

/* A testbed with no device. Returns NULL when umockdev is not preloaded
 * (the caller skips). GLib's worker context, an fd that stays, is made
 * before it returns, not later by umockdev's thread (see the .c). */
struct usb_emul *usb_emul_create(void);
/* Unplugs what is plugged and frees. */
void usb_emul_destroy(struct usb_emul *e);

/* Plugs a projector of geom with buffers volume buffers speaking version
 * 1.minor (proj_simdev_set_minor(): GET_INFO says so, and below 2 it stalls
 * SWAP_HALF as unknown; it takes delta records at any minor), at bus path
 * "1-2". Dark, every buffer empty. Returns 0 or negative errno. */
int usb_emul_plug(struct usb_emul *e, const struct geometry *geom, uint32_t buffers, uint8_t minor);
/* Pulls it out: URBs in flight complete with -ENODEV, later ioctls fail
 * with ENODEV, and a remove uevent goes out. */
void usb_emul_unplug(struct usb_emul *e);

/* Announces the device again ("add") without touching it: a duplicate
 * hot-plug arrival. */
void usb_emul_announce_again(struct usb_emul *e);

/* Makes the plugged device speak 1.minor from now on, whatever its GET_INFO
 * said: a device that claims what it does not do. */
void usb_emul_set_minor(struct usb_emul *e, uint8_t minor);

/* The rotor the device turns with (real time, 1800 rpm), whose true
 * revolution and half-turn starts its swaps take. */
struct sim_rotor;
const struct sim_rotor *usb_emul_rotor(const struct usb_emul *e);

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

/* ---- Permissions, for a driver that runs unprivileged ----
 *
 * On a real system the kernel creates the device node root-owned and udev
 * then applies its rule (owner, group, mode) before it passes the event on
 * to libudev's listeners, libusb's hot-plug among them. Here the test
 * process itself plays the kernel, and a rule set with
 * usb_emul_set_node_rule() plays udev. */

/* Gives the device node at path its owner, group and mode: 0 or a negative
 * errno. */
typedef int usb_emul_node_rule(void *data, const char *path);

/* From now on usb_emul_plug() calls rule (NULL: none; the node keeps what
 * umockdev gives it) on the device node once the device is in the testbed
 * and before it returns, so before a driver can try to open it. The node
 * is the file that open() of /dev/bus/usb/001/002 reaches, created anew
 * at each plug: the kernel checks its owner, group and mode as it would
 * the real node's. (The socket umockdev answers the node's ioctls on is
 * no part of it: the preload library connects to it at each open, even
 * a refused one, and exits the process when that connect() is refused.)
 * A failing rule fails the plug. */
void usb_emul_set_node_rule(struct usb_emul *e, usb_emul_node_rule *rule, void *data);
/* Calls the rule again on the node of the device plugged now (as
 * `udevadm trigger` does after a rule changed). 0, -ENODEV when none is
 * plugged, or the rule's error. */
int usb_emul_apply_node_rule(struct usb_emul *e);
/* The node's file in the testbed (see usb_emul_set_node_rule()). */
const char *usb_emul_node_path(const struct usb_emul *e);
/* Gives every file of the testbed but the node to uid:gid, so that this
 * process can go on playing the kernel after it gave up root: adding and
 * removing the device's sysfs entries and node, and sending uevents to the
 * listeners' sockets (umockdev connects to each, which needs write access,
 * and aborts when refused); and so that the driver's opens can connect to
 * the node's ioctl socket. The tree is the test's plumbing; the node alone
 * stands for what udev guards. 0 or a negative errno. */
int usb_emul_chown_testbed(struct usb_emul *e, uid_t uid, gid_t gid);
/* Closes what the preload library leaves of the opens of the node that the
 * kernel refused: it connects to the node's ioctl socket at each open,
 * refused or not, and closes that socket only with the fd the open
 * returned, so a refused open's stays, an fd of this process and a client
 * of the emulator (which usb_emul_wait_closed() would wait for in vain).
 * For a time no driver holds the device open (its own connection would go
 * too). Returns how many it closed. */
int usb_emul_close_stray_sockets(struct usb_emul *e);

#endif
