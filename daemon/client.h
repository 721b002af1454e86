/* A connected client and the objects it made: buffers, display lists,
 * layers, callbacks and captures (docs/protocol.md). Lists and layers keep a
 * pending state, changed by requests, and a committed state, replaced by
 * the pending one at display.commit; the renderer sees committed state only. */
#ifndef SPINDLE_CLIENT_H
#define SPINDLE_CLIENT_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "idmap.h"
#include "link.h"
#include "scene.h"
#include "spindle-protocol.h"

struct server;
struct sd_event_source;

/* Vertex data copied out of a buffer by one draw; shared by the pending and
 * committed states and by scene snapshots, hence counted. Main thread only. */
struct vdata {
	unsigned refs;
	uint32_t count;
	float xyz[];
};

struct vdata *vdata_ref(struct vdata *v);
void vdata_unref(struct vdata *v);

struct list_draw {
	enum scene_prim prim;
	struct vdata *data;
	float transform[16];
	uint8_t rgba[4];
};

struct draw_array {
	struct list_draw *draws;
	uint32_t count, cap;
	uint64_t vertices;
};

struct object {
	uint32_t id;
	enum proto_interface type;
	struct client *client;
};

struct buffer {
	struct object base;
	const uint8_t *map; /* read-only shared mapping of the sealed memfd */
	uint64_t size;
};

/* Lists are counted: the client's id table holds one reference and each
 * layer showing it another, so a destroyed list stays on display until the
 * layer is changed. */
struct list {
	struct object base;
	unsigned refs;
	struct draw_array pending, committed;
	uint8_t color[4];
	float transform[16];
	bool changed;       /* pending differs from committed */
	struct link link;   /* client.lists */
};

struct layer_state {
	struct list *list; /* holds a reference */
	float transform[16];
	bool visible;
};

struct layer {
	struct object base;
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
int objects_create_list(struct client *c, uint32_t id);
int objects_create_layer(struct client *c, uint32_t id);
/* Registers a new object under its client-chosen id (checked). */
int object_register(struct client *c, struct object *obj, uint32_t id, enum proto_interface type);
void object_destroy(struct object *obj);
/* Moves every pending list and layer state to committed. Returns true if
 * anything visible may have changed. */
bool objects_commit(struct client *c);

void list_unref(struct list *l);

#endif
