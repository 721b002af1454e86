/* The daemon: one sd-event loop owning the listening socket, the clients,
 * the devices and the volume pipeline. */
#ifndef SPINDLE_SERVER_H
#define SPINDLE_SERVER_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "admission.h"
#include "client.h"
#include "config.h"
#include "frames.h"
#include "geometry.h"
#include "link.h"
#include "listen_socket.h"
#include "spindle-protocol.h"
#include "stage.h"
#include "watch.h"

struct sd_event;
struct sd_event_source;
struct pipeline;
struct devices;

/* The daemon. server.c only wires: the loop, the socket and accept, the
 * listeners between the modules (docs/architecture.md), status, signals. */
struct server {
	struct sd_event *event;
	struct config cfg;
	struct geometry geom;
	struct listen_socket sock;
	struct sd_event_source *reap_source; /* deferred: frees dead clients */
	struct sd_event_source *state_timer; /* pushes state events, expires handshakes */
	struct log_ratelimit refusal_log;    /* refusals: once a second */
	struct admission_counters admission;
	struct link clients;
	uint32_t client_count;
	struct devices *dev;
	struct pipeline *pipe;
	struct stage stage;                  /* the committed scene */
	struct frames frames;                /* frame callbacks and captures waiting */
	struct watch watch;                  /* watchers of the volumes shown */
	struct sd_event_source *watch_timer; /* a watcher waiting for its rate */
	struct client_env client_env;
	struct client_totals totals; /* against memory-budget and max-mappings */
	struct watchdog *watchdog;   /* fed while nothing below is stuck */
	struct volume *empty;        /* what a capture gets before any volume was shown */
	/* Signs of progress, for the watchdog (CLOCK_MONOTONIC ns). */
	int64_t dead_since_ns; /* the oldest dead client not yet reaped; 0: none */
	int64_t state_ns;      /* the state timer's last run */
	int64_t revolution_ns; /* the last revolution reported, or lit */
};

/* Runs the daemon until SIGINT/SIGTERM. Returns the exit status. */
int server_run(const struct config *cfg);

/* The parts of server_run(), for tests and fuzzers that drive the loop
 * themselves: sets up the loop, devices and renderer, and the listening
 * socket when listen. On failure the caller still calls server_finish(). */
int server_init(struct server *srv, const struct config *cfg, bool listen);
void server_finish(struct server *srv);
/* Serves a connected socket (owned from now on) as a new client. */
int server_add_client(struct server *srv, int fd);

/* The status as display.status carries it: every field filled here. */
void server_get_status(struct server *srv, struct proto_display_status_args *out);
/* What the object cache did, as display.composition carries it. */
void server_get_composition(struct server *srv, struct proto_display_composition_args *out);
/* The limits and what they did, as display.limits carries them. */
void server_get_limits(struct server *srv, struct proto_display_limits_args *out);

#endif
