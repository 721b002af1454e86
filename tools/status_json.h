/* `spindlectl status --json`: the daemon's device and status as one JSON
 * object, for scripts (spindlectl(1) lists the fields). */
#ifndef SPINDLE_STATUS_JSON_H
#define SPINDLE_STATUS_JSON_H

#include <stdint.h>
#include <stdio.h>

#include <spindle/spindle.h>

/* Writes the object and a newline to f. socket is the path used; ws the
 * watchers' counters (protocol 5), or NULL; cal the calibration (protocol
 * 6), or NULL. */
void status_print_json(FILE *f, const char *socket, uint32_t protocol, const struct spindle_device_info *dev,
		       const struct spindle_status *st, const struct spindle_watch_stats *ws,
		       const struct spindle_calibration *cal);

#endif
