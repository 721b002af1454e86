/* The USB projector's test rig: the driver (proj_usb.c) opened on the
 * device model under umockdev (usb_emul.h), its events counted, and the
 * daemon's loop turned by hand. Under umockdev the device node always
 * polls ready, so the loops poll with a short timeout and dispatch each
 * time round. Shared by test_proj_usb.c and test_proj_usb_drop.c. */
#ifndef SPINDLE_TEST_PROJ_USB_RIG_H
#define SPINDLE_TEST_PROJ_USB_RIG_H

#include <stdbool.h>
#include <stdint.h>

#include "proj_usb_priv.h"
#include "projector.h"
#include "usb_emul.h"

/* Small; and large enough that one volume takes several 256 KiB bulk
 * transfers. */
extern const struct geometry geom, big;

struct events {
	int swaps, errors, gone, arrived;
	uint32_t buffer, err_buffer;
	int64_t time_ns;
	uint64_t seq;
	int err, gone_err;
	bool half; /* swapped_at()'s half_turn */
};

/* The events counted; half_listener the same, told which boundary each
 * swap took (swapped_at()). */
extern const struct projector_listener listener, half_listener;

struct rig {
	struct usb_emul *emul;
	struct projector *p;
	struct events ev;
	struct proj_usb_config cfg;
	int fds; /* before the projector: umockdev's own come and go apart */
};

/* The driver at geometry g with listener l, the device model plugged
 * first at dev_geom (none: NULL) speaking protocol 1.minor. */
void rig_init_with(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor,
		   const struct projector_listener *l);
/* The same with listener. */
void rig_init(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor);
/* The driver destroyed, nothing of it left open, the model gone. */
void rig_finish(struct rig *r);
/* One turn of the daemon's loop. */
void turn(struct projector *p);
/* Dispatches until *count moves past before (at most ms milliseconds);
 * returns the milliseconds it took. */
int64_t wait_for(struct projector *p, const int *count, int before, int ms);
/* Dispatches for ms milliseconds. */
void run_for(struct projector *p, int ms);
/* vol uploaded to buffer, swapped in and checked on the model's screen. */
void upload_and_show(struct rig *r, uint32_t buffer, const struct volume *vol);
/* Pulls the device mid-upload: gone() once, after every transfer's
 * callback; then every call says -ENODEV. */
void unplug_mid_upload(struct rig *r, const struct volume *vol);
/* The device plugged again at g and found; the milliseconds it took. */
int64_t replug(struct rig *r, const struct geometry *g);

/* ---- Hot-plug after the privilege drop (test_proj_usb_drop.c) ---- */

/* The argument this program is run again with, as the child that drops
 * root, and the socket's fd after it. */
#define AFTER_DROP_ARG "--after-drop"
/* The child: its exit status. */
int after_drop(int udev_fd);
/* As root: the child run (self: this program) and served; else skipped. */
void test_hotplug_after_drop(const char *self);

#endif
