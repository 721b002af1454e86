/* Watchers (display.watch): clients sent the volumes shown, live, as watch
 * volumes (wvol.h) in sealed memfds. Cheap for the daemon: at most one
 * volume in flight per watcher (the next only after its release), at most
 * its rate (the client's and max-watch-rate), and one encoding of a volume
 * shared by every watcher it goes to. Volumes shown meanwhile are skipped
 * and counted, never queued: the loop never waits for a watcher.
 *
 * server.c calls watch_serve() with the volume on display whenever one is
 * shown, at every boundary, and when the module asks through its listener
 * (wake: a release, a new watcher); watch_next_due() is when a watcher
 * waiting for its rate becomes due (a timer). */
#ifndef SPINDLE_WATCH_H
#define SPINDLE_WATCH_H

#include <stdbool.h>
#include <stdint.h>

#include "link.h"

struct volume;

/* One watcher; embedded in the client's object. */
struct watch_entry {
	struct link link;   /* struct watch.watchers */
	uint64_t period_ns; /* at least this long between two volumes */
	int64_t next_ns;    /* not before then */
	uint64_t sent_seq;  /* the last volume sent (valid when sent_any) */
	uint64_t seen_seq;  /* the newest volume seen (valid when seen_any) */
	uint64_t skipped;   /* volumes seen and not sent since the last sent */
	bool sent_any, seen_any;
	bool in_flight; /* sent, not yet released */
};

#define WATCH_LISTENER_VERSION 1

struct watch_listener {
	uint32_t version; /* WATCH_LISTENER_VERSION */
	/* Send w the watch volume in fd (a sealed memfd of size bytes,
	 * valid during the call: the listener sends a copy), volume seq,
	 * skipped volumes before it; or fd a negative errno: the watcher
	 * failed (the listener sends failed and frees it; w is off the
	 * list). */
	void (*send)(void *data, struct watch_entry *w, int fd, uint64_t size, uint64_t seq, uint64_t skipped);
	/* Volumes were sent: the events may go out now. */
	void (*answered)(void *data);
	/* A watcher may be due now (released, or new): call watch_serve(). */
	void (*wake)(void *data);
};

struct watch_stats {
	uint32_t watchers;
	uint64_t sent, skipped, bytes, refused, denied;
};

struct watch {
	struct link watchers;
	uint32_t count;
	uint32_t max_watchers, max_rate_hz;
	struct watch_stats stats;
	int fd; /* the last encoding, of volume fd_seq (-1: none) */
	uint64_t fd_seq, fd_size;
	const struct watch_listener *listener;
	void *data;
};

void watch_init(struct watch *wt, uint32_t max_watchers, uint32_t max_rate_hz, const struct watch_listener *listener,
		void *data);
void watch_fini(struct watch *wt);

/* Adds w at rate_hz (0: the daemon's rate). 0, or -EUSERS over
 * max-watchers (counted). The first volume goes out at the next
 * watch_serve(), which the listener's wake asks for. */
int watch_add(struct watch *wt, struct watch_entry *w, uint32_t rate_hz);
/* A watcher denied by the policy (counted). */
void watch_count_denied(struct watch *wt);
/* Takes w off (its client destroyed it or went). */
void watch_remove(struct watch *wt, struct watch_entry *w);
/* The client released w's volume. */
void watch_release(struct watch *wt, struct watch_entry *w);

/* Whether any watcher exists (cheap). */
static inline bool watch_any(const struct watch *wt)
{
	return wt->count != 0;
}
/* Sends the volume on display (shown) to every watcher due at now_ns that
 * has not had it; notes it as seen by the others. */
void watch_serve(struct watch *wt, const struct volume *shown, int64_t now_ns);
/* The earliest time a watcher that waits only for its rate (a volume it
 * has not had is on display) becomes due, or 0 when none does. After
 * watch_serve(now_ns) it is later than now_ns. */
int64_t watch_next_due(const struct watch *wt);

#endif
