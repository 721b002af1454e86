#include "listen_socket.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <systemd/sd-daemon.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#define REST_FIRST_MS 50
#define REST_MAX_MS 1600

/* A socket file nobody listens on is left over from a crash: remove it. */
static int remove_stale(const struct sockaddr_un *addr)
{
	struct stat st;
	if (lstat(addr->sun_path, &st) < 0)
		return errno == ENOENT ? 0 : -errno;
	if (!S_ISSOCK(st.st_mode))
		return -EEXIST;
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
	if (fd < 0)
		return -errno;
	int r = connect(fd, (const struct sockaddr *)addr, sizeof(*addr));
	int e = errno;
	close(fd);
	if (r == 0)
		return -EADDRINUSE;
	if (e != ECONNREFUSED)
		return -e;
	return unlink(addr->sun_path) < 0 ? -errno : 0;
}

/* The socket's directory, made when it is missing (what systemd's
 * RuntimeDirectory= does for the unit, for a daemon run by hand): one
 * level, mode 0755, as /run/spindle. */
static int make_directory(const char *path)
{
	char dir[sizeof(((struct sockaddr_un *)0)->sun_path)];
	snprintf(dir, sizeof(dir), "%s", path);
	char *slash = strrchr(dir, '/');
	if (!slash || slash == dir)
		return 0;
	*slash = '\0';
	if (mkdir(dir, 0755) == 0) {
		log_info("created %s for the socket", dir);
		return 0;
	}
	if (errno == EEXIST)
		return 0;
	int r = -errno;
	log_error("cannot make %s for the socket %s: %s (make it, or give another path with --socket PATH)", dir, path,
		  strerror(errno));
	return r;
}

static int bind_path(struct listen_socket *ls, const char *path)
{
	struct sockaddr_un addr = { .sun_family = AF_UNIX };
	snprintf(addr.sun_path, sizeof(addr.sun_path), "%s", path);
	int r = make_directory(addr.sun_path);
	if (r < 0)
		return r;
	r = remove_stale(&addr);
	if (r < 0) {
		log_error("socket %s: %s", addr.sun_path,
			  r == -EADDRINUSE ? "another spindled is listening there" : strerror(-r));
		return r;
	}
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
	if (fd < 0)
		return -errno;
	if (bind(fd, (const struct sockaddr *)&addr, sizeof(addr)) < 0 || chmod(addr.sun_path, 0660) < 0 ||
	    listen(fd, 64) < 0) {
		r = -errno;
		log_error("cannot listen on %s: %s", addr.sun_path, strerror(errno));
		close(fd);
		return r;
	}
	ls->fd = fd;
	ls->path = strdup(addr.sun_path);
	log_info("listening on %s", addr.sun_path);
	return 0;
}

/* systemd socket activation first, else our own socket. */
static int open_fd(struct listen_socket *ls, const char *path)
{
	int n = sd_listen_fds(1);
	if (n > 1) {
		log_error("systemd passed %d sockets, expected one", n);
		return -EINVAL;
	}
	if (n == 0)
		return bind_path(ls, path);
	if (sd_is_socket_unix(SD_LISTEN_FDS_START, SOCK_STREAM, 1, NULL, 0) <= 0) {
		log_error("the socket systemd passed is not a listening Unix stream socket");
		return -EINVAL;
	}
	ls->fd = SD_LISTEN_FDS_START;
	fcntl(ls->fd, F_SETFL, fcntl(ls->fd, F_GETFL) | O_NONBLOCK);
	log_info("listening on the socket from systemd");
	return 0;
}

static void rest(struct listen_socket *ls, int err)
{
	ls->pauses++;
	ls->rest_ms = ls->rest_ms ? ls->rest_ms * 2 : REST_FIRST_MS;
	if (ls->rest_ms > REST_MAX_MS)
		ls->rest_ms = REST_MAX_MS;
	if (log_ratelimit_ok(&ls->rest_log)) {
		log_warn("accept: %s: not accepting clients for %u ms (%llu pauses so far; said at most every 10 s)",
			 strerror(err), ls->rest_ms, (unsigned long long)ls->pauses);
		ls->rest_log.suppressed = 0;
	}
	sd_event_source_set_enabled(ls->source, SD_EVENT_OFF);
	sd_event_source_set_time_relative(ls->rest_timer, (uint64_t)ls->rest_ms * 1000);
	sd_event_source_set_enabled(ls->rest_timer, SD_EVENT_ONESHOT);
}

static int on_rested(sd_event_source *s, uint64_t usec, void *data)
{
	struct listen_socket *ls = data;
	sd_event_source_set_enabled(ls->source, SD_EVENT_ON);
	return 0;
}

static int on_readable(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	struct listen_socket *ls = data;
	for (;;) {
		int cfd = accept4(fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
		if (cfd < 0) {
			if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM)
				rest(ls, errno);
			else if (errno != EAGAIN && errno != EINTR && errno != ECONNABORTED)
				log_warn("accept: %s", strerror(errno));
			return 0;
		}
		ls->rest_ms = 0;
		ls->listener->accepted(ls->data, cfd);
	}
}

int listen_socket_open(struct listen_socket *ls, struct sd_event *event, const char *path,
		       const struct listen_socket_listener *listener, void *data)
{
	*ls = (struct listen_socket){
		.fd = -1,
		.rest_log = { .interval_ns = 10000000000LL },
		.listener = listener,
		.data = data,
	};
	int r = open_fd(ls, path);
	if (r < 0)
		return r;
	r = sd_event_add_time(event, &ls->rest_timer, CLOCK_MONOTONIC, 0, 1000, on_rested, ls);
	if (r < 0 || (r = sd_event_source_set_enabled(ls->rest_timer, SD_EVENT_OFF)) < 0)
		return r;
	return sd_event_add_io(event, &ls->source, ls->fd, EPOLLIN, on_readable, ls);
}

void listen_socket_close(struct listen_socket *ls)
{
	sd_event_source_disable_unref(ls->source);
	sd_event_source_disable_unref(ls->rest_timer);
	if (ls->fd >= 0)
		close(ls->fd);
	if (ls->path) {
		unlink(ls->path);
		free(ls->path);
	}
	*ls = (struct listen_socket){ .fd = -1 };
}
