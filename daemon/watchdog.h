/* The service manager's watchdog, fed only while the daemon makes
 * progress. sd-event's own watchdog support feeds on every loop iteration,
 * so a loop spinning on one source (the accept() livelock of an fd-exhausted
 * daemon, say) kept systemd content while nothing else was served. Here a
 * timer at a quarter of WatchdogSec asks the listener whether any work is
 * stuck, and sends WATCHDOG=1 only when nothing is; systemd restarts a
 * daemon that stays stuck for WatchdogSec. */
#ifndef SPINDLE_WATCHDOG_H
#define SPINDLE_WATCHDOG_H

#include <stdint.h>

struct sd_event;

#define WATCHDOG_LISTENER_VERSION 1

struct watchdog_listener {
	uint32_t version; /* WATCHDOG_LISTENER_VERSION */
	/* What is stuck, as a phrase for the log, or NULL when the daemon
	 * is making progress. interval_ns is the watchdog's timeout: work
	 * pending for a good part of it is stuck. */
	const char *(*stalled)(void *data, int64_t now_ns, int64_t interval_ns);
};

struct watchdog_stats {
	int64_t interval_ns; /* WatchdogSec; 0: no watchdog asked for */
	uint64_t fed;
	uint64_t withheld; /* checks that found something stuck */
};

struct watchdog;

/* Arms the watchdog if the service manager asked for one (WATCHDOG_USEC,
 * WATCHDOG_PID: sd_watchdog_enabled()); else returns an idle one. NULL +
 * errno on failure. */
struct watchdog *watchdog_create(struct sd_event *event, const struct watchdog_listener *listener, void *data);
/* Accepts NULL. */
void watchdog_destroy(struct watchdog *w);
void watchdog_get_stats(const struct watchdog *w, struct watchdog_stats *out);

#endif
