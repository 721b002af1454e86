/* Starting, connecting to and measuring spindled for the daemon-level
 * benchmarks (bench/daemon.h). */
#include "daemon.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

int64_t bench_mono_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

void bench_sleep_ms(int ms)
{
	struct timespec ts = { ms / 1000, (ms % 1000) * 1000000L };
	nanosleep(&ts, NULL);
}

void bench_die(const char *prog, const char *what, int err)
{
	fprintf(stderr, "%s: %s: %s\n", prog, what, strerror(err));
	exit(1);
}

static bool is_socket(const char *path)
{
	struct stat st;
	return stat(path, &st) == 0 && S_ISSOCK(st.st_mode);
}

static _Noreturn void exec_daemon(const struct bench_daemon *d, const char *exe, const char *profile,
				  const char *renderer)
{
	char log[128];
	snprintf(log, sizeof(log), "%s/spindled.log", d->dir);
	int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
	if (fd >= 0)
		dup2(fd, 2);
	unsetenv("LISTEN_FDS");
	if (renderer)
		execl(exe, exe, "--device", "sim", "--profile", profile, "--renderer", renderer, "--socket", d->socket,
		      "--config", "/dev/null", (char *)NULL);
	else
		execl(exe, exe, "--device", "sim", "--profile", profile, "--socket", d->socket, "--config", "/dev/null",
		      (char *)NULL);
	_exit(127);
}

void bench_daemon_start(struct bench_daemon *d, const char *prog, const char *target, const char *profile,
			const char *renderer)
{
	d->prog = prog;
	if (is_socket(target)) {
		snprintf(d->socket, sizeof(d->socket), "%s", target);
		return;
	}
	snprintf(d->dir, sizeof(d->dir), "/tmp/spindle-bench-XXXXXX");
	if (!mkdtemp(d->dir))
		bench_die(prog, "mkdtemp", errno);
	snprintf(d->socket, sizeof(d->socket), "%s/spindle.sock", d->dir);
	d->ours = true;
	d->pid = fork();
	if (d->pid < 0)
		bench_die(prog, "fork", errno);
	if (d->pid == 0)
		exec_daemon(d, target, profile, renderer);
}

struct spindle *bench_daemon_connect(struct bench_daemon *d)
{
	for (int i = 0; i < 1000; i++) {
		struct spindle *sp = spindle_connect(d->socket);
		if (sp || !d->ours)
			return sp;
		if (waitpid(d->pid, NULL, WNOHANG) != 0) {
			fprintf(stderr, "%s: spindled exited; see %s/spindled.log\n", d->prog, d->dir);
			exit(1);
		}
		bench_sleep_ms(10);
	}
	return NULL;
}

pid_t bench_daemon_pid(struct bench_daemon *d, struct spindle *sp)
{
	struct ucred cred;
	socklen_t len = sizeof(cred);
	if (getsockopt(spindle_get_fd(sp), SOL_SOCKET, SO_PEERCRED, &cred, &len) < 0)
		bench_die(d->prog, "SO_PEERCRED", errno);
	return cred.pid;
}

void bench_daemon_stop(struct bench_daemon *d)
{
	if (!d->ours)
		return;
	int status = 0;
	kill(d->pid, SIGTERM);
	waitpid(d->pid, &status, 0);
	if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
		fprintf(stderr, "%s: spindled did not exit cleanly; see %s/spindled.log\n", d->prog, d->dir);
		return;
	}
	char path[128];
	snprintf(path, sizeof(path), "%s/spindled.log", d->dir);
	unlink(path);
	rmdir(d->dir);
}

/* The first sizeof(buf) - 1 bytes of /proc/PID/NAME, NUL-terminated. */
static void read_proc(const char *prog, pid_t pid, const char *name, char *buf, size_t size)
{
	char path[64];
	snprintf(path, sizeof(path), "/proc/%d/%s", (int)pid, name);
	FILE *f = fopen(path, "r");
	if (!f)
		bench_die(prog, path, errno);
	size_t n = fread(buf, 1, size - 1, f);
	fclose(f);
	buf[n] = 0;
}

double bench_cpu_seconds(const char *prog, pid_t pid)
{
	char buf[1024];
	read_proc(prog, pid, "stat", buf, sizeof(buf));
	/* Fields after the command name: state is field 3, utime 14, stime 15. */
	const char *p = strrchr(buf, ')');
	unsigned long long utime, stime;
	if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %llu %llu", &utime, &stime) != 2)
		bench_die(prog, "parsing /proc/PID/stat", EINVAL);
	return (double)(utime + stime) / (double)sysconf(_SC_CLK_TCK);
}

static uint64_t status_kib(const char *prog, const char *status, const char *key)
{
	const char *p = strstr(status, key);
	unsigned long long kib;
	if (!p || sscanf(p + strlen(key), " %llu kB", &kib) != 1)
		bench_die(prog, "parsing /proc/PID/status", EINVAL);
	return kib;
}

void bench_memory(const char *prog, pid_t pid, struct bench_memory *out)
{
	char buf[4096];
	read_proc(prog, pid, "status", buf, sizeof(buf));
	out->rss_kib = status_kib(prog, buf, "\nVmRSS:");
	out->hwm_kib = status_kib(prog, buf, "\nVmHWM:");
}
