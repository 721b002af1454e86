#include "process.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>

#include "log.h"

static int on_signal(sd_event_source *s, const struct signalfd_siginfo *si, void *data)
{
	log_info("signal %u (%s): shutting down", si->ssi_signo, strsignal((int)si->ssi_signo));
	return sd_event_exit(sd_event_source_get_event(s), 0);
}

/* The configuration is read at start only: a reload would have to move
 * the socket, the devices and the renderer under running clients. */
static int on_hangup(sd_event_source *s, const struct signalfd_siginfo *si, void *data)
{
	log_info("SIGHUP: ignored (spindled does not reload its configuration; restart it)");
	return 0;
}

/* Signals whose default would kill the daemon without its shutdown path
 * (projector dark, socket removed, STOPPING=1) take that path instead. */
static const int shutdown_signals[] = { SIGINT, SIGTERM, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM };

int process_setup_signals(sd_event *event)
{
	sigset_t mask;
	sigemptyset(&mask);
	for (size_t i = 0; i < sizeof(shutdown_signals) / sizeof(shutdown_signals[0]); i++)
		sigaddset(&mask, shutdown_signals[i]);
	sigaddset(&mask, SIGHUP);
	sigprocmask(SIG_BLOCK, &mask, NULL);
	signal(SIGPIPE, SIG_IGN);
	int r;
	for (size_t i = 0; i < sizeof(shutdown_signals) / sizeof(shutdown_signals[0]); i++)
		if ((r = sd_event_add_signal(event, NULL, shutdown_signals[i], on_signal, NULL)) < 0)
			return r;
	return sd_event_add_signal(event, NULL, SIGHUP, on_hangup, NULL);
}

/* As many fds as the hard limit allows (systemd's default soft limit is
 * 1024): clients hold fds while their messages wait, and running out only
 * pauses accepting (pause_accept()). The daemon polls with epoll only. */
void process_raise_fd_limit(void)
{
	struct rlimit rl;
	if (getrlimit(RLIMIT_NOFILE, &rl) < 0 || rl.rlim_cur >= rl.rlim_max)
		return;
	rlim_t was = rl.rlim_cur;
	rl.rlim_cur = rl.rlim_max;
	if (setrlimit(RLIMIT_NOFILE, &rl) < 0)
		log_warn("cannot raise the fd limit from %llu to %llu: %s", (unsigned long long)was,
			 (unsigned long long)rl.rlim_max, strerror(errno));
	else
		log_debug("fd limit raised from %llu to %llu", (unsigned long long)was,
			  (unsigned long long)rl.rlim_max);
}

/* The fds open now (for the limits event: asked for, never polled). */
uint32_t process_open_fds(void)
{
	DIR *d = opendir("/proc/self/fd");
	if (!d)
		return 0;
	uint32_t n = 0;
	while (readdir(d))
		n++;
	closedir(d);
	return n > 3 ? n - 3 : 0; /* ".", "..", and the directory's own fd */
}
