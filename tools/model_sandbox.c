/* The model loader child and its parent's side (model_sandbox.h). fork()
 * without exec: the child is this program, confined before it reads a
 * byte of the file, and leaves with _exit() (no atexit handlers, no stdio
 * flush, no leak check). The parent reads the result within the deadline,
 * always reaps the child (killing it when the exchange failed) and says
 * what happened to it: its message, a crash, a timeout, a malformed
 * result. */
#include "model_sandbox.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "model_import.h"
#include "model_wire.h"

/* Where model_load() says that a slow load goes on, or NULL. */
static FILE *progress;

void model_sandbox_set_progress(FILE *f)
{
	progress = f;
}

struct loader {
	pid_t pid;
	int rfd; /* the read end of the result pipe */
	const char *path;
	int64_t start_ms, note_ms; /* the next progress line, 0: none yet due */
	int64_t deadline_ms;
	int timeout_ms;
	unsigned cpu_s;
	int wstatus;
	bool timed_out; /* killed at the deadline */
};

static __attribute__((noreturn)) void child_main(int in_fd, int out_fd, uint64_t size, const char *path,
						 const struct model_companions *comp, const struct model_confine *c)
{
	char why[512];
	struct model_mesh mesh;
	int ret = model_confine_child(c, &in_fd, &out_fd, why, sizeof(why));
	if (ret < 0)
		_exit(model_wire_send_error(out_fd, -ret, why) < 0 ? 1 : 0);
#ifdef SPINDLE_MODEL_TEST_HOOKS
	model_test_hook(in_fd, out_fd);
#endif
	ret = model_import_fd(in_fd, size, path, comp, &mesh, why, sizeof(why));
	if (ret < 0)
		ret = model_wire_send_error(out_fd, -ret, why);
	else
		ret = model_wire_send_mesh(out_fd, &mesh);
	_exit(ret < 0 ? 1 : 0);
}

static int64_t now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

static int start(struct loader *l, int fd, uint64_t size, const char *path, const struct model_companions *comp,
		 const struct model_confine *c)
{
	int p[2];
	if (pipe2(p, O_CLOEXEC) < 0)
		return -errno;
	l->pid = fork();
	if (l->pid < 0) {
		int e = errno;
		close(p[0]);
		close(p[1]);
		return -e;
	}
	if (l->pid == 0) {
		close(p[0]);
		child_main(fd, p[1], size, path, comp, c);
	}
	close(p[1]);
	l->rfd = p[0];
	l->deadline_ms = now_ms() + l->timeout_ms;
	l->start_ms = now_ms();
	l->note_ms = l->start_ms; /* note_progress() sets the first at 1 s */
	l->path = path;
	return 0;
}

/* Exactly len bytes before the deadline: 0, -ETIMEDOUT, -EPIPE (the pipe
 * ended first) or -errno. */
/* A load that takes over a second says so, and again every two seconds. */
static void note_progress(struct loader *l, int64_t now)
{
	if (!progress || now < l->note_ms)
		return;
	if (l->note_ms > l->start_ms) {
		fprintf(progress, "spindlectl: %s: loading, %.0f s so far\n", l->path, (now - l->start_ms) / 1000.0);
		fflush(progress);
	}
	l->note_ms = l->note_ms > l->start_ms ? l->note_ms + 2000 : l->start_ms + 1000;
}

static int read_full(struct loader *l, void *buf, size_t len)
{
	uint8_t *p = buf;
	while (len > 0) {
		int64_t now = now_ms(), left = l->deadline_ms - now;
		struct pollfd pfd = { .fd = l->rfd, .events = POLLIN };
		if (left <= 0)
			return -ETIMEDOUT;
		note_progress(l, now);
		if (progress && l->note_ms - now < left)
			left = l->note_ms - now;
		int n = poll(&pfd, 1, left > INT_MAX ? INT_MAX : (int)left);
		if (n < 0 && errno != EINTR)
			return -errno;
		if (n <= 0)
			continue;
		ssize_t r = read(l->rfd, p, len);
		if (r < 0 && errno != EINTR && errno != EAGAIN)
			return -errno;
		if (r == 0)
			return -EPIPE;
		if (r > 0) {
			p += r;
			len -= (size_t)r;
		}
	}
	return 0;
}

/* The whole message and the end of the pipe: 0, -ETIMEDOUT, -EPIPE (cut
 * short), -EPROTO (malformed: why filled), -ENOMEM or -errno. */
static int receive(struct loader *l, struct model_wire_header *h, uint8_t **payload, char *why, size_t why_size)
{
	size_t len = 0;
	uint8_t extra;
	int ret = read_full(l, h, sizeof(*h));
	if (ret < 0)
		return ret;
	if (model_wire_check_header(h, &len, why, why_size) < 0)
		return -EPROTO;
	*payload = malloc(len ? len : 1);
	if (!*payload)
		return -ENOMEM;
	ret = read_full(l, *payload, len);
	if (ret < 0)
		return ret;
	ret = read_full(l, &extra, 1);
	if (ret == 0) {
		snprintf(why, why_size, "more bytes than it announced");
		return -EPROTO;
	}
	return ret == -EPIPE ? 0 : ret;
}

static void wait_blocking(struct loader *l)
{
	while (waitpid(l->pid, &l->wstatus, 0) < 0 && errno == EINTR)
		;
}

/* Waits for the child until the deadline, then kills it; with kill_now,
 * kills it first. A child already reaped by someone (SIGCHLD ignored)
 * counts as a clean exit. */
static void reap(struct loader *l, bool kill_now)
{
	const struct timespec ms = { .tv_nsec = 1000000 };
	l->wstatus = 0;
	while (!kill_now) {
		pid_t r = waitpid(l->pid, &l->wstatus, WNOHANG);
		if (r == l->pid || (r < 0 && errno == ECHILD))
			return;
		if (now_ms() >= l->deadline_ms) {
			l->timed_out = true;
			break;
		}
		nanosleep(&ms, NULL);
	}
	kill(l->pid, SIGKILL);
	wait_blocking(l);
}

/* What went wrong with the loader itself, if anything: 0 or -EINVAL with
 * reason filled. */
static int loader_failure(const struct loader *l, int rx, const char *why, char *reason, size_t reason_size)
{
	int st = l->wstatus;
	if (l->timed_out || rx == -ETIMEDOUT)
		snprintf(reason, reason_size, "the model loader took longer than %d s and was stopped",
			 (l->timeout_ms + 999) / 1000);
	else if (rx == -EPROTO)
		snprintf(reason, reason_size, "the model loader sent a malformed result (%s)", why);
	else if (rx < 0 && rx != -EPIPE)
		snprintf(reason, reason_size, "reading the model loader's result: %s", strerror(-rx));
	else if (WIFSIGNALED(st) && WTERMSIG(st) == SIGXCPU)
		snprintf(reason, reason_size, "the model loader used more than %u s of CPU time and was stopped",
			 l->cpu_s);
	else if (WIFSIGNALED(st))
		snprintf(reason, reason_size, "the model loader crashed (signal %d)", WTERMSIG(st));
	else if (WIFEXITED(st) && WEXITSTATUS(st) != 0)
		snprintf(reason, reason_size, "the model loader failed (exit status %d)", WEXITSTATUS(st));
	else if (rx == -EPIPE)
		snprintf(reason, reason_size, "the model loader sent a malformed result (cut short)");
	else
		return 0;
	return rx == -ENOMEM ? -ENOMEM : -EINVAL;
}

/* The child did its job: its error, or the checked model. */
static int verdict(const struct model_wire_header *h, const uint8_t *payload, struct model **out, char *reason,
		   size_t reason_size)
{
	char why[256];
	if (h->status != 0) {
		model_wire_error_text(payload, h->text_len, reason, reason_size);
		return -model_wire_error_errno(h->status);
	}
	int ret = model_wire_decode(h, payload, out, why, sizeof(why));
	if (ret == -EINVAL)
		snprintf(reason, reason_size, "the model loader sent a malformed result (%s)", why);
	else if (ret < 0)
		snprintf(reason, reason_size, "%s", why);
	return ret;
}

int model_sandbox_load(int fd, uint64_t size, const char *path, const struct model_companions *comp, struct model **out,
		       char *reason, size_t reason_size)
{
	struct model_confine c;
	struct loader l = { .timeout_ms = MODEL_LOADER_TIMEOUT_MS };
	struct model_wire_header h = { 0 };
	uint8_t *payload = NULL;
	char why[256] = "";

	model_confine_prepare(&c);
#ifdef SPINDLE_MODEL_TEST_HOOKS
	model_test_limits(&l.timeout_ms, &c);
#endif
	l.cpu_s = c.cpu_s;
	int ret = start(&l, fd, size, path, comp, &c);
	if (ret < 0) {
		snprintf(reason, reason_size, "cannot start the model loader: %s", strerror(-ret));
		return ret;
	}
	int rx = receive(&l, &h, &payload, why, sizeof(why));
	if (progress && rx == 0 && now_ms() - l.start_ms >= 1000) {
		fprintf(progress, "spindlectl: %s: read in %.1f s\n", path, (now_ms() - l.start_ms) / 1000.0);
		fflush(progress);
	}
	reap(&l, rx < 0 && rx != -EPIPE);
	close(l.rfd);
	ret = rx == -ENOMEM ? -ENOMEM : loader_failure(&l, rx, why, reason, reason_size);
	if (ret == -ENOMEM)
		snprintf(reason, reason_size, "%s", strerror(ENOMEM));
	else if (ret == 0)
		ret = verdict(&h, payload, out, reason, reason_size);
	free(payload);
	return ret;
}
