/* Who may connect: the limits a new connection is checked against before
 * the daemon serves it, so that no local user can fill the daemon with
 * connections and lock the others out (dbus-daemon's limits are the model:
 * max_connections_per_user, max_incomplete_connections, auth_timeout).
 *
 * - max-clients: connections in all. admin-reserved-clients of them (1)
 *   are kept for admins (root, the daemon's own user, the admin group), so
 *   that `spindlectl status` works when the rest are taken; others get at
 *   least one.
 * - max-clients-per-user: connections of one uid (admins are not counted
 *   against it).
 * - max-incomplete-clients: connections that have not completed hello
 *   (admins not counted against it); handshake-timeout-ms closes those
 *   that take longer, admin or not. */
#ifndef SPINDLE_ADMISSION_H
#define SPINDLE_ADMISSION_H

#include <stdbool.h>
#include <stdint.h>

struct config;

/* What is connected when a new peer asks. */
struct admission_load {
	uint32_t clients;    /* every connection being served */
	uint32_t incomplete; /* of them, not past hello */
	uint32_t same_user;  /* of them, of the new peer's uid */
};

enum admission_verdict {
	ADMISSION_OK = 0,
	ADMISSION_FULL,       /* max-clients (or all but the admin's slot) */
	ADMISSION_USER,       /* max-clients-per-user */
	ADMISSION_INCOMPLETE, /* max-incomplete-clients */
};

/* Whether a peer (admin or not) may connect now. */
enum admission_verdict admission_check(const struct config *cfg, bool admin, const struct admission_load *load);

/* Why, for the refused client and the log. */
const char *admission_reason(enum admission_verdict v);

/* What the limits did since start (logged on exit). */
struct admission_counters {
	uint64_t refused[4];         /* by verdict (refused[ADMISSION_OK] is unused) */
	uint64_t handshake_timeouts; /* closed for no hello in time */
};

#endif
