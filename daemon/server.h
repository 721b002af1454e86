/* The daemon: one sd-event loop owning the listening socket, the clients,
 * the devices and the volume pipeline. */
#ifndef SPINDLE_SERVER_H
#define SPINDLE_SERVER_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "config.h"
#include "geometry.h"
#include "link.h"

struct sd_event;
struct sd_event_source;
struct pipeline;
struct devices;
struct volume;

struct server {
	struct sd_event *event;
	struct config cfg;
	struct geometry geom;
	char device_name[64];
	int listen_fd;
	bool listen_fd_owned; /* false when systemd passed it */
	char *socket_path;    /* to unlink on exit, when we bound it */
	struct sd_event_source *listen_source;
	struct sd_event_source *reap_source; /* deferred: frees dead clients */
	struct link clients;
	uint32_t client_count;
	struct devices *dev;
	struct pipeline *pipe;
	unsigned captures_waiting;
	uint64_t unseen_seq; /* swapped in while the projector was dark */
	uint64_t shown_seq;  /* the volume on display, seen lit */
	/* Frame callbacks may wait for a revolution start of shown_seq: of
	 * commits made after it was swapped in, identical to it. */
	bool frames_waiting;
	uint64_t layer_serial; /* layers made so far */
	gid_t admin_gid;       /* admin-group's gid, or (gid_t)-1 */
	struct sd_event_source *state_timer; /* pushes state events */
};

struct server_status {
	float rpm;
	uint32_t flags; /* PROTO_DISPLAY_STATUS_FLAGS_* */
	uint64_t volumes_shown;
	uint64_t underruns;
	uint32_t clients;
	uint64_t volumes_rendered;
	uint64_t volumes_skipped;
	uint64_t bytes_uploaded;
	uint32_t render_us;
	float jitter_us;
	uint64_t missed_pulses;
	uint64_t upload_rate;
	float index_error_us;
	float angle_error_p99, angle_error_max;
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

/* For clients and objects. */
/* The client whose exclusive layer shows, or NULL. */
struct client *server_exclusive_client(struct server *srv);
void server_reap_later(struct server *srv);
/* A commit changed what is visible, or waits for frame callbacks: a new
 * volume is needed. */
void server_commit(struct server *srv);
void server_scene_changed(struct server *srv, bool changed);
void server_get_status(struct server *srv, struct server_status *out);
void server_capture_requested(struct server *srv);

/* For the pipeline: volume seq was swapped in at time_ns; shown then if
 * the projector is lit, else once it is (server_projector_lit()). */
void server_volume_shown(struct server *srv, uint64_t seq, int64_t time_ns);
/* For the pipeline: frame callbacks were tied to the volume last
 * rendered, which may be on display already: they are answered at the
 * next revolution start (server_revolution()). */
void server_frames_waiting(struct server *srv);
/* For the devices: the projector was lit at time_ns. */
void server_projector_lit(struct server *srv, int64_t time_ns);
/* For the devices: a revolution started at time_ns, the projector lit.
 * Cheap when no frame callback waits. */
void server_revolution(struct server *srv, int64_t time_ns);
/* The volume on display: as the projector holds it when it can tell,
 * else as the daemon sent it; NULL before the first. */
const struct volume *server_shown(struct server *srv);
/* Answers waiting captures with the volume shown now. */
void server_serve_captures(struct server *srv, const struct volume *shown);

#endif
