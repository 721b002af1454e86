/* A connected client and the objects it made: buffers, display lists,
 * layers, callbacks and captures (docs/protocol.md). Lists and layers keep a
 * pending state, changed by requests, and a committed state, replaced by
 * the pending one at display.commit; the renderer sees committed state only. */
#ifndef SPINDLE_CLIENT_H
#define SPINDLE_CLIENT_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "draw.h"
#include "idmap.h"
#include "link.h"
#include "scene.h"
#include "spindle-protocol.h"

struct server;
struct sd_event_source;

struct list_draw {
	struct vdata *data;
	float transform[16];
	uint8_t rgba[4];     /* used when data has no colour per primitive */
	uint8_t point_size;
};

struct draw_array {
	struct list_draw *draws;
	uint32_t count, cap;
	uint64_t vertices;
	uint64_t prims;
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
	bool changed;       /* pending differs from committed */
	struct link link;   /* client.lists */
};

struct layer_state {
	struct list *list; /* holds a reference */
	float transform[16];
	bool visible;
	bool exclusive;
	int32_t priority;
};

struct layer {
	struct object base;
	uint64_t serial; /* creation order, server-wide: ties of priority */
	struct layer_state pending, committed;
	bool changed;
	struct link link; /* client.layers */
};

/* Frame callbacks and captures waiting for a volume. */
struct waiter {
	struct object base;
	uint64_t commit_serial; /* frame: the commit it belongs to (0: next) */
	uint64_t volume_seq;    /* frame: the volume first showing it (0: none yet) */
	int64_t commit_ns;      /* frame: when its commit was handled */
	struct link link;
};

struct client {
	struct server *server;
	struct link link; /* server.clients */
	struct proto_conn *conn;
	struct sd_event_source *source;
	uid_t uid;
	gid_t gid;
	pid_t pid; /* for logs only */
	uint32_t version; /* 0 until hello */
	struct idmap objects;
	struct link lists, layers;
	struct link frames_pending; /* asked for, before their commit */
	struct link frames;         /* committed, waiting to be shown */
	struct link captures;
	uint64_t commit_serial;
	uint64_t buffer_bytes, vertices;
	bool admin;     /* root, the daemon's user, or in the admin group */
	uint32_t state_flags; /* the last state event sent (version 2) */
	float state_rpm;
	bool dead;
};

/* Takes over a connected socket. NULL + errno. */
struct client *client_create(struct server *srv, int fd);
/* Frees the client and its objects. */
void client_destroy(struct client *c);

/* Sends a fatal error and marks the client dead (destroyed soon after, from
 * the event loop). Returns -EPROTO. */
int client_fail(struct client *c, uint32_t object, uint32_t code, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));

/* Queues events are flushed; a client that cannot take them is failed. */
void client_flush(struct client *c);

/* Request handlers of buffer, list and layer objects (objects.c). */
extern const struct proto_buffer_requests buffer_requests;
extern const struct proto_list_requests list_requests;
extern const struct proto_layer_requests layer_requests;

int objects_create_buffer(struct client *c, uint32_t id, uint64_t size, int fd);
int objects_create_buffer_inline(struct client *c, uint32_t id, const void *data, uint32_t size);
int objects_create_list(struct client *c, uint32_t id);
int objects_create_layer(struct client *c, uint32_t id);
/* Registers a new object under its client-chosen id (checked). */
int object_register(struct client *c, struct object *obj, uint32_t id, enum proto_interface type);
void object_destroy(struct object *obj);
/* Moves every pending list and layer state to committed. Returns true if
 * anything visible may have changed. */
bool objects_commit(struct client *c);
/* Whether a commit now may be made: 0, or the display.refused code, with
 * the object at fault and a reason in text. */
uint32_t objects_commit_check(struct client *c, uint32_t *object, char *text, size_t size);
/* The layer's committed state is exclusive and visible. */
bool layer_exclusive(const struct layer *y);
/* Removing the layer changes the scene: it shows a list, or hides the
 * other clients (exclusive). */
bool layer_affects_scene(const struct layer *y);
/* The exclusive policy lets c have exclusive layers. */
bool client_may_be_exclusive(const struct client *c);
/* Sends c a state event if the state changed (version 2 clients). */
void client_send_state(struct client *c, uint32_t flags, float rpm, bool force);

void list_unref(struct list *l);

#endif
