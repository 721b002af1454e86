#include "server.h"

#include <errno.h>
#include <grp.h>
#include <malloc.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <systemd/sd-daemon.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "admission.h"
#include "cache.h"
#include "client.h"
#include "devices.h"
#include "listen_socket.h"
#include "log.h"
#include "pipeline.h"
#include "privilege.h"
#include "process.h"
#include "render.h"
#include "watchdog.h"

/* ---- admitting clients ---- */

/* Tells a client over a limit why, as far as its socket takes it
 * without waiting, and closes it. */
static void refuse_client(int fd, const char *why, uint32_t clients)
{
	struct proto_conn *conn = proto_conn_create(fd, 4096);
	if (!conn)
		return; /* fd closed */
	char text[120];
	snprintf(text, sizeof(text), "%s: %u connected", why, clients);
	proto_ev_display_error(conn, 1, 1, PROTO_ERR_TOO_MANY_CLIENTS, text);
	proto_conn_flush(conn);
	proto_conn_destroy(conn);
}

/* At most one line a second about refused clients. */
static void log_refusal(struct server *srv, enum admission_verdict v, uid_t uid)
{
	if (!log_ratelimit_ok(&srv->refusal_log))
		return;
	log_warn("refusing a client (uid %u): %s; %u connected; %llu more refused since the last message",
		 (unsigned)uid, admission_reason(v), srv->client_count,
		 (unsigned long long)srv->refusal_log.suppressed);
	srv->refusal_log.suppressed = 0;
}

/* What is connected, as a new peer of uid sees it: a client that is gone
 * holds no slot, even before reap() frees it (it runs after the events
 * already pending, so a burst of connections would find it counted). */
static void admission_load(struct server *srv, uid_t uid, struct admission_load *out)
{
	*out = (struct admission_load){ 0 };
	struct client *c;
	link_for_each(c, &srv->clients, link) {
		if (c->dead)
			continue;
		out->clients++;
		out->incomplete += !c->version && !c->admin;
		out->same_user += c->uid == uid && !c->admin;
	}
}

/* 0 to serve cfd; else it was refused, and is closed. */
static int admit(struct server *srv, int cfd)
{
	struct ucred cred;
	socklen_t len = sizeof(cred);
	if (getsockopt(cfd, SOL_SOCKET, SO_PEERCRED, &cred, &len) < 0) {
		close(cfd);
		return -1;
	}
	struct admission_load load;
	admission_load(srv, cred.uid, &load);
	bool admin = client_peer_is_admin(srv->client_env.admin_gid, cfd, &cred);
	enum admission_verdict v = admission_check(&srv->cfg, admin, &load);
	if (v == ADMISSION_OK)
		return 0;
	srv->admission.refused[v]++;
	log_refusal(srv, v, cred.uid);
	refuse_client(cfd, admission_reason(v), srv->client_count);
	return -1;
}

static void accepted(void *data, int fd)
{
	struct server *srv = data;
	if (admit(srv, fd) < 0)
		return;
	int r = server_add_client(srv, fd);
	if (r < 0)
		log_warn("cannot set up a client: %s", strerror(-r));
	else
		log_debug("client %d connected", fd);
}

static const struct listen_socket_listener listen_socket_listener = {
	.version = LISTEN_SOCKET_LISTENER_VERSION,
	.accepted = accepted,
};

/* Connections that have not said hello within handshake-timeout-ms are
 * closed (checked with the state events, 20 times a second). */
static void expire_handshakes(struct server *srv)
{
	int64_t limit = now_ns() - (int64_t)srv->cfg.handshake_timeout_ms * 1000000;
	struct client *c;
	link_for_each(c, &srv->clients, link) {
		if (c->version || c->dead || c->connected_ns > limit)
			continue;
		srv->admission.handshake_timeouts++;
		client_fail(c, 1, PROTO_ERR_VERSION, "no hello within %u ms", srv->cfg.handshake_timeout_ms);
	}
}

/* ---- clients ---- */

#define TRIM_AFTER_BYTES (8u << 20)

static int reap(sd_event_source *s, void *data)
{
	struct server *srv = data;
	struct client *c, *tmp;
	bool changed = false;
	uint64_t freed = 0;
	link_for_each_safe(c, tmp, &srv->clients, link) {
		if (!c->dead)
			continue;
		changed |= c->left_scene;
		freed += c->buffer_bytes + c->vertices * CLIENT_VERTEX_BYTES;
		link_remove(&c->link);
		srv->client_count--;
		log_debug("client %d disconnected", proto_conn_get_fd(c->conn));
		client_destroy(c);
	}
	sd_event_source_set_enabled(srv->reap_source, SD_EVENT_OFF);
	srv->dead_since_ns = 0;
	/* Give what large clients held back to the system, not just to
	 * malloc's free lists. */
	if (freed >= TRIM_AFTER_BYTES)
		malloc_trim(0);
	if (changed)
		stage_changed(&srv->stage);
	return 0;
}

static void client_dead(void *data, struct client *c)
{
	struct server *srv = data;
	if (!srv->dead_since_ns)
		srv->dead_since_ns = now_ns();
	sd_event_source_set_enabled(srv->reap_source, SD_EVENT_ONESHOT);
}

static void client_status(void *data, struct proto_display_status_args *out)
{
	server_get_status(data, out);
}

static void client_service(void *data, struct proto_display_service_args *out)
{
	struct server *srv = data;
	struct watchdog_stats ws = { 0 };
	if (srv->watchdog)
		watchdog_get_stats(srv->watchdog, &ws);
	*out = (struct proto_display_service_args){
		.watchdog_ms = (uint32_t)(ws.interval_ns / 1000000),
		.watchdog_fed = ws.fed,
		.watchdog_withheld = ws.withheld,
		.max_client_fds = srv->cfg.max_client_fds,
		.refused_fds = srv->totals.refused_fds,
	};
}

static void client_watchers(void *data, struct proto_display_watchers_args *out)
{
	struct server *srv = data;
	const struct watch_stats *st = &srv->watch.stats;
	*out = (struct proto_display_watchers_args){
		.watchers = srv->watch.count,
		.max_watchers = srv->cfg.max_watchers,
		.max_rate_hz = srv->cfg.max_watch_rate,
		.volumes_sent = st->sent,
		.volumes_skipped = st->skipped,
		.bytes_sent = st->bytes,
		.refused = st->refused,
		.denied = st->denied,
	};
}

static void client_composition(void *data, struct proto_display_composition_args *out)
{
	server_get_composition(data, out);
}

static void client_limits(void *data, struct proto_display_limits_args *out)
{
	server_get_limits(data, out);
}

static void client_calibration(void *data, struct calibration *out)
{
	struct server *srv = data;
	*out = srv->cfg.calibration;
}

static int client_calibrate(void *data, unsigned key, double value, uid_t uid)
{
	struct server *srv = data;
	struct calibration cal = srv->cfg.calibration;
	if (calibration_set(&cal, key, value) < 0 || calibration_check(&cal, &srv->geom) < 0)
		return -EINVAL;
	char text[32];
	calibration_format(&cal, key, text, sizeof(text));
	log_info("calibration: %s = %s (set by uid %u)", calibration_key_name(key), text, (unsigned)uid);
	srv->cfg.calibration = cal;
	pipeline_set_calibration(srv->pipe, &cal);
	return 0;
}

static const struct client_listener client_listener = {
	.version = CLIENT_LISTENER_VERSION,
	.dead = client_dead,
	.status = client_status,
	.limits = client_limits,
	.composition = client_composition,
	.watchers = client_watchers,
	.calibration = client_calibration,
	.calibrate = client_calibrate,
	.service = client_service,
};

/* ---- the stage, frames and captures ---- */

/* The object cache yields to the clients: it holds at most what of
 * memory-budget they leave (and cache-budget), so that clients and cache
 * together stay within memory-budget; it evicts down to that at the next
 * volume. */
static void cache_budget(struct server *srv)
{
	const struct client_totals *t = &srv->totals;
	uint64_t used = t->buffer_bytes + t->vertices * CLIENT_VERTEX_BYTES;
	uint64_t left = srv->cfg.memory_budget > used ? srv->cfg.memory_budget - used : 0;
	pipeline_set_cache_budget(srv->pipe, left < srv->cfg.cache_budget ? left : srv->cfg.cache_budget);
}

static void scene_changed(void *data)
{
	struct server *srv = data;
	if (!srv->pipe)
		return;
	cache_budget(srv);
	pipeline_mark_dirty(srv->pipe);
}

static const struct stage_listener stage_listener = {
	.version = STAGE_LISTENER_VERSION,
	.changed = scene_changed,
};

static void frame_done(void *data, struct waiter *w, uint64_t seq, int64_t time_ns)
{
	client_frame_done(w, seq, time_ns);
}

static void capture_done(void *data, struct waiter *w, int fd, uint64_t size)
{
	client_capture_done(w, fd, size);
}

static void answered(void *data)
{
	struct server *srv = data;
	struct client *c;
	link_for_each(c, &srv->clients, link)
		client_flush_answered(c);
}

static const struct frames_listener frames_listener = {
	.version = FRAMES_LISTENER_VERSION,
	.frame_done = frame_done,
	.capture_done = capture_done,
	.answered = answered,
};

/* The volume on display: as the projector holds it when it can tell, else
 * as the daemon sent it, else (nothing shown yet) the empty volume (NULL
 * when out of memory). */
static const struct volume *shown_volume(struct server *srv)
{
	const struct volume *v = srv->dev ? devices_shown(srv->dev) : NULL;
	if (!v && srv->pipe)
		v = pipeline_shown(srv->pipe);
	if (!v && !srv->empty && !(srv->empty = volume_create(&srv->geom)))
		log_error("capture: out of memory for the empty volume");
	return v ? v : srv->empty;
}

/* Waiting captures get the volume on display. */
static void serve_captures(struct server *srv)
{
	if (!frames_capture_waiting(&srv->frames))
		return;
	frames_serve_captures(&srv->frames, shown_volume(srv));
}

/* Watchers due get the volume on display; the timer wakes the loop for
 * the next one that waits for its rate. A single test without watchers. */
static void serve_watchers(struct server *srv)
{
	if (!watch_any(&srv->watch) || !srv->pipe)
		return;
	watch_serve(&srv->watch, shown_volume(srv), now_ns());
	int64_t due = watch_next_due(&srv->watch);
	if (!srv->watch_timer)
		return;
	if (due > 0) {
		sd_event_source_set_time(srv->watch_timer, (uint64_t)due / 1000 + 1);
		sd_event_source_set_enabled(srv->watch_timer, SD_EVENT_ONESHOT);
	} else {
		sd_event_source_set_enabled(srv->watch_timer, SD_EVENT_OFF);
	}
}

static int on_watch_timer(sd_event_source *s, uint64_t usec, void *data)
{
	serve_watchers(data);
	return 0;
}

static void watch_send(void *data, struct watch_entry *w, int fd, uint64_t size, uint64_t seq, uint64_t skipped)
{
	client_watch_send(w, fd, size, seq, skipped);
}

static void watch_wake(void *data)
{
	serve_watchers(data);
}

static void answered(void *data);

static const struct watch_listener watch_listener = {
	.version = WATCH_LISTENER_VERSION,
	.send = watch_send,
	.answered = answered,
	.wake = watch_wake,
};

/* ---- the pipeline ---- */

static void scene_taken(void *data, uint64_t seq, bool unchanged)
{
	struct server *srv = data;
	if (frames_tie(&srv->frames, seq) && unchanged)
		frames_wait_revolution(&srv->frames);
}

static void volume_shown(void *data, uint64_t seq, int64_t time_ns)
{
	struct server *srv = data;
	if (frames_shown(&srv->frames, seq, time_ns, devices_lit(srv->dev)))
		serve_captures(srv);
	serve_watchers(srv);
}

static const struct pipeline_listener pipeline_listener = {
	.version = PIPELINE_LISTENER_VERSION,
	.scene_taken = scene_taken,
	.shown = volume_shown,
};

/* ---- the devices ---- */

static void projector_lit(void *data, int64_t time_ns)
{
	struct server *srv = data;
	srv->revolution_ns = time_ns;
	if (frames_lit(&srv->frames, time_ns))
		serve_captures(srv);
	serve_watchers(srv);
}

static void revolution(void *data, int64_t time_ns)
{
	struct server *srv = data;
	srv->revolution_ns = time_ns;
	if (srv->pipe) /* none while setting up */
		frames_revolution(&srv->frames, time_ns, pipeline_swap_pending(srv->pipe));
	serve_watchers(srv);
}

static void half_turn(void *data, int64_t time_ns)
{
	revolution(data, time_ns); /* a boundary as good as a revolution start */
}

/* A capture takes the volume on display at a revolution start. */
static void synced(void *data)
{
	serve_captures(data);
}

static void push_state(struct server *srv);

static void devices_state_changed(void *data)
{
	push_state(data);
}

static void swapped(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	struct server *srv = data;
	if (srv->pipe) /* none while setting up */
		pipeline_swapped(srv->pipe, buffer, time_ns, seq);
}

static void buffer_error(void *data, uint32_t buffer, int err)
{
	struct server *srv = data;
	if (srv->pipe) /* none while setting up */
		pipeline_device_error(srv->pipe, buffer, err);
}

static void projector_gone(void *data)
{
	struct server *srv = data;
	if (srv->pipe) /* none while setting up */
		pipeline_projector_gone(srv->pipe);
}

static void projector_arrived(void *data)
{
	struct server *srv = data;
	if (srv->pipe) /* none while setting up */
		pipeline_projector_arrived(srv->pipe);
}

static const struct devices_listener devices_listener = {
	.version = DEVICES_LISTENER_VERSION,
	.lit = projector_lit,
	.revolution = revolution,
	.half_turn = half_turn,
	.synced = synced,
	.state_changed = devices_state_changed,
	.swapped = swapped,
	.buffer_error = buffer_error,
	.gone = projector_gone,
	.arrived = projector_arrived,
};

/* ---- status and state events ---- */

/* Clients past the handshake and not being dropped. */
static uint32_t active_clients(struct server *srv)
{
	uint32_t n = 0;
	struct client *c;
	link_for_each(c, &srv->clients, link)
		n += c->version && !c->dead;
	return n;
}

void server_get_status(struct server *srv, struct proto_display_status_args *out)
{
	struct devices_status ds;
	struct pipeline_stats ps;
	devices_get_status(srv->dev, &ds);
	pipeline_get_stats(srv->pipe, &ps);
	*out = (struct proto_display_status_args){
		.rpm = ds.rpm,
		.flags = (ds.locked ? PROTO_DISPLAY_STATUS_FLAGS_LOCKED : 0) |
			 (ds.blanked ? PROTO_DISPLAY_STATUS_FLAGS_BLANKED : 0) |
			 (ds.projector_present ? PROTO_DISPLAY_STATUS_FLAGS_PROJECTOR_PRESENT : 0),
		.volumes_shown = ps.volumes_shown,
		.underruns = ds.underruns,
		.clients = active_clients(srv),
		.volumes_rendered = ps.volumes_rendered,
		.volumes_skipped = ps.volumes_skipped,
		.bytes_uploaded = ps.bytes_uploaded,
		.render_us = ps.last_render_us,
		.jitter_us = ds.jitter_us,
		.missed_pulses = ds.missed_pulses,
		.upload_rate = ds.upload_rate,
		.index_error_us = ds.index_error_us,
		.angle_error_p99 = ds.angle_error_p99,
		.angle_error_max = ds.angle_error_max,
	};
}

void server_get_composition(struct server *srv, struct proto_display_composition_args *out)
{
	struct cache_stats st;
	*out = (struct proto_display_composition_args){ 0 };
	if (!srv->pipe || !pipeline_get_cache_stats(srv->pipe, &st))
		return;
	*out = (struct proto_display_composition_args){
		.flags = PROTO_DISPLAY_COMPOSITION_FLAGS_CACHE,
		.objects = st.objects,
		.cached = st.cached,
		.cache_bytes = st.bytes,
		.cache_budget = st.budget,
		.hits = st.hits,
		.misses = st.misses,
		.creates = st.creates,
		.invalidations = st.invalidations,
		.evictions = st.evictions,
		.objects_rendered = st.last_rendered,
		.objects_reused = st.last_reused,
		.render_us = st.last_render_us,
		.compose_us = st.last_compose_us,
	};
}

void server_get_limits(struct server *srv, struct proto_display_limits_args *out)
{
	const struct admission_counters *a = &srv->admission;
	const struct client_totals *t = &srv->totals;
	struct rlimit rl = { 0 };
	getrlimit(RLIMIT_NOFILE, &rl);
	uint32_t incomplete = 0;
	struct client *c;
	link_for_each(c, &srv->clients, link)
		incomplete += !c->version && !c->dead;
	*out = (struct proto_display_limits_args){
		.refused_clients = a->refused[ADMISSION_FULL],
		.refused_per_user = a->refused[ADMISSION_USER],
		.refused_incomplete = a->refused[ADMISSION_INCOMPLETE],
		.handshake_timeouts = a->handshake_timeouts,
		.accept_pauses = srv->sock.pauses,
		.clients_in_handshake = incomplete,
		.fds = process_open_fds(),
		.fd_limit = rl.rlim_cur > UINT32_MAX ? UINT32_MAX : (uint32_t)rl.rlim_cur,
		.memory_used = t->buffer_bytes + t->vertices * CLIENT_VERTEX_BYTES,
		.memory_budget = srv->cfg.memory_budget,
		.refused_memory = t->refused_memory,
		.mappings = t->mappings,
		.mapping_budget = srv->cfg.max_mappings,
		.refused_mappings = t->refused_mappings,
	};
}

/* Tells version 2 clients of a change of state (a flag, or rpm by 1% of
 * nominal): when the devices report one, and 20 times a second for rpm. */
#define STATE_INTERVAL_US 50000

static void push_state(struct server *srv)
{
	if (!srv->pipe)
		return; /* still setting up */
	struct proto_display_status_args st;
	server_get_status(srv, &st);
	struct client *c;
	link_for_each(c, &srv->clients, link)
		client_send_state(c, &st, false);
}

static int on_state_timer(sd_event_source *s, uint64_t usec, void *data)
{
	struct server *srv = data;
	srv->state_ns = now_ns();
	expire_handshakes(data);
	/* A dark display (not turning, or no timing yet) has no revolution
	 * to wait for: captures get what it holds at once. */
	if (srv->dev && !devices_lit(srv->dev)) {
		serve_captures(srv);
		serve_watchers(srv);
	}
	push_state(data);
	sd_event_source_set_time(s, usec + STATE_INTERVAL_US);
	return 0;
}

static int setup_state_timer(struct server *srv)
{
	uint64_t now;
	sd_event_now(srv->event, CLOCK_MONOTONIC, &now);
	int r = sd_event_add_time(srv->event, &srv->state_timer, CLOCK_MONOTONIC, now + STATE_INTERVAL_US, 10000,
				  on_state_timer, srv);
	if (r >= 0)
		r = sd_event_source_set_enabled(srv->state_timer, SD_EVENT_ON);
	return r;
}

/* The admin group's gid, when it exists. */
static gid_t admin_gid(const char *name)
{
	if (!*name)
		return (gid_t)-1;
	struct group *g = getgrnam(name);
	if (!g) {
		log_debug("admin group '%s' does not exist: capture and exclusive layers for root and the daemon's "
			  "user only",
			  name);
		return (gid_t)-1;
	}
	return g->gr_gid;
}

/* ---- set-up and the loop ---- */

static int setup_loop(struct server *srv)
{
	int r = sd_event_new(&srv->event);
	if (r < 0)
		return r;
	if ((r = process_setup_signals(srv->event)) < 0 ||
	    (r = sd_event_add_defer(srv->event, &srv->reap_source, reap, srv)) < 0)
		return r;
	sd_event_source_set_enabled(srv->reap_source, SD_EVENT_OFF);
	sd_event_source_set_priority(srv->reap_source, SD_EVENT_PRIORITY_NORMAL + 10);
	return 0;
}

/* What the watchdog asks: work pending for half its interval is stuck.
 * The state timer runs 20 times a second at the clients' priority, so a
 * loop that spins on one source without serving the rest shows there;
 * dead clients wait for the reap, which runs after the clients' events; a
 * render runs on its own thread; and a lit projector is locked to a
 * rotor whose revolutions the devices report. */
static const char *stalled(void *data, int64_t now, int64_t interval)
{
	struct server *srv = data;
	int64_t patience = interval / 2;
	if (srv->state_ns && now - srv->state_ns > patience)
		return "the event loop is not serving (the state timer is late)";
	if (srv->dead_since_ns && now - srv->dead_since_ns > patience)
		return "disconnected clients are not being freed";
	int64_t started = pipeline_render_started(srv->pipe);
	if (started && now - started > patience)
		return "a render is taking too long (render thread stuck?)";
	if (devices_lit(srv->dev) && srv->revolution_ns && now - srv->revolution_ns > patience)
		return "the projector is lit but no revolution has been reported";
	return NULL;
}

static const struct watchdog_listener watchdog_listener = {
	.version = WATCHDOG_LISTENER_VERSION,
	.stalled = stalled,
};

static int setup_render(struct server *srv)
{
	const struct config *cfg = &srv->cfg;
	struct renderer *r = render_create(cfg->renderer, &srv->geom, cfg->render_threads);
	if (!r && strcmp(cfg->renderer, "cpu") != 0) {
		log_warn("renderer '%s' unavailable (%s): using the CPU renderer", cfg->renderer, strerror(errno));
		r = render_create("cpu", &srv->geom, cfg->render_threads);
	}
	if (!r)
		return -errno;
	log_info("renderer: %s", r->impl->name);
	log_info("brightness: %s", geometry_brightness_name(srv->geom.brightness));
	struct pipeline_config pc = {
		.event = srv->event,
		.stage = &srv->stage,
		.devices = srv->dev,
		.max_scene_primitives = cfg->max_scene_primitives,
		.cache = cfg->cache,
		.cache_budget = cfg->cache_budget,
		.threads = cfg->render_threads,
		.calibration = cfg->calibration,
	};
	srv->pipe = pipeline_create(&pc, r, &pipeline_listener, srv);
	return srv->pipe ? 0 : -errno;
}

void server_finish(struct server *srv)
{
	struct client *c, *tmp;
	link_for_each_safe(c, tmp, &srv->clients, link) {
		c->dead = true; /* no new volumes for departing clients */
		link_remove(&c->link);
		client_destroy(c);
	}
	pipeline_destroy(srv->pipe);
	volume_destroy(srv->empty);
	watch_fini(&srv->watch);
	sd_event_source_disable_unref(srv->watch_timer);
	srv->pipe = NULL;          /* the devices may still report while they close */
	devices_destroy(srv->dev); /* blanks the projector */
	watchdog_destroy(srv->watchdog);
	sd_event_source_disable_unref(srv->reap_source);
	sd_event_source_disable_unref(srv->state_timer);
	listen_socket_close(&srv->sock);
	sd_event_unref(srv->event);
	*srv = (struct server){ .sock.fd = -1 };
}

/* What every client shares. */
static void set_client_env(struct server *srv)
{
	srv->client_env = (struct client_env){
		.event = srv->event,
		.cfg = &srv->cfg,
		.geom = &srv->geom,
		.device_name = devices_name(srv->dev),
		.admin_gid = admin_gid(srv->cfg.admin_group),
		.stage = &srv->stage,
		.frames = &srv->frames,
		.watch = &srv->watch,
		.totals = &srv->totals,
		.listener = &client_listener,
		.data = srv,
	};
}

int server_init(struct server *srv, const struct config *cfg, bool listen)
{
	*srv = (struct server){ .cfg = *cfg, .sock.fd = -1, .refusal_log.interval_ns = 1000000000 };
	link_init(&srv->clients);
	stage_init(&srv->stage, &stage_listener, srv);
	frames_init(&srv->frames, &frames_listener, srv);
	watch_init(&srv->watch, cfg->max_watchers, cfg->max_watch_rate, &watch_listener, srv);
	int r = geometry_from_profile(cfg->profile, &srv->geom);
	if (r < 0) {
		log_error("unknown profile '%s'", cfg->profile);
		return r;
	}
	srv->geom.brightness = cfg->brightness;
	if (calibration_check(&cfg->calibration, &srv->geom) < 0) {
		log_error("axis-offset-u %d or axis-offset-v %d: more than a quarter of the image (%ux%u)",
			  cfg->calibration.axis_u, cfg->calibration.axis_v, srv->geom.width, srv->geom.height);
		return -EINVAL;
	}
	if ((r = setup_loop(srv)) < 0) {
		log_error("event loop: %s", strerror(-r));
		return r;
	}
	srv->dev = devices_create(srv->event, &srv->cfg, &srv->geom, &devices_listener, srv);
	if (!srv->dev) {
		r = -errno;
		log_error("devices: %s", strerror(errno));
		return r;
	}
	if ((r = setup_render(srv)) < 0) {
		log_error("renderer: %s", strerror(-r));
		return r;
	}
	set_client_env(srv);
	if ((r = setup_state_timer(srv)) < 0)
		return r;
	if ((r = sd_event_add_time(srv->event, &srv->watch_timer, CLOCK_MONOTONIC, 0, 1000, on_watch_timer, srv)) < 0 ||
	    (r = sd_event_source_set_enabled(srv->watch_timer, SD_EVENT_OFF)) < 0)
		return r;
	if (!listen)
		return 0;
	return listen_socket_open(&srv->sock, srv->event, srv->cfg.socket_path, &listen_socket_listener, srv);
}

int server_add_client(struct server *srv, int fd)
{
	struct client *c = client_create(&srv->client_env, fd);
	if (!c)
		return -errno;
	link_append(&srv->clients, &c->link);
	srv->client_count++;
	return 0;
}

/* What the limits did, for the log at exit. */
static void log_admission(const struct server *srv)
{
	const struct admission_counters *a = &srv->admission;
	log_info("clients refused: %llu over max-clients, %llu over max-clients-per-user, %llu over "
		 "max-incomplete-clients; %llu closed for no hello in time; accepting paused %llu times (out of fds)",
		 (unsigned long long)a->refused[ADMISSION_FULL], (unsigned long long)a->refused[ADMISSION_USER],
		 (unsigned long long)a->refused[ADMISSION_INCOMPLETE], (unsigned long long)a->handshake_timeouts,
		 (unsigned long long)srv->sock.pauses);
}

int server_run(const struct config *cfg)
{
	struct server srv;
	process_raise_fd_limit();
	int r = server_init(&srv, cfg, true);
	if (r < 0)
		goto out;
	/* The devices, the renderer and the socket are open: root is no
	 * longer needed. A failed drop may leave the ids half switched. */
	if ((r = privilege_drop(srv.cfg.user)) < 0) {
		log_error("not serving: could not give up root");
		goto out;
	}
	log_info("ready: %s, %ux%u, %u images per revolution%s, %.0f rpm", devices_name(srv.dev), srv.geom.width,
		 srv.geom.height, srv.geom.images_per_rev, srv.geom.mirrored ? " (mirrored)" : "", srv.geom.rpm);
	sd_notify(0, "READY=1\nSTATUS=Serving clients");
	if (!(srv.watchdog = watchdog_create(srv.event, &watchdog_listener, &srv))) {
		r = -errno;
		log_error("cannot set up the watchdog: %s", strerror(errno));
		goto out;
	}
	r = sd_event_loop(srv.event);
	sd_notify(0, "STOPPING=1");
	log_admission(&srv);
out:
	server_finish(&srv);
	return r < 0 ? 1 : 0;
}
