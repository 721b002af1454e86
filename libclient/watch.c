/* libspindle: watchers of the volumes shown (protocol 5). */
#include <errno.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

#include "private.h"

struct spindle_watcher {
	struct spindle *sp;
	uint32_t id;
	struct link link; /* spindle.watchers */
	spindle_watch_func func;
	void *data;
	int error;        /* 0, or why the daemon ended it */
	bool gone;        /* the daemon destroyed it (failed) */
	bool destroyed;   /* the client did: kept for events already sent */
	uint32_t horizon; /* the first id made after the destroy */
	bool held;        /* a volume is held until release */
	int fd;           /* the volume held, or -1 */
	void *map;        /* its mapping, or NULL */
	size_t size;
};

static void drop_volume(struct spindle_watcher *w)
{
	if (w->map)
		munmap(w->map, w->size);
	if (w->fd >= 0)
		close(w->fd);
	w->map = NULL;
	w->fd = -1;
	w->size = 0;
}

static void watcher_free(struct spindle_watcher *w)
{
	drop_volume(w);
	link_remove(&w->link);
	free(w);
}

void lib_watchers_free(struct spindle *sp)
{
	while (!link_empty(&sp->watchers))
		watcher_free(link_entry(sp->watchers.next, struct spindle_watcher, link));
}

struct spindle_watcher *spindle_watch_create(struct spindle *sp, uint32_t max_rate_hz, spindle_watch_func func,
					     void *data)
{
	if (!sp->dead && sp->version < 5) {
		errno = EPROTONOSUPPORT;
		return NULL;
	}
	if (max_rate_hz > 1000) {
		errno = EINVAL;
		return NULL;
	}
	uint32_t id;
	struct spindle_watcher *w = lib_alloc(sp, sizeof(*w), &id);
	if (!w)
		return NULL;
	*w = (struct spindle_watcher){ .sp = sp, .id = id, .func = func, .data = data, .fd = -1 };
	link_append(&sp->watchers, &w->link);
	int r = lib_sent(sp, proto_req_display_watch(sp->conn, 1, id, max_rate_hz));
	if (r == 0)
		r = spindle_flush(sp) == -EAGAIN ? 0 : (sp->dead ? -EPIPE : 0);
	if (r < 0) {
		watcher_free(w);
		errno = -r;
		return NULL;
	}
	return w;
}

int spindle_watch_release(struct spindle_watcher *w)
{
	if (w->gone)
		return w->error;
	if (!w->held)
		return 0;
	drop_volume(w);
	w->held = false;
	int r = lib_sent(w->sp, proto_req_watcher_release(w->sp->conn, w->id));
	if (r == 0 && spindle_flush(w->sp) < 0 && w->sp->dead)
		r = -EPIPE;
	return r;
}

int spindle_watch_get_error(const struct spindle_watcher *w)
{
	return w->error;
}

/* The daemon may have sent a volume before it reads the destroy: the
 * watcher stays, silent, to take it, until the event of a callback made
 * after the destroy shows that the daemon read it
 * (lib_watchers_forget()). */
void spindle_watch_destroy(struct spindle_watcher *w)
{
	if (!w)
		return;
	if (w->gone || w->sp->dead) {
		watcher_free(w);
		return;
	}
	lib_sent(w->sp, proto_req_watcher_destroy(w->sp->conn, w->id));
	drop_volume(w);
	w->destroyed = true;
	w->func = NULL;
	w->horizon = w->sp->next_id;
}

void lib_watchers_forget(struct spindle *sp, uint32_t callback_id)
{
	struct spindle_watcher *w, *tmp;
	link_for_each_safe(w, tmp, &sp->watchers, link) {
		if (w->destroyed && w->horizon <= callback_id)
			watcher_free(w);
	}
}

static int on_volume(void *target, const struct proto_watcher_volume_args *a)
{
	struct spindle_watcher *w = target;
	if (w->destroyed) {
		close(a->fd);
		return 0;
	}
	drop_volume(w);
	w->fd = a->fd;
	w->size = (size_t)a->size;
	w->held = true;
	if (w->size) {
		void *p = mmap(NULL, w->size, PROT_READ, MAP_SHARED, w->fd, 0);
		w->map = p == MAP_FAILED ? NULL : p;
	}
	if (!w->map) {
		/* Unreadable: let it go, and say so through the volume's absence. */
		lib_log(w->sp, "watcher %u: cannot map a volume of %zu bytes", w->id, w->size);
		drop_volume(w);
		return 0;
	}
	struct spindle_watch_volume vol = {
		.data = w->map,
		.size = w->size,
		.fd = w->fd,
		.seq = a->seq,
		.skipped = a->skipped,
	};
	if (w->func)
		w->func(w->data, w, &vol);
	return 0;
}

static int on_failed(void *target, const struct proto_watcher_failed_args *a)
{
	struct spindle_watcher *w = target;
	w->gone = true;
	w->error = a->code == PROTO_WATCHER_FAILURE_DENIED  ? -EACCES
		   : a->code == PROTO_WATCHER_FAILURE_LIMIT ? -EUSERS
							    : -EIO;
	lib_log(w->sp, "watcher %u failed: %s", w->id, a->reason);
	if (w->func)
		w->func(w->data, w, NULL);
	return 0;
}

static const struct proto_watcher_events watcher_events = {
	.volume = on_volume,
	.failed = on_failed,
};

int lib_watch_dispatch(struct spindle *sp, struct proto_message *m, struct proto_error *err)
{
	struct spindle_watcher *w;
	link_for_each(w, &sp->watchers, link) {
		if (w->id == m->object && !w->gone)
			return proto_watcher_dispatch_event(&watcher_events, w, m, sp->version, err);
	}
	return -ENOENT;
}

int spindle_get_watch_stats(struct spindle *sp, struct spindle_watch_stats *out)
{
	if (!sp->dead && sp->version < 5)
		return -EPROTONOSUPPORT;
	struct spindle_status st;
	int r = spindle_get_status(sp, &st);
	if (r == 0)
		*out = sp->watch_stats;
	return r;
}
