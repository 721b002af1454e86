/* The simulated projector's device side: what firmware on a Spindle projector
 * does, modelled in process. It speaks only the wire protocol of
 * proto/projector.md (control transfers, bulk OUT bytes, bulk IN events),
 * so the host half (proj_sim.c) and the tests drive it exactly as the USB
 * driver would drive a real device. Private to drivers/ and its tests.
 *
 * It places slice k of each revolution at index + period * k / N from the
 * latest SET_TIMING and measures where that really was on the rotor
 * (proj_sim_meter.h). Swaps take effect at the rotor's true revolution
 * starts, SWAP_HALF ones (1.2) at its true half-turn starts
 * (sim_rotor_next_half_turn()). It goes dark when no control request came
 * for 2 s. Time is the rotor's clock (sim_rotor_now). */
#ifndef SPINDLE_PROJ_SIM_DEV_H
#define SPINDLE_PROJ_SIM_DEV_H

#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "proj_sim_meter.h"
#include "projwire.h"
#include "volume.h"

struct sim_rotor;
struct proj_simdev;

/* A device on rotor, blanked, every buffer empty. link_bytes_per_sec = 0
 * makes transfers instantaneous. NULL + errno. */
struct proj_simdev *proj_simdev_create(struct sim_rotor *rotor, const struct geometry *geom, uint32_t buffers,
				       uint64_t link_bytes_per_sec);
/* Accepts NULL. */
void proj_simdev_destroy(struct proj_simdev *dev);

/* Makes dev a device of protocol version 1.minor (by default the latest,
 * PROJWIRE_VERSION_MINOR): GET_INFO says so, and below 2 it stalls
 * SWAP_HALF as an unknown request (UNSUPPORTED), as a 1.0 or 1.1 device
 * does. Delta records are taken at any minor (a 1.0 device would reject
 * them: hosts send them to none). */
void proj_simdev_set_minor(struct proj_simdev *dev, uint8_t minor);

/* EP0: one control transfer with its OUT data stage (out, out_len); an IN
 * reply goes to in (in_cap bytes). Returns the reply length, or -EPIPE when
 * the device stalls the request (GET_STATUS.last_error says why). */
int proj_simdev_control(struct proj_simdev *dev, const uint8_t setup[PROJWIRE_SETUP_SIZE], const uint8_t *out,
			size_t out_len, uint8_t *in, size_t in_cap);

/* Bulk OUT: one transfer, arriving now. The link model charges its bytes;
 * a volume is ready when the transfer carrying its VOLUME_END is through. */
void proj_simdev_bulk_out(struct proj_simdev *dev, const uint8_t *buf, size_t len);

/* Bulk IN: moves whole queued events into buf; returns the bytes moved. */
size_t proj_simdev_bulk_in(struct proj_simdev *dev, uint8_t *buf, size_t cap);

/* Readable when a revolution start needs handling or events are queued. */
int proj_simdev_get_fd(struct proj_simdev *dev);
/* Handles every revolution start up to now. 0 or negative errno. */
int proj_simdev_dispatch(struct proj_simdev *dev);

/* The volume lit now as the device decoded it; NULL while blanked or before
 * the first swap. Valid until the next call into dev. */
const struct volume *proj_simdev_shown(struct proj_simdev *dev);

/* Brings the device up to now and fills out: slice angle error against
 * the true rotor, the safety record, watchdog blanks. */
void proj_simdev_get_stats(struct proj_simdev *dev, struct proj_simdev_stats *out);

#endif
