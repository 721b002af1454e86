/* A connected client and the objects it made: buffers, display lists,
 * layers, callbacks and captures (docs/protocol.md). Lists and layers keep a
 * pending state, changed by requests, and a committed state, replaced by
 * the pending one at display.commit; the renderer sees committed state only. */
#ifndef SPINDLE_CLIENT_H
#define SPINDLE_CLIENT_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "calibration.h"
#include "frames.h"
#include "idmap.h"
#include "layer.h"
#include "link.h"
#include "spindle-protocol.h"
#include "watch.h"

struct config;
struct geometry;
struct sd_event;
struct sd_event_source;
struct stage;
struct ucred;
struct client;

#define CLIENT_LISTENER_VERSION 1

/* What a client tells, or asks, the daemon around it. */
struct client_listener {
	uint32_t version; /* CLIENT_LISTENER_VERSION */
	/* c stopped being served (its layers are off the stage already):
	 * call client_destroy() on it soon, from the event loop. */
	void (*dead)(void *data, struct client *c);
	/* The daemon's status now, for display.get_status and state events. */
	void (*status)(void *data, struct proto_display_status_args *out);
	/* The daemon's limits and what they did, for display.get_status
	 * (version 3). */
	void (*limits)(void *data, struct proto_display_limits_args *out);
	/* The watchdog and the fd cap, for display.get_status (version 4). */
	void (*service)(void *data, struct proto_display_service_args *out);
	/* What the object cache did, for display.get_status (version 4). */
	void (*composition)(void *data, struct proto_display_composition_args *out);
	/* What the watchers did, for display.get_status (version 5). */
	void (*watchers)(void *data, struct proto_display_watchers_args *out);
	/* The calibration in use (version 6); and a change of one key by a
	 * privileged client of uid: 0, or -EINVAL out of range (nothing
	 * changes). */
	void (*calibration)(void *data, struct calibration *out);
	int (*calibrate)(void *data, unsigned key, double value, uid_t uid);
};

/* The daemon-wide budget counts this much for a vertex a list holds
 * (12 bytes of position and the copy's overhead). */
#define CLIENT_VERTEX_BYTES 16

/* What every client holds together, against the daemon-wide budgets
 * (memory-budget, max-mappings), and what those refused. */
struct client_totals {
	uint64_t buffer_bytes; /* every client's buffers, mapped or inline */
	uint64_t vertices;     /* every client's vertices held (as c->vertices counts them) */
	uint32_t mappings;     /* memfd buffers mapped */
	uint64_t refused_memory, refused_mappings;
	uint64_t refused_fds; /* clients disconnected over max-client-fds */
};

/* What every client shares, set up by the daemon and outliving them. */
struct client_env {
	struct sd_event *event;
	const struct config *cfg;
	const struct geometry *geom;
	const char *device_name;
	gid_t admin_gid;       /* admin-group's gid, or (gid_t)-1 */
	struct stage *stage;   /* where committed layers go */
	struct frames *frames; /* where committed frames and captures wait */
	struct watch *watch;   /* watchers of the volumes shown */
	struct client_totals *totals;
	const struct client_listener *listener;
	void *data;
};

/* The state draws take, saved and restored by push and pop. */
struct list_state {
	float transform[16];
	uint8_t color[4];
	uint8_t point_size;
	uint8_t format; /* enum draw_format */
};

#define LIST_STACK_DEPTH 16

struct object {
	uint32_t id;
	enum proto_interface type;
	struct client *client;
};

struct buffer {
	struct object base;
	const uint8_t *map; /* read-only shared mapping of the sealed memfd, or
			     * the inline data (owned) */
	uint64_t size;
	bool inline_data;
};

/* Lists are counted: the client's id table holds one reference and each
 * layer showing it another, so a destroyed list stays on display until the
 * layer is changed. */
struct list {
	struct object base;
	unsigned refs;
	struct draw_array pending, committed;
	struct list_state state;
	struct list_state stack[LIST_STACK_DEPTH];
	unsigned depth;
	bool changed;     /* pending differs from committed */
	struct link link; /* client.lists */
	uint8_t *lut;     /* set_volume_lut's table: lut_count RGB entries, or NULL */
	uint32_t lut_count;
};

/* A volume (volumes.c): its samples, shared with the draws of it. */
struct volume_obj {
	struct object base;
	struct vgrid *grid;
};

/* A layer's state as requests set it, before display.commit. */
struct layer_state {
	struct list *list; /* holds a reference */
	float transform[16];
	bool visible;
	bool exclusive;
	int32_t priority;
};

struct layer {
	struct object base;
	struct layer_state pending;
	struct list *committed_list;  /* holds a reference; its committed draws show */
	struct stage_layer committed; /* on the stage from creation to destruction */
	bool changed;
	struct link link; /* client.layers */
};

/* A frame callback or a capture object. */
struct callback {
	struct object base;
	struct waiter wait;
};

/* A watcher (display.watch). */
struct watcher {
	struct object base;
	struct watch_entry entry;
};

struct client {
	const struct client_env *env;
	struct link link; /* the server's list of clients */
	struct proto_conn *conn;
	struct sd_event_source *source;
	uid_t uid;
	gid_t gid;
	pid_t pid;            /* for logs only */
	int64_t connected_ns; /* the handshake has handshake-timeout-ms from then */
	uint32_t version;     /* 0 until hello */
	struct idmap objects;
	struct link lists, layers;
	struct link frames_pending; /* asked for, before their commit */
	uint64_t buffer_bytes, vertices;
	bool admin;           /* root, the daemon's user, or in the admin group */
	uint32_t state_flags; /* the last state event sent (version 2) */
	float state_rpm;
	bool dead;
	/* NULL, or a volume being made a step at a time (volumes.c): the
	 * client's later requests wait, unread, until it is made. */
	struct vbuild *building;
	bool answered;   /* answers queued, not yet flushed */
	bool left_scene; /* its layers, taken off the stage when it died, showed */
};

/* Root, the daemon's own user, or a member of the admin group (admin_gid,
 * or (gid_t)-1 for none): by the peer's credentials (SO_PEERCRED, and
 * SO_PEERGROUPS on fd), never its pid. */
bool client_peer_is_admin(gid_t admin_gid, int fd, const struct ucred *cred);

/* Takes over a connected socket. NULL + errno. */
struct client *client_create(const struct client_env *env, int fd);
/* Frees the client and its objects. */
void client_destroy(struct client *c);

/* Sends a fatal error and marks the client dead (destroyed soon after, from
 * the event loop). Returns -EPROTO. */
int client_fail(struct client *c, uint32_t object, uint32_t code, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));

/* Queued events are flushed; a client that cannot take them is failed. */
void client_flush(struct client *c);

/* A frame callback or capture of a client is answered (frames.h): what
 * the daemon's frames listener calls. A dead client's is just freed. The
 * event is queued; client_flush_answered() sends it. */
void client_frame_done(struct waiter *w, uint64_t seq, int64_t time_ns);
void client_capture_done(struct waiter *w, int fd, uint64_t size);
/* A watcher is sent a volume (watch.h), or failed (fd < 0: the object is
 * destroyed). Queued like the answers above. */
void client_watch_send(struct watch_entry *w, int fd, uint64_t size, uint64_t seq, uint64_t skipped);
/* Flushes c if answers were queued since its last flush. */
void client_flush_answered(struct client *c);

/* Request handlers of buffer, list and layer objects (objects.c). */
extern const struct proto_buffer_requests buffer_requests;
extern const struct proto_list_requests list_requests;
extern const struct proto_layer_requests layer_requests;
extern const struct proto_watcher_requests watcher_requests;
extern const struct proto_volume_requests volume_requests;

int objects_create_buffer(struct client *c, uint32_t id, uint64_t size, int fd);
int objects_create_buffer_inline(struct client *c, uint32_t id, const void *data, uint32_t size);
int objects_create_list(struct client *c, uint32_t id);
int objects_create_layer(struct client *c, uint32_t id);
int objects_create_volume(struct client *c, const struct proto_display_create_volume_args *a);
/* The destroy request of buffers, lists, layers and volumes. */
int objects_destroy_req(void *target);
/* Buffer id of c, or NULL after failing c (invalid_object on object
 * blame; what names the request). */
const struct buffer *objects_buffer(struct client *c, uint32_t blame, uint32_t id, const char *what);
/* Counts bytes of c's against max-buffer-bytes and memory-budget: 0, or c
 * failed with the quota error. objects_uncharge() gives them back. */
int objects_charge(struct client *c, uint64_t bytes);
void objects_uncharge(struct client *c, uint64_t bytes);
/* The parts of those: room for bytes more under memory-budget (else c
 * failed, quota), and bytes and mappings counted (negative: given back). */
int objects_budget_room(struct client *c, uint64_t bytes);
void objects_account_buffer(struct client *c, int64_t bytes, int mappings);
/* Frees a buffer and gives its bytes and mapping back (buffers.c). */
void buffers_destroy(struct buffer *b);
/* Appends a draw of v (its reference taken over) to l's pending draws with
 * l's state, its count against max-vertices and memory-budget: 0, or l's
 * client failed (v released). */
int objects_list_append(struct list *l, struct vdata *v);
/* list.draw_volume and list.set_volume_lut (volumes.c). */
int volumes_list_draw(void *target, const struct proto_list_draw_volume_args *a);
int volumes_list_set_lut(void *target, const struct proto_list_set_volume_lut_args *a);
void volume_object_destroy(struct volume_obj *vo);
/* Stops making c's volume, if it is making one (its object goes with c). */
void volumes_cancel_build(struct client *c);
/* c's volume is made: its waiting requests are served, and it is read
 * again (client.c). */
void client_resume(struct client *c);
/* Registers a new object under its client-chosen id (checked). */
int object_register(struct client *c, struct object *obj, uint32_t id, enum proto_interface type);
void object_destroy(struct object *obj);
/* Moves every pending list and layer state to committed. Returns true if
 * anything visible may have changed. */
bool objects_commit(struct client *c);
/* Whether a commit now may be made: 0, or the display.refused code, with
 * the object at fault and a reason in text. */
uint32_t objects_commit_check(struct client *c, uint32_t *object, char *text, size_t size);
/* Takes every layer of c off the stage. Returns whether the scene changed. */
bool objects_leave_stage(struct client *c);
/* Takes every watcher of c out of the daemon's watch. */
void objects_leave_watch(struct client *c);
/* The exclusive policy lets c have exclusive layers. */
bool client_may_be_exclusive(const struct client *c);
/* Sends c a state event if the state changed (version 2 clients). */
void client_send_state(struct client *c, const struct proto_display_status_args *st, bool force);

void list_unref(struct list *l);

#endif
