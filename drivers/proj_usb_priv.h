/* The USB projector's internals that its tests look at. Not for the
 * daemon: nothing here is part of the projector interface. */
#ifndef SPINDLE_PROJ_USB_PRIV_H
#define SPINDLE_PROJ_USB_PRIV_H

#include <stdbool.h>
#include <stdint.h>

#include "usb_transport.h"

struct projector;

struct proj_usb_debug {
	struct usb_transport_debug usb; /* the transport's transfers and hot-plug */
	uint64_t gone;                  /* gone() reports */
};

/* Fills out for a projector made by proj_usb_create(). */
void proj_usb_get_debug(struct projector *p, struct proj_usb_debug *out);

#endif
