/* The service manager's watchdog, fed only while the daemon makes
 * progress (watchdog.h). */
#include "watchdog.h"

#include <errno.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <systemd/sd-daemon.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "log.h"

struct watchdog {
	int notify_fd; /* connected to NOTIFY_SOCKET, -1: sd_notify() */
	const struct watchdog_listener *listener;
	void *data;
	sd_event_source *timer;
	uint64_t period_us; /* between checks */
	struct watchdog_stats stats;
	struct log_ratelimit log;
	bool stuck; /* at the last check */
};

/* The notify socket, connected once: sd_notify() opens a socket for each
 * message, which fails when the daemon is out of fds, the very time it
 * must keep its watchdog fed while it sheds clients. */
static int open_notify(void)
{
	const char *path = getenv("NOTIFY_SOCKET");
	if (!path || !*path)
		return -1;
	struct sockaddr_un addr = { .sun_family = AF_UNIX };
	size_t len = strlen(path);
	if ((path[0] != '/' && path[0] != '@') || len >= sizeof(addr.sun_path))
		return -1; /* vsock and the like: sd_notify() knows them */
	memcpy(addr.sun_path, path, len);
	if (path[0] == '@')
		addr.sun_path[0] = 0; /* abstract */
	int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
	if (fd < 0)
		return -1;
	if (connect(fd, (struct sockaddr *)&addr, (socklen_t)(offsetof(struct sockaddr_un, sun_path) + len)) < 0) {
		close(fd);
		return -1;
	}
	return fd;
}

static void feed(struct watchdog *w)
{
	static const char msg[] = "WATCHDOG=1";
	if (w->notify_fd < 0)
		sd_notify(0, msg);
	else if (send(w->notify_fd, msg, sizeof(msg) - 1, MSG_NOSIGNAL) < 0)
		log_debug("watchdog: cannot notify: %s", strerror(errno)); /* a full queue: the next one */
}

static int check(sd_event_source *s, uint64_t usec, void *data)
{
	struct watchdog *w = data;
	const char *why = w->listener->stalled(w->data, now_ns(), w->stats.interval_ns);
	if (!why) {
		if (w->stuck)
			log_info("watchdog: making progress again, fed");
		w->stuck = false;
		w->stats.fed++;
		feed(w);
	} else {
		w->stuck = true;
		w->stats.withheld++;
		if (log_ratelimit_ok(&w->log))
			log_error("watchdog not fed: %s", why);
	}
	sd_event_source_set_time(s, usec + w->period_us);
	return 0;
}

struct watchdog *watchdog_create(struct sd_event *event, const struct watchdog_listener *listener, void *data)
{
	if (!listener || listener->version != WATCHDOG_LISTENER_VERSION || !listener->stalled) {
		errno = EINVAL;
		return NULL;
	}
	struct watchdog *w = calloc(1, sizeof(*w));
	if (!w)
		return NULL;
	w->notify_fd = -1;
	w->listener = listener;
	w->data = data;
	w->log.interval_ns = 1000000000;
	uint64_t usec = 0;
	int r = sd_watchdog_enabled(0, &usec);
	if (r <= 0 || !usec) {
		if (r < 0)
			log_warn("watchdog: cannot read WATCHDOG_USEC: %s", strerror(-r));
		return w; /* none asked for */
	}
	w->stats.interval_ns = (int64_t)usec * 1000;
	w->notify_fd = open_notify();
	w->period_us = usec / 4 ? usec / 4 : 1;
	uint64_t now;
	sd_event_now(event, CLOCK_MONOTONIC, &now);
	/* Fed at once: the daemon is ready when this is set up. */
	if ((r = sd_event_add_time(event, &w->timer, CLOCK_MONOTONIC, now, 0, check, w)) < 0 ||
	    (r = sd_event_source_set_enabled(w->timer, SD_EVENT_ON)) < 0) {
		watchdog_destroy(w);
		errno = -r;
		return NULL;
	}
	/* Above the clients: a flood of requests must not delay the check. */
	sd_event_source_set_priority(w->timer, SD_EVENT_PRIORITY_IMPORTANT);
	log_debug("watchdog: %.1f s, checked every %.2f s", usec / 1e6, w->period_us / 1e6);
	return w;
}

void watchdog_destroy(struct watchdog *w)
{
	if (!w)
		return;
	sd_event_source_disable_unref(w->timer);
	if (w->notify_fd >= 0)
		close(w->notify_fd);
	free(w);
}

void watchdog_get_stats(const struct watchdog *w, struct watchdog_stats *out)
{
	*out = w->stats;
}
