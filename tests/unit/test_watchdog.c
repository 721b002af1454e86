/* daemon/watchdog: WATCHDOG=1 reaches the service manager (a datagram
 * socket standing in for systemd's notify socket) at each check while the
 * listener says nothing is stuck, and none while it says something is; no
 * watchdog asked for, nothing is sent. */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "check.h"
#include "log.h"
#include "watchdog.h"

struct probe {
	const char *why; /* what stalled() answers */
	int asked;
	int64_t interval_ns;
};

static const char *stalled(void *data, int64_t now, int64_t interval)
{
	struct probe *p = data;
	p->asked++;
	p->interval_ns = interval;
	return p->why;
}

static const struct watchdog_listener listener = {
	.version = WATCHDOG_LISTENER_VERSION,
	.stalled = stalled,
};

static int feeds;

/* The notify socket, drained as systemd does: a full queue (10 datagrams
 * by default) would block the sender. */
static int on_notify(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	char buf[256];
	ssize_t len;
	while ((len = recv(fd, buf, sizeof(buf) - 1, MSG_DONTWAIT)) > 0) {
		buf[len] = 0;
		if (strstr(buf, "WATCHDOG=1"))
			feeds++;
	}
	return 0;
}

/* Runs the loop for ms; the WATCHDOG=1 datagrams received meanwhile. */
static int feeds_during(sd_event *e, int ms)
{
	int before = feeds;
	int64_t end = now_ns() + (int64_t)ms * 1000000;
	while (now_ns() < end)
		sd_event_run(e, 5000);
	return feeds - before;
}

int main(void)
{
	char dir[] = "/tmp/spindle-wd-XXXXXX";
	CHECK(mkdtemp(dir) != NULL);
	struct sockaddr_un addr = { .sun_family = AF_UNIX };
	snprintf(addr.sun_path, sizeof(addr.sun_path), "%s/notify", dir);
	int sock = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
	CHECK(sock >= 0);
	CHECK_EQ(bind(sock, (struct sockaddr *)&addr, sizeof(addr)), 0);
	setenv("NOTIFY_SOCKET", addr.sun_path, 1);
	sd_event *e;
	CHECK_EQ(sd_event_new(&e), 0);
	CHECK(sd_event_add_io(e, NULL, sock, EPOLLIN, on_notify, NULL) >= 0);

	/* No watchdog asked for: idle, the listener is never asked. */
	unsetenv("WATCHDOG_USEC");
	struct probe p = { 0 };
	struct watchdog *w = watchdog_create(e, &listener, &p);
	CHECK(w != NULL);
	CHECK_EQ(feeds_during(e, 100), 0);
	CHECK_EQ(p.asked, 0);
	struct watchdog_stats st;
	watchdog_get_stats(w, &st);
	CHECK_EQ(st.interval_ns, 0);
	watchdog_destroy(w);

	/* 80 ms: checked every 20 ms. */
	setenv("WATCHDOG_USEC", "80000", 1);
	unsetenv("WATCHDOG_PID");
	w = watchdog_create(e, &listener, &p);
	CHECK(w != NULL);
	int fed = feeds_during(e, 300);
	printf("making progress: %d feeds in 300 ms, %d checks\n", fed, p.asked);
	CHECK(fed >= 5 && fed >= p.asked - 1); /* the last may still be on its way */
	CHECK_EQ(p.interval_ns, 80000000);

	p.why = "a render is taking too long";
	int asked = p.asked;
	watchdog_get_stats(w, &st);
	uint64_t was_fed = st.fed;
	fed = feeds_during(e, 300);
	watchdog_get_stats(w, &st);
	printf("stuck: %llu fed in 300 ms, %d checks\n", (unsigned long long)(st.fed - was_fed), p.asked - asked);
	CHECK_EQ(st.fed, was_fed);
	CHECK(fed <= 1); /* the last one fed before may arrive late */
	CHECK(p.asked - asked >= 5);

	p.why = NULL; /* it recovers by itself */
	fed = feeds_during(e, 200);
	CHECK(fed >= 3);
	watchdog_get_stats(w, &st);
	CHECK_EQ(st.fed, (uint64_t)p.asked - (st.withheld));
	CHECK(st.withheld >= 5);
	watchdog_destroy(w);

	/* A listener of another version is refused. */
	struct watchdog_listener bad = listener;
	bad.version = 99;
	CHECK(watchdog_create(e, &bad, &p) == NULL);

	sd_event_unref(e);
	close(sock);
	unlink(addr.sun_path);
	rmdir(dir);
	return check_done();
}
