/* Client connections: reading, dispatching to objects, the display
 * object's requests, and disconnecting a client that misbehaves. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "client.h"
#include "config.h"
#include "geometry.h"
#include "log.h"
#include "stage.h"

/* Events a client may leave unread before it is cut off. */
#define CLIENT_MAX_OUT (1u << 20)
/* Reads per wake-up, so that one busy client cannot starve the others. */
#define CLIENT_READS_PER_WAKEUP 16

/* Stops serving c: its layers leave the stage now; it is freed from the
 * event loop soon (its listener's dead()). */
static void client_kill(struct client *c)
{
	c->dead = true;
	volumes_cancel_build(c);
	c->left_scene = objects_leave_stage(c);
	objects_leave_watch(c);
	/* A closed socket stays readable: stop listening, or the loop spins. */
	sd_event_source_set_enabled(c->source, SD_EVENT_OFF);
	c->env->listener->dead(c->env->data, c);
}

int client_fail(struct client *c, uint32_t object, uint32_t code, const char *fmt, ...)
{
	char text[256];
	va_list ap;
	if (c->dead)
		return -EPROTO;
	va_start(ap, fmt);
	vsnprintf(text, sizeof(text), fmt, ap);
	va_end(ap);
	log_info("client %d (pid %d): protocol error on object %u: %s", proto_conn_get_fd(c->conn), (int)c->pid, object,
		 text);
	proto_ev_display_error(c->conn, 1, object, code, text);
	proto_conn_flush(c->conn);
	client_kill(c);
	return -EPROTO;
}

void client_flush(struct client *c)
{
	if (c->dead)
		return;
	int r = proto_conn_flush(c->conn);
	/* Not read while a volume of its own is being made. */
	uint32_t in = c->building ? 0 : EPOLLIN;
	if (r == -EAGAIN) {
		sd_event_source_set_io_events(c->source, in | EPOLLOUT);
	} else if (r < 0) {
		log_debug("client %d: write failed: %s", proto_conn_get_fd(c->conn), strerror(-r));
		client_kill(c);
	} else {
		sd_event_source_set_io_events(c->source, in);
	}
}

/* After queueing an event: a client whose queue overflowed is cut off. */
static void client_sent(struct client *c, int r)
{
	if (r == -ENOBUFS) {
		log_info("client %d (pid %d) does not read its events: disconnected", proto_conn_get_fd(c->conn),
			 (int)c->pid);
		client_kill(c);
	}
}

/* ---- the display object ---- */

static int display_hello(void *target, const struct proto_display_hello_args *a)
{
	struct client *c = target;
	const struct client_env *env = c->env;
	if (c->version)
		return client_fail(c, 1, PROTO_ERR_VERSION, "hello sent twice");
	if (a->version == 0)
		return client_fail(c, 1, PROTO_ERR_VERSION, "no common protocol version");
	c->version = a->version < PROTO_VERSION ? a->version : PROTO_VERSION;
	const struct geometry *g = env->geom;
	proto_ev_display_welcome(c->conn, 1, c->version);
	int r = proto_ev_display_device(c->conn, 1, g->width, g->height, g->images_per_rev,
					g->mirrored ? PROTO_DISPLAY_DEVICE_FLAGS_MIRRORED : 0, g->half_height, g->rpm,
					env->device_name);
	client_sent(c, r);
	if (c->version >= 2) {
		struct proto_display_status_args st;
		env->listener->status(env->data, &st);
		client_send_state(c, &st, true);
	}
	return 0;
}

void client_send_state(struct client *c, const struct proto_display_status_args *st, bool force)
{
	if (c->dead || c->version < 2)
		return;
	float step = c->env->geom->rpm * 0.01f;
	if (!force && st->flags == c->state_flags && fabsf(st->rpm - c->state_rpm) < step)
		return;
	c->state_flags = st->flags;
	c->state_rpm = st->rpm;
	client_sent(c, proto_ev_display_state(c->conn, 1, st->flags, st->rpm));
	client_flush(c);
}

bool client_may_be_exclusive(const struct client *c)
{
	switch (c->env->cfg->exclusive) {
	case POLICY_NONE:
		return false;
	case POLICY_ADMIN:
		return c->admin;
	case POLICY_ANY:
		return true;
	}
	return false;
}

/* A new frame callback or capture object, not queued anywhere yet. */
static struct callback *new_callback(struct client *c, uint32_t id, enum proto_interface type)
{
	struct callback *cb = calloc(1, sizeof(*cb));
	if (!cb) {
		client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
		return NULL;
	}
	link_init(&cb->wait.link);
	if (object_register(c, &cb->base, id, type) < 0) {
		free(cb);
		return NULL;
	}
	return cb;
}

void client_frame_done(struct waiter *w, uint64_t seq, int64_t time_ns)
{
	struct callback *cb = link_entry(w, struct callback, wait);
	struct client *c = cb->base.client;
	if (!c->dead) {
		client_sent(c, proto_ev_callback_done(c->conn, cb->base.id, seq, (uint64_t)time_ns));
		c->answered = true;
	}
	object_destroy(&cb->base);
}

void client_capture_done(struct waiter *w, int fd, uint64_t size)
{
	struct callback *cb = link_entry(w, struct callback, wait);
	struct client *c = cb->base.client;
	if (!c->dead) {
		if (fd >= 0)
			client_sent(c, proto_ev_capture_ready(c->conn, cb->base.id, fd, size));
		else
			client_sent(c, proto_ev_capture_failed(c->conn, cb->base.id, PROTO_CAPTURE_FAILURE_ERROR,
							       strerror(-fd)));
		c->answered = true;
	}
	object_destroy(&cb->base);
}

void client_watch_send(struct watch_entry *w, int fd, uint64_t size, uint64_t seq, uint64_t skipped)
{
	struct watcher *wa = link_entry(w, struct watcher, entry);
	struct client *c = wa->base.client;
	if (c->dead)
		return;
	if (fd >= 0) {
		client_sent(c, proto_ev_watcher_volume(c->conn, wa->base.id, fd, size, seq, skipped));
	} else {
		client_sent(c,
			    proto_ev_watcher_failed(c->conn, wa->base.id, PROTO_WATCHER_FAILURE_ERROR, strerror(-fd)));
		object_destroy(&wa->base);
	}
	c->answered = true;
}

void client_flush_answered(struct client *c)
{
	if (!c->answered)
		return;
	c->answered = false;
	client_flush(c);
}

static int display_sync(void *target, const struct proto_display_sync_args *a)
{
	struct client *c = target;
	if (a->callback < 2 || a->callback > 0xfeffffffu || idmap_get(&c->objects, a->callback))
		return client_fail(c, 1, PROTO_ERR_OBJECT, "sync: bad new id %u", a->callback);
	client_sent(c, proto_ev_callback_done(c->conn, a->callback, 0, 0));
	return 0;
}

static int display_create_buffer(void *target, const struct proto_display_create_buffer_args *a)
{
	return objects_create_buffer(target, a->id, a->size, a->fd);
}

static int display_create_volume(void *target, const struct proto_display_create_volume_args *a)
{
	return objects_create_volume(target, a);
}

static int display_create_buffer_inline(void *target, const struct proto_display_create_buffer_inline_args *a)
{
	return objects_create_buffer_inline(target, a->id, a->data, a->data_size);
}

static int display_create_list(void *target, const struct proto_display_create_list_args *a)
{
	return objects_create_list(target, a->id);
}

static int display_create_layer(void *target, const struct proto_display_create_layer_args *a)
{
	return objects_create_layer(target, a->id);
}

static int display_frame(void *target, const struct proto_display_frame_args *a)
{
	struct client *c = target;
	struct callback *cb = new_callback(c, a->callback, PROTO_IFACE_CALLBACK);
	if (!cb)
		return -EPROTO;
	link_append(&c->frames_pending, &cb->wait.link);
	return 0;
}

/* A refused commit changes nothing: its changes and frames stay pending. */
static bool commit_refused(struct client *c)
{
	char text[200];
	uint32_t object = 1;
	uint32_t code = objects_commit_check(c, &object, text, sizeof(text));
	if (!code)
		return false;
	if (c->version < 2) {
		client_fail(c, object, PROTO_ERR_QUOTA, "%s", text); /* no refused event at version 1 */
		return true;
	}
	log_debug("client %d: commit refused: %s", proto_conn_get_fd(c->conn), text);
	client_sent(c, proto_ev_display_refused(c->conn, 1, object, code, text));
	return true;
}

static int display_commit(void *target)
{
	struct client *c = target;
	struct waiter *w, *tmp;
	if (commit_refused(c))
		return 0;
	int64_t now = now_ns();
	bool frames = !link_empty(&c->frames_pending);
	link_for_each_safe(w, tmp, &c->frames_pending, link)
		frames_commit(c->env->frames, w, now);
	bool changed = objects_commit(c);
	if (!c->dead && (changed || frames))
		stage_changed(c->env->stage);
	return 0;
}

static void send_calibration(struct client *c)
{
	struct calibration cal;
	c->env->listener->calibration(c->env->data, &cal);
	client_sent(c, proto_ev_display_calibration(c->conn, 1, cal.phase_deg, cal.axis_u, cal.axis_v,
						    cal.vertical_scale, cal.vertical_offset));
}

static int display_get_status(void *target)
{
	struct client *c = target;
	if (c->version >= 3) {
		struct proto_display_limits_args lim;
		c->env->listener->limits(c->env->data, &lim);
		client_sent(c, proto_ev_display_limits(c->conn, 1, &lim));
	}
	if (c->version >= 4) {
		struct proto_display_service_args svc;
		c->env->listener->service(c->env->data, &svc);
		client_sent(c, proto_ev_display_service(c->conn, 1, svc.watchdog_ms, svc.watchdog_fed,
							svc.watchdog_withheld, svc.max_client_fds, svc.refused_fds));
		struct proto_display_composition_args comp;
		c->env->listener->composition(c->env->data, &comp);
		client_sent(c, proto_ev_display_composition(c->conn, 1, &comp));
	}
	if (c->version >= 5) {
		struct proto_display_watchers_args wa;
		c->env->listener->watchers(c->env->data, &wa);
		client_sent(c, proto_ev_display_watchers(c->conn, 1, wa.watchers, wa.max_watchers, wa.max_rate_hz,
							 wa.volumes_sent, wa.volumes_skipped, wa.bytes_sent, wa.refused,
							 wa.denied));
	}
	if (c->version >= 6)
		send_calibration(c);
	struct proto_display_status_args st;
	c->env->listener->status(c->env->data, &st);
	client_sent(c, proto_ev_display_status(c->conn, 1, &st));
	return 0;
}

static int display_capture(void *target, const struct proto_display_capture_args *a)
{
	struct client *c = target;
	struct callback *cb = new_callback(c, a->id, PROTO_IFACE_CAPTURE);
	if (!cb)
		return -EPROTO;
	if (!c->admin) {
		client_sent(c, proto_ev_capture_failed(c->conn, a->id, PROTO_CAPTURE_FAILURE_DENIED,
						       "capture is restricted to root, the daemon's user and the admin "
						       "group"));
		object_destroy(&cb->base);
		return 0;
	}
	frames_capture(c->env->frames, &cb->wait);
	return 0;
}

static int display_watch(void *target, const struct proto_display_watch_args *a)
{
	struct client *c = target;
	if (a->max_rate_hz > 1000)
		return client_fail(c, 1, PROTO_ERR_VALUE, "watch: max_rate_hz %u is over 1000", a->max_rate_hz);
	struct watcher *wa = calloc(1, sizeof(*wa));
	if (!wa)
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	link_init(&wa->entry.link);
	if (object_register(c, &wa->base, a->id, PROTO_IFACE_WATCHER) < 0) {
		free(wa);
		return -EPROTO;
	}
	uint32_t code = 0;
	const char *why = NULL;
	if (!c->admin) {
		watch_count_denied(c->env->watch);
		code = PROTO_WATCHER_FAILURE_DENIED;
		why = "watching is restricted to root, the daemon's user and the admin group";
	} else if (watch_add(c->env->watch, &wa->entry, a->max_rate_hz) < 0) {
		code = PROTO_WATCHER_FAILURE_LIMIT;
		why = "the daemon has max-watchers watchers";
	}
	if (code) {
		client_sent(c, proto_ev_watcher_failed(c->conn, a->id, code, why));
		object_destroy(&wa->base);
	}
	return 0;
}

/* Root or the daemon's own user: who may change the calibration. */
static bool client_privileged(const struct client *c)
{
	return c->uid == 0 || c->uid == geteuid();
}

static int display_calibrate(void *target, const struct proto_display_calibrate_args *a)
{
	struct client *c = target;
	const char *name = calibration_key_name(a->key);
	if (!name)
		return client_fail(c, 1, PROTO_ERR_VALUE, "calibrate: unknown key %u", a->key);
	char text[160];
	uint32_t code = 0;
	if (!client_privileged(c)) {
		code = PROTO_DISPLAY_REFUSAL_DENIED;
		snprintf(text, sizeof(text), "calibration is restricted to root and the daemon's user");
	} else if (c->env->listener->calibrate(c->env->data, a->key, a->value, c->uid) < 0) {
		code = PROTO_DISPLAY_REFUSAL_OUT_OF_RANGE;
		snprintf(text, sizeof(text), "calibrate: %s %g is out of range (spindled(8))", name, (double)a->value);
	}
	if (code)
		client_sent(c, proto_ev_display_refused(c->conn, 1, 1, code, text));
	send_calibration(c);
	return 0;
}

static int watcher_release(void *target)
{
	struct watcher *wa = target;
	watch_release(wa->base.client->env->watch, &wa->entry);
	return 0;
}

static int watcher_destroy(void *target)
{
	object_destroy(target);
	return 0;
}

const struct proto_watcher_requests watcher_requests = {
	.destroy = watcher_destroy,
	.release = watcher_release,
};

static const struct proto_display_requests display_requests = {
	.hello = display_hello,
	.sync = display_sync,
	.create_buffer = display_create_buffer,
	.create_buffer_inline = display_create_buffer_inline,
	.create_list = display_create_list,
	.create_layer = display_create_layer,
	.frame = display_frame,
	.commit = display_commit,
	.get_status = display_get_status,
	.capture = display_capture,
	.watch = display_watch,
	.calibrate = display_calibrate,
	.create_volume = display_create_volume,
};

/* ---- dispatch ---- */

static int dispatch_message(struct client *c, struct proto_message *m)
{
	struct proto_error err = { 0 };
	int r;
	if (m->object == 1) {
		if (!c->version && m->opcode != PROTO_DISPLAY_REQ_HELLO)
			return client_fail(c, 1, PROTO_ERR_VERSION, "the first request must be hello");
		r = proto_display_dispatch_request(&display_requests, c, m, c->version ? c->version : 1, &err);
	} else {
		struct object *obj = idmap_get(&c->objects, m->object);
		if (!c->version)
			return client_fail(c, 1, PROTO_ERR_VERSION, "the first request must be hello");
		if (!obj)
			return client_fail(c, m->object, PROTO_ERR_OBJECT, "no object %u", m->object);
		switch (obj->type) {
		case PROTO_IFACE_BUFFER:
			r = proto_buffer_dispatch_request(&buffer_requests, obj, m, c->version, &err);
			break;
		case PROTO_IFACE_LIST:
			r = proto_list_dispatch_request(&list_requests, obj, m, c->version, &err);
			break;
		case PROTO_IFACE_LAYER:
			r = proto_layer_dispatch_request(&layer_requests, obj, m, c->version, &err);
			break;
		case PROTO_IFACE_WATCHER:
			r = proto_watcher_dispatch_request(&watcher_requests, obj, m, c->version, &err);
			break;
		case PROTO_IFACE_VOLUME:
			r = proto_volume_dispatch_request(&volume_requests, obj, m, c->version, &err);
			break;
		default:
			return client_fail(c, m->object, PROTO_ERR_METHOD, "%s objects take no requests",
					   proto_interface_name(obj->type));
		}
	}
	if (r == -EPROTO && !c->dead)
		return client_fail(c, m->object, err.code, "%s", err.text);
	return r;
}

/* Serves the requests already read, until one makes c wait (building).
 * false: c failed. */
static bool client_dispatch(struct client *c)
{
	struct proto_error err = { 0 };
	struct proto_message m;
	int r = 0;
	while (!c->dead && !c->building && (r = proto_conn_next(c->conn, &m, &err)) == 1)
		dispatch_message(c, &m);
	if (r < 0 && !c->dead)
		client_fail(c, 0, err.code, "%s", err.text);
	return !c->dead;
}

static void client_read(struct client *c)
{
	struct proto_error err = { 0 };
	for (int i = 0; i < CLIENT_READS_PER_WAKEUP && !c->dead && !c->building; i++) {
		int n = proto_conn_read(c->conn, &err);
		if (n == -EPROTO) {
			if (proto_conn_over_fd_cap(c->conn))
				c->env->totals->refused_fds++;
			client_fail(c, 0, err.code, "%s", err.text);
			return;
		}
		if (n < 0) {
			if (proto_conn_has_partial(c->conn))
				log_info("client %d (pid %d) left mid-message", proto_conn_get_fd(c->conn),
					 (int)c->pid);
			client_kill(c);
			return;
		}
		if (!client_dispatch(c))
			return;
		if (n == 0)
			break;
	}
	client_flush(c);
}

void client_resume(struct client *c)
{
	if (c->dead)
		return;
	sd_event_source_set_enabled(c->source, SD_EVENT_ON);
	if (client_dispatch(c))
		client_flush(c); /* reading again, unless another volume waits */
}

static int client_event(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	struct client *c = data;
	if (c->dead)
		return 0;
	if (revents & EPOLLOUT)
		client_flush(c);
	if (c->building && (revents & (EPOLLHUP | EPOLLERR))) {
		/* Hung up while its volume is made: what it sent before is
		 * still served (client_resume()); meanwhile not listening, as
		 * these would come again and again. */
		sd_event_source_set_enabled(c->source, SD_EVENT_OFF);
		return 0;
	}
	if (!c->building && (revents & (EPOLLIN | EPOLLHUP | EPOLLERR)))
		client_read(c);
	return 0;
}

bool client_peer_is_admin(gid_t admin_gid, int fd, const struct ucred *cred)
{
	if (cred->uid == 0 || cred->uid == geteuid())
		return true;
	if (admin_gid == (gid_t)-1)
		return false;
	if (cred->gid == admin_gid)
		return true;
	gid_t groups[256];
	socklen_t len = sizeof(groups);
	if (getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups, &len) < 0)
		return false; /* too many groups, or an old kernel: not admin */
	for (size_t i = 0; i < len / sizeof(gid_t); i++)
		if (groups[i] == admin_gid)
			return true;
	return false;
}

struct client *client_create(const struct client_env *env, int fd)
{
	struct client *c = calloc(1, sizeof(*c));
	if (!c) {
		close(fd);
		return NULL;
	}
	struct ucred cred;
	socklen_t len = sizeof(cred);
	if (getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) < 0) {
		close(fd);
		free(c);
		return NULL;
	}
	c->uid = cred.uid;
	c->gid = cred.gid;
	c->pid = cred.pid;
	c->admin = client_peer_is_admin(env->admin_gid, fd, &cred);
	c->connected_ns = now_ns();
	c->env = env;
	link_init(&c->link);
	link_init(&c->lists);
	link_init(&c->layers);
	link_init(&c->frames_pending);
	c->conn = proto_conn_create(fd, CLIENT_MAX_OUT);
	if (!c->conn)
		goto err_free;
	proto_conn_set_max_fds(c->conn, env->cfg->max_client_fds);
	int r = sd_event_add_io(env->event, &c->source, fd, EPOLLIN, client_event, c);
	if (r < 0) {
		errno = -r;
		goto err_conn;
	}
	return c;
err_conn:
	proto_conn_destroy(c->conn);
err_free:
	free(c);
	return NULL;
}

void client_destroy(struct client *c)
{
	volumes_cancel_build(c);
	/* Layers first: they hold references to lists. */
	struct layer *y, *ytmp;
	link_for_each_safe(y, ytmp, &c->layers, link)
		object_destroy(&y->base);
	/* Each removal may shift later entries back into slot i. */
	for (uint32_t i = 0; i < c->objects.cap; i++)
		while (c->objects.slots[i].id)
			object_destroy(c->objects.slots[i].value);
	idmap_finish(&c->objects);
	sd_event_source_disable_unref(c->source);
	proto_conn_destroy(c->conn);
	free(c);
}
