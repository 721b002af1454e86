/* The daemon's listening socket: the one systemd passes (socket
 * activation), else one it binds itself (removing a stale file a crash left
 * behind). Accepting runs on the event loop; when accept() runs out of fds
 * or memory the socket rests (50 ms, doubling while it recurs, at most
 * 1.6 s) while the rest of the loop goes on, then is watched again by
 * itself: no busy loop, and it recovers once fds are free. */
#ifndef SPINDLE_LISTEN_SOCKET_H
#define SPINDLE_LISTEN_SOCKET_H

#include <stdbool.h>
#include <stdint.h>

#include "log.h"

struct sd_event;
struct sd_event_source;

#define LISTEN_SOCKET_LISTENER_VERSION 1

struct listen_socket_listener {
	uint32_t version; /* LISTEN_SOCKET_LISTENER_VERSION */
	/* A connection was accepted (non-blocking, close-on-exec): the
	 * listener owns fd from now on. */
	void (*accepted)(void *data, int fd);
};

struct listen_socket {
	int fd;     /* -1: none */
	char *path; /* bound by us: unlinked on close; NULL for systemd's */
	struct sd_event_source *source, *rest_timer;
	uint32_t rest_ms; /* the last rest; 0 after an accept */
	uint64_t pauses;  /* rests since start */
	struct log_ratelimit rest_log;
	const struct listen_socket_listener *listener;
	void *data;
};

/* Opens systemd's socket, or binds path (mode 0660), and watches it on
 * event. On failure (logged) the caller still calls listen_socket_close(). */
int listen_socket_open(struct listen_socket *ls, struct sd_event *event, const char *path,
		       const struct listen_socket_listener *listener, void *data);
/* Stops watching, closes, and removes the file when we bound it. */
void listen_socket_close(struct listen_socket *ls);

#endif
