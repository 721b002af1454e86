/* libspindle: the connection, event dispatch and the blocking helpers. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "private.h"

/* Requests the library lets pile up before it writes them out itself. */
#define AUTO_FLUSH_BYTES (64u * 1024)
#define MAX_OUT (4u << 20)

void lib_log(struct spindle *sp, const char *fmt, ...)
{
	char text[300];
	va_list ap;
	if (!sp->log)
		return;
	va_start(ap, fmt);
	vsnprintf(text, sizeof(text), fmt, ap);
	va_end(ap);
	sp->log(sp->log_data, text);
}

int lib_set_error(struct spindle *sp, int err, const char *fmt, ...)
{
	va_list ap;
	if (sp->dead)
		return -EPIPE;
	sp->dead = true;
	va_start(ap, fmt);
	vsnprintf(sp->error, sizeof(sp->error), fmt, ap);
	va_end(ap);
	lib_log(sp, "%s", sp->error);
	(void)err;
	return -EPIPE;
}

void *lib_alloc(struct spindle *sp, size_t size, uint32_t *id)
{
	if (sp->dead) {
		errno = EPIPE;
		return NULL;
	}
	if (sp->next_id > 0xfeffffffu) {
		errno = ENOSPC;
		return NULL;
	}
	void *p = calloc(1, size);
	if (p)
		*id = sp->next_id++;
	return p;
}

int lib_sent(struct spindle *sp, int r)
{
	if (r < 0)
		return r == -ENOBUFS ? lib_set_error(sp, r, "too many unsent requests") : r;
	if (proto_conn_pending_out(sp->conn) >= AUTO_FLUSH_BYTES)
		return lib_flush_blocking(sp);
	return 0;
}

/* ---- pending callbacks ---- */

struct lib_callback *lib_callback_add(struct spindle *sp, enum lib_callback_kind kind)
{
	uint32_t id;
	struct lib_callback *cb = lib_alloc(sp, sizeof(*cb), &id);
	if (!cb)
		return NULL;
	cb->id = id;
	cb->kind = kind;
	cb->fd = -1;
	cb->next = sp->callbacks;
	sp->callbacks = cb;
	return cb;
}

static struct lib_callback **callback_slot(struct spindle *sp, uint32_t id)
{
	struct lib_callback **p = &sp->callbacks;
	while (*p && (*p)->id != id)
		p = &(*p)->next;
	return p;
}

void lib_callback_remove(struct spindle *sp, struct lib_callback *cb)
{
	struct lib_callback **p = callback_slot(sp, cb->id);
	if (*p == cb)
		*p = cb->next;
	if (cb->fd >= 0)
		close(cb->fd);
	free(cb);
}

/* ---- events ---- */

static int on_welcome(void *target, const struct proto_display_welcome_args *a)
{
	struct spindle *sp = target;
	if (a->version == 0 || a->version > SPINDLE_PROTOCOL_VERSION || a->version > sp->offered)
		return lib_set_error(sp, EPROTO, "daemon chose protocol version %u", a->version);
	sp->version = a->version;
	return 0;
}

static int on_device(void *target, const struct proto_display_device_args *a)
{
	struct spindle *sp = target;
	struct spindle_device_info *d = &sp->info;
	d->width = a->width;
	d->height = a->height;
	d->images_per_rev = a->images_per_rev;
	d->mirrored = a->flags & PROTO_DISPLAY_DEVICE_FLAGS_MIRRORED;
	d->half_height = a->half_height;
	d->rpm = a->rpm;
	snprintf(d->name, sizeof(d->name), "%s", a->name);
	sp->have_info = true;
	return 0;
}

static int on_error(void *target, const struct proto_display_error_args *a)
{
	struct spindle *sp = target;
	sp->error_code = a->code;
	return lib_set_error(sp, EPROTO, "spindled: error %u on object %u: %s", a->code, a->object, a->message);
}

static int on_status(void *target, const struct proto_display_status_args *a)
{
	struct spindle *sp = target;
	sp->status = (struct spindle_status){
		.rpm = a->rpm,
		.locked = a->flags & PROTO_DISPLAY_STATUS_FLAGS_LOCKED,
		.blanked = a->flags & PROTO_DISPLAY_STATUS_FLAGS_BLANKED,
		.projector_present = a->flags & PROTO_DISPLAY_STATUS_FLAGS_PROJECTOR_PRESENT,
		.volumes_shown = a->volumes_shown,
		.underruns = a->underruns,
		.clients = a->clients,
		.volumes_rendered = a->volumes_rendered,
		.volumes_skipped = a->volumes_skipped,
		.bytes_uploaded = a->bytes_uploaded,
		.render_us = a->render_us,
		.jitter_us = a->jitter_us,
		.missed_pulses = a->missed_pulses,
		.upload_rate = a->upload_rate,
		.index_error_us = a->index_error_us,
		.angle_error_p99 = a->angle_error_p99,
		.angle_error_max = a->angle_error_max,
		.limits_known = sp->limits_known,
		.limits = sp->limits,
		.composition_known = sp->composition_known,
		.composition = sp->composition,
		.service = sp->service,
	};
	sp->status_serial++;
	return 0;
}

/* Comes before status; spindle_get_watch_stats() reads it. */
static int on_watchers(void *target, const struct proto_display_watchers_args *a)
{
	struct spindle *sp = target;
	sp->watch_stats = (struct spindle_watch_stats){
		.watchers = a->watchers,
		.max_watchers = a->max_watchers,
		.max_rate_hz = a->max_rate_hz,
		.volumes_sent = a->volumes_sent,
		.volumes_skipped = a->volumes_skipped,
		.bytes_sent = a->bytes_sent,
		.refused = a->refused,
		.denied = a->denied,
	};
	return 0;
}

/* Comes before status, which takes it along. */
static int on_service(void *target, const struct proto_display_service_args *a)
{
	struct spindle *sp = target;
	sp->service = (struct spindle_service){
		.watchdog_ms = a->watchdog_ms,
		.watchdog_fed = a->watchdog_fed,
		.watchdog_withheld = a->watchdog_withheld,
		.max_client_fds = a->max_client_fds,
		.refused_fds = a->refused_fds,
	};
	return 0;
}

/* Comes just before status, which takes it along. */
static int on_composition(void *target, const struct proto_display_composition_args *a)
{
	struct spindle *sp = target;
	sp->composition = (struct spindle_composition){
		.cache = a->flags & PROTO_DISPLAY_COMPOSITION_FLAGS_CACHE,
		.objects = a->objects,
		.cached = a->cached,
		.cache_bytes = a->cache_bytes,
		.cache_budget = a->cache_budget,
		.hits = a->hits,
		.misses = a->misses,
		.creates = a->creates,
		.invalidations = a->invalidations,
		.evictions = a->evictions,
		.objects_rendered = a->objects_rendered,
		.objects_reused = a->objects_reused,
		.render_us = a->render_us,
		.compose_us = a->compose_us,
	};
	sp->composition_known = true;
	return 0;
}

/* Comes just before status, which takes it along. */
static int on_limits(void *target, const struct proto_display_limits_args *a)
{
	struct spindle *sp = target;
	sp->limits = (struct spindle_limits){
		.refused_clients = a->refused_clients,
		.refused_per_user = a->refused_per_user,
		.refused_incomplete = a->refused_incomplete,
		.handshake_timeouts = a->handshake_timeouts,
		.accept_pauses = a->accept_pauses,
		.clients_in_handshake = a->clients_in_handshake,
		.fds = a->fds,
		.fd_limit = a->fd_limit,
		.memory_used = a->memory_used,
		.memory_budget = a->memory_budget,
		.refused_memory = a->refused_memory,
		.mappings = a->mappings,
		.mapping_budget = a->mapping_budget,
		.refused_mappings = a->refused_mappings,
	};
	sp->limits_known = true;
	return 0;
}

static int on_state(void *target, const struct proto_display_state_args *a)
{
	struct spindle *sp = target;
	sp->state = (struct spindle_state){
		.locked = a->flags & PROTO_DISPLAY_STATUS_FLAGS_LOCKED,
		.blanked = a->flags & PROTO_DISPLAY_STATUS_FLAGS_BLANKED,
		.projector_present = a->flags & PROTO_DISPLAY_STATUS_FLAGS_PROJECTOR_PRESENT,
		.rpm = a->rpm,
	};
	if (sp->listener && sp->listener->state)
		sp->listener->state(sp->listener_data, &sp->state);
	return 0;
}

static int on_refused(void *target, const struct proto_display_refused_args *a)
{
	struct spindle *sp = target;
	sp->refusals++;
	sp->last_refusal = a->code;
	sp->refused_at = sp->events;
	lib_log(sp, "spindled refused a request (object %u): %s", a->object, a->message);
	if (sp->listener && sp->listener->refused)
		sp->listener->refused(sp->listener_data, (enum spindle_refusal)a->code, a->object, a->message);
	return 0;
}

/* In answer to calibrate, and before status (version 6). */
static int on_calibration(void *target, const struct proto_display_calibration_args *a)
{
	struct spindle *sp = target;
	sp->calibration = (struct spindle_calibration){
		.phase_offset = a->phase_offset,
		.axis_offset_u = a->axis_offset_u,
		.axis_offset_v = a->axis_offset_v,
		.vertical_scale = a->vertical_scale,
		.vertical_offset = a->vertical_offset,
	};
	sp->calibration_serial++;
	/* The daemon answers a refused calibrate with refused, then at once
	 * this event: a refusal just before it was that one. */
	sp->calibration_refusal = sp->refused_at == sp->events - 1 ? sp->last_refusal : 0;
	return 0;
}

static const struct proto_display_events display_events = {
	.welcome = on_welcome,
	.device = on_device,
	.error = on_error,
	.status = on_status,
	.state = on_state,
	.refused = on_refused,
	.limits = on_limits,
	.composition = on_composition,
	.service = on_service,
	.watchers = on_watchers,
	.calibration = on_calibration,
};

static int on_done(void *target, const struct proto_callback_done_args *a)
{
	struct lib_callback *cb = target;
	cb->done = true;
	cb->frame = (struct spindle_frame){ a->volume_seq, a->time_ns };
	return 0;
}

static const struct proto_callback_events callback_events = { .done = on_done };

static int on_capture_ready(void *target, const struct proto_capture_ready_args *a)
{
	struct lib_callback *cb = target;
	cb->done = true;
	cb->fd = a->fd;
	cb->size = a->size;
	return 0;
}

static int on_capture_failed(void *target, const struct proto_capture_failed_args *a)
{
	struct lib_callback *cb = target;
	cb->done = true;
	cb->error = a->code == PROTO_CAPTURE_FAILURE_DENIED ? -EACCES : -EIO;
	return 0;
}

static const struct proto_capture_events capture_events = {
	.ready = on_capture_ready,
	.failed = on_capture_failed,
};

/* Frame callbacks run their function and go; others wait for their owner. */
static void finish_callback(struct spindle *sp, struct lib_callback *cb)
{
	if (cb->kind != LIB_CALLBACK_FRAME || !cb->done)
		return;
	spindle_frame_func func = cb->func;
	void *data = cb->data;
	struct spindle_frame frame = cb->frame;
	lib_callback_remove(sp, cb);
	if (func)
		func(data, &frame);
}

static int dispatch_one(struct spindle *sp, struct proto_message *m)
{
	struct proto_error err = { 0 };
	int r;
	sp->events++;
	if (m->object == 1)
		return proto_display_dispatch_event(&display_events, sp, m, sp->version ? sp->version : 1, &err) ==
				       -EPROTO
			       ? lib_set_error(sp, EPROTO, "bad event from the daemon: %s", err.text)
			       : 0;
	struct lib_callback *cb = *callback_slot(sp, m->object);
	if (!cb && (r = lib_watch_dispatch(sp, m, &err)) != -ENOENT)
		return r == -EPROTO ? lib_set_error(sp, EPROTO, "bad event from the daemon: %s", err.text) : 0;
	if (!cb)
		return lib_set_error(sp, EPROTO, "event for unknown object %u", m->object);
	lib_watchers_forget(sp, cb->id);
	if (cb->kind == LIB_CALLBACK_CAPTURE)
		r = proto_capture_dispatch_event(&capture_events, cb, m, sp->version, &err);
	else
		r = proto_callback_dispatch_event(&callback_events, cb, m, sp->version, &err);
	if (r == -EPROTO)
		return lib_set_error(sp, EPROTO, "bad event from the daemon: %s", err.text);
	finish_callback(sp, cb);
	return 0;
}

/* Handles every complete event received. Returns the count or -EPIPE. */
static int dispatch_buffered(struct spindle *sp)
{
	struct proto_message m;
	struct proto_error err = { 0 };
	int n = 0, r = 0;
	while (!sp->dead && (r = proto_conn_next(sp->conn, &m, &err)) == 1) {
		dispatch_one(sp, &m);
		n++;
	}
	if (r < 0)
		return lib_set_error(sp, EPROTO, "bad data from the daemon: %s", err.text);
	return sp->dead ? -EPIPE : n;
}

int spindle_dispatch(struct spindle *sp)
{
	struct proto_error err = { 0 };
	int total = 0;
	if (sp->dead)
		return -EPIPE;
	for (;;) {
		int r = proto_conn_read(sp->conn, &err);
		if (r == -EPIPE)
			return dispatch_buffered(sp) < 0 ? -EPIPE
							 : lib_set_error(sp, EPIPE, "spindled closed the connection");
		if (r < 0)
			return lib_set_error(sp, -r, "read from spindled: %s", r == -EPROTO ? err.text : strerror(-r));
		int n = dispatch_buffered(sp);
		if (n < 0)
			return n;
		total += n;
		if (r == 0)
			return total;
	}
}

int spindle_flush(struct spindle *sp)
{
	if (sp->dead)
		return -EPIPE;
	int r = proto_conn_flush(sp->conn);
	if (r < 0 && r != -EAGAIN)
		return lib_set_error(sp, -r, "write to spindled: %s", strerror(-r));
	return r;
}

static int wait_fd(struct spindle *sp, short events)
{
	struct pollfd pfd = { proto_conn_get_fd(sp->conn), events, 0 };
	int r;
	do
		r = poll(&pfd, 1, -1);
	while (r < 0 && errno == EINTR);
	return r < 0 ? -errno : 0;
}

int lib_flush_blocking(struct spindle *sp)
{
	int r;
	while ((r = spindle_flush(sp)) == -EAGAIN) {
		if ((r = wait_fd(sp, POLLOUT)) < 0)
			return r;
	}
	return r;
}

int lib_wait(struct spindle *sp, bool (*ready)(struct spindle *sp, void *data), void *data)
{
	int r = lib_flush_blocking(sp);
	while (r >= 0 && !ready(sp, data)) {
		if ((r = wait_fd(sp, POLLIN)) < 0)
			break;
		r = spindle_dispatch(sp);
	}
	return r < 0 ? r : 0;
}

static bool callback_done(struct spindle *sp, void *data)
{
	return ((struct lib_callback *)data)->done;
}

int lib_wait_callback(struct spindle *sp, struct lib_callback *cb)
{
	return lib_wait(sp, callback_done, cb);
}

int spindle_roundtrip(struct spindle *sp)
{
	struct lib_callback *cb = lib_callback_add(sp, LIB_CALLBACK_SYNC);
	if (!cb)
		return -errno;
	int r = lib_sent(sp, proto_req_display_sync(sp->conn, 1, cb->id));
	if (r == 0)
		r = lib_wait_callback(sp, cb);
	lib_callback_remove(sp, cb);
	return r;
}

/* ---- connecting ---- */

static int connect_socket(const char *path)
{
	struct sockaddr_un addr = { .sun_family = AF_UNIX };
	if (strlen(path) >= sizeof(addr.sun_path)) {
		errno = ENAMETOOLONG;
		return -1;
	}
	strcpy(addr.sun_path, path);
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
	if (fd < 0)
		return -1;
	if (connect(fd, (struct sockaddr *)&addr, sizeof(addr)) < 0 ||
	    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK) < 0) {
		int e = errno;
		close(fd);
		errno = e;
		return -1;
	}
	return fd;
}

static bool have_info(struct spindle *sp, void *data)
{
	return sp->have_info;
}

struct spindle *spindle_connect(const char *path)
{
	return spindle_connect_version(path, SPINDLE_PROTOCOL_VERSION);
}

struct spindle *spindle_connect_version(const char *path, uint32_t max_version)
{
	if (max_version < 1 || max_version > SPINDLE_PROTOCOL_VERSION) {
		errno = EINVAL;
		return NULL;
	}
	if (!path) {
		path = getenv("SPINDLE_SOCKET");
		if (!path || !*path)
			path = SPINDLE_DEFAULT_SOCKET;
	}
	int fd = connect_socket(path);
	if (fd < 0)
		return NULL;
	struct spindle *sp = calloc(1, sizeof(*sp));
	if (!sp) {
		close(fd);
		return NULL;
	}
	sp->next_id = 2;
	sp->offered = max_version;
	link_init(&sp->objects);
	link_init(&sp->watchers);
	sp->conn = proto_conn_create(fd, MAX_OUT);
	if (!sp->conn) {
		free(sp);
		return NULL;
	}
	int r = proto_req_display_hello(sp->conn, 1, max_version);
	if (r == 0)
		r = lib_wait(sp, have_info, NULL);
	if (r < 0) {
		spindle_disconnect(sp);
		errno = r == -EPIPE ? EPROTO : -r;
		return NULL;
	}
	return sp;
}

void spindle_disconnect(struct spindle *sp)
{
	if (!sp)
		return;
	while (!link_empty(&sp->objects))
		lib_object_free(link_entry(sp->objects.next, struct lib_object, link));
	lib_watchers_free(sp);
	while (sp->callbacks)
		lib_callback_remove(sp, sp->callbacks);
	proto_conn_destroy(sp->conn);
	free(sp);
}

void spindle_set_log_handler(struct spindle *sp, spindle_log_func func, void *data)
{
	sp->log = func;
	sp->log_data = data;
}

uint32_t spindle_get_version(struct spindle *sp)
{
	return sp->version;
}

const struct spindle_device_info *spindle_get_device_info(struct spindle *sp)
{
	return &sp->info;
}

int spindle_get_fd(struct spindle *sp)
{
	return proto_conn_get_fd(sp->conn);
}

const char *spindle_get_error(struct spindle *sp)
{
	return sp->dead ? sp->error : NULL;
}

uint32_t spindle_get_error_code(struct spindle *sp)
{
	return sp->error_code;
}

const char *spindle_library_version(void)
{
	return SPINDLE_VERSION; /* of the headers this library was built with */
}

void spindle_set_listener(struct spindle *sp, const struct spindle_listener *listener, void *data)
{
	sp->listener = listener;
	sp->listener_data = data;
}

int spindle_get_state(struct spindle *sp, struct spindle_state *out)
{
	if (sp->version < 2)
		return -ENOTSUP;
	*out = sp->state;
	return 0;
}
