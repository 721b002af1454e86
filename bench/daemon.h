/* The daemon-level benchmarks' shared part: start spindled on a private
 * socket (or use a running one), connect, stop it, and read what it costs
 * from /proc. Not a test harness: a failure prints and exits. */
#ifndef BENCH_DAEMON_H
#define BENCH_DAEMON_H

#include <stdbool.h>
#include <stdint.h>
#include <sys/types.h>

#include "spindle/spindle.h"

struct bench_daemon {
	const char *prog; /* the benchmark's name, for messages */
	pid_t pid;
	bool ours; /* started here: stop it at the end */
	char dir[64];
	char socket[128];
};

/* What the daemon's memory is at one moment (/proc/PID/status), in KiB. */
struct bench_memory {
	uint64_t rss_kib; /* VmRSS */
	uint64_t hwm_kib; /* VmHWM: the peak RSS so far */
};

int64_t bench_mono_ns(void);
void bench_sleep_ms(int ms);
/* Prints "PROG: WHAT: strerror(err)" and exits 1. */
_Noreturn void bench_die(const char *prog, const char *what, int err);

/* target: a spindled executable, started with --device sim, the profile and
 * (when not NULL) the renderer, on a socket in a new directory under /tmp,
 * its stderr in spindled.log there; or the path of a running daemon's
 * socket, used as it is. */
void bench_daemon_start(struct bench_daemon *d, const char *prog, const char *target, const char *profile,
			const char *renderer);
/* Connects, waiting up to 10 s for a daemon started here to listen; NULL
 * with errno set when it does not. */
struct spindle *bench_daemon_connect(struct bench_daemon *d);
/* The daemon's pid, from the socket's peer credentials. */
pid_t bench_daemon_pid(struct bench_daemon *d, struct spindle *sp);
/* SIGTERM and wait, for a daemon started here; removes its directory when
 * it exited cleanly, else says where its log is. */
void bench_daemon_stop(struct bench_daemon *d);

/* utime + stime of every thread of pid, in seconds. */
double bench_cpu_seconds(const char *prog, pid_t pid);
void bench_memory(const char *prog, pid_t pid, struct bench_memory *out);

#endif
