/* libspindle internals shared by its files. */
#ifndef SPINDLE_LIB_PRIVATE_H
#define SPINDLE_LIB_PRIVATE_H

#include <stdbool.h>
#include <stdint.h>

#include "link.h"
#include "spindle-protocol.h"
#include "spindle/spindle.h"

enum lib_callback_kind {
	LIB_CALLBACK_SYNC,
	LIB_CALLBACK_FRAME,
	LIB_CALLBACK_CAPTURE,
};

/* A callback or capture object waiting for its event. */
struct lib_callback {
	struct lib_callback *next;
	uint32_t id;
	enum lib_callback_kind kind;
	bool done;
	spindle_frame_func func;
	void *data;
	struct spindle_frame frame;
	int fd; /* capture: the memfd received, owned until handed out */
	uint64_t size;
	int error;
};

/* Buffers, lists and layers: what spindle_disconnect() frees. */
struct lib_object {
	struct spindle *sp;
	uint32_t id;
	struct link link;
};

struct spindle {
	struct proto_conn *conn;
	uint32_t version;
	uint32_t offered; /* the version sent in hello */
	uint32_t next_id;
	bool have_info;
	bool dead;
	struct spindle_device_info info;
	struct spindle_status status;
	struct spindle_limits limits; /* from the limits event before status (version 3) */
	bool limits_known;
	struct spindle_composition composition; /* from the composition event before status (version 4) */
	struct spindle_service service;         /* from the service event before status (version 4) */
	bool composition_known;
	struct spindle_watch_stats watch_stats; /* from the watchers event before status (version 5) */
	uint64_t status_serial;
	struct spindle_calibration calibration; /* the last calibration event (version 6) */
	uint64_t calibration_serial;            /* calibration events received */
	uint32_t calibration_refusal;           /* the refusal code just before it, or 0 */
	struct spindle_state state;             /* version 2: the last state event */
	uint64_t refusals;                      /* refused events received */
	uint32_t last_refusal;                  /* the code of the last one */
	uint64_t refused_at;                    /* its number among the events received */
	uint64_t events;                        /* events received */
	const struct spindle_listener *listener;
	void *listener_data;
	uint32_t error_code; /* the daemon's fatal error code */
	struct lib_callback *callbacks;
	struct link objects;
	struct link watchers; /* struct spindle_watcher (watch.c) */
	spindle_log_func log;
	void *log_data;
	char error[300];
};

void lib_log(struct spindle *sp, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Marks the connection broken with a reason; returns -EPIPE. */
int lib_set_error(struct spindle *sp, int err, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* Zeroed memory for a new object and a fresh id for it; NULL + errno
 * (EPIPE: connection broken, ENOSPC: ids ran out, ENOMEM). */
void *lib_alloc(struct spindle *sp, size_t size, uint32_t *id);
/* A frame request: its callback, or NULL + errno. */
struct lib_callback *lib_request_frame(struct spindle *sp, spindle_frame_func func, void *data);
/* After queueing a request: maps its result, flushes when much is queued. */
int lib_sent(struct spindle *sp, int r);
int lib_flush_blocking(struct spindle *sp);
int lib_wait(struct spindle *sp, bool (*ready)(struct spindle *sp, void *data), void *data);

struct lib_callback *lib_callback_add(struct spindle *sp, enum lib_callback_kind kind);
void lib_callback_remove(struct spindle *sp, struct lib_callback *cb);
int lib_wait_callback(struct spindle *sp, struct lib_callback *cb);

void lib_object_free(struct lib_object *obj);

/* Watchers (watch.c): an event for one of them dispatched (the result of
 * its dispatch), or -ENOENT when m is for no watcher; all freed. */
int lib_watch_dispatch(struct spindle *sp, struct proto_message *m, struct proto_error *err);
void lib_watchers_free(struct spindle *sp);
/* Frees the watchers destroyed before callback_id was made: the daemon
 * has read their destroy once that callback's event arrives. */
void lib_watchers_forget(struct spindle *sp, uint32_t callback_id);

#endif
