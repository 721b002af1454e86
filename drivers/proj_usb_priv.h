/* The USB projector's internals that its tests look at. Not for the
 * daemon: nothing here is part of the projector interface. */
#ifndef SPINDLE_PROJ_USB_PRIV_H
#define SPINDLE_PROJ_USB_PRIV_H

#include <stdbool.h>
#include <stdint.h>

struct projector;

struct proj_usb_debug {
	int live_transfers;                          /* submitted, callback not yet seen */
	int allocated_transfers;                     /* libusb_alloc_transfer'd, not yet freed */
	int max_out_in_flight;                       /* most bulk OUT transfers in flight at once */
	bool hotplug;                                /* libusb delivers hot-plug events here */
	uint64_t hotplug_arrivals, hotplug_removals; /* events seen */
	uint64_t rescan_opens;                       /* devices found by the periodic rescan */
	uint64_t gone;                               /* gone() reports */
};

/* Fills out for a projector made by proj_usb_create(). */
void proj_usb_get_debug(struct projector *p, struct proj_usb_debug *out);

#endif
