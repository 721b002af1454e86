/* The model loader child and its parent's side (model_sandbox.h), on the
 * sandboxed child that the scan loader uses too. fork() without exec: the
 * child is this program, confined before it reads a byte of the file, and
 * leaves with _exit() (no atexit handlers, no stdio flush, no leak check).
 * The parent reads the result within the deadline, always reaps the child
 * (killing it when the exchange failed) and says what happened to it: its
 * message, a crash, a timeout, a malformed result. */
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

/* ---- the child, whatever it loads ---- */

/* Where a slow load says that it goes on, or NULL. */
static FILE *progress;

void sandbox_set_progress(FILE *f)
{
	progress = f;
}

FILE *sandbox_progress(void)
{
	return progress;
}

void model_sandbox_set_progress(FILE *f)
{
	sandbox_set_progress(f);
}

static int64_t now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

#define SANDBOX_PIPE_BYTES (1 << 20)

int sandbox_start(struct sandbox *sb, sandbox_child_fn fn, void *arg)
{
	int p[2];
	if (pipe2(p, O_CLOEXEC) < 0)
		return -errno;
	/* A scan's hundreds of MB cross it: 1 MiB at a time (the most an
	 * unprivileged process may ask by default) rather than 64 KiB cuts the
	 * switches between child and parent. Only a hint: failing is fine. */
	(void)fcntl(p[0], F_SETPIPE_SZ, SANDBOX_PIPE_BYTES);
	sb->pid = fork();
	if (sb->pid < 0) {
		int e = errno;
		close(p[0]);
		close(p[1]);
		return -e;
	}
	if (sb->pid == 0) {
		close(p[0]);
		fn(arg, p[1]);
		_exit(1);
	}
	close(p[1]);
	sb->rfd = p[0];
	sb->start_ms = now_ms();
	sb->deadline_ms = sb->start_ms + sb->timeout_ms;
	sb->note_ms = sb->start_ms; /* note_progress() sets the first at 1 s */
	sb->timed_out = false;
	sb->wstatus = 0;
	return 0;
}

/* A load that takes over a second says so, and again every two seconds. */
static void note_progress(struct sandbox *sb, int64_t now)
{
	if (!progress || now < sb->note_ms)
		return;
	if (sb->note_ms > sb->start_ms) {
		fprintf(progress, "spindlectl: %s: loading, %.0f s so far\n", sb->path, (now - sb->start_ms) / 1000.0);
		fflush(progress);
	}
	sb->note_ms = sb->note_ms > sb->start_ms ? sb->note_ms + 2000 : sb->start_ms + 1000;
}

int sandbox_read(struct sandbox *sb, void *buf, size_t len)
{
	uint8_t *p = buf;
	while (len > 0) {
		int64_t now = now_ms(), left = sb->deadline_ms - now;
		struct pollfd pfd = { .fd = sb->rfd, .events = POLLIN };
		if (left <= 0)
			return -ETIMEDOUT;
		note_progress(sb, now);
		if (progress && sb->note_ms - now < left)
			left = sb->note_ms - now;
		int n = poll(&pfd, 1, left > INT_MAX ? INT_MAX : (int)left);
		if (n < 0 && errno != EINTR)
			return -errno;
		if (n <= 0)
			continue;
		ssize_t r = read(sb->rfd, p, len < (1u << 30) ? len : (1u << 30));
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

int sandbox_read_end(struct sandbox *sb, char *why, size_t why_size)
{
	uint8_t extra;
	int ret = sandbox_read(sb, &extra, 1);
	if (ret == 0) {
		snprintf(why, why_size, "more bytes than it announced");
		return -EPROTO;
	}
	if (ret == -EPIPE && progress && now_ms() - sb->start_ms >= 1000) {
		fprintf(progress, "spindlectl: %s: read in %.1f s\n", sb->path, (now_ms() - sb->start_ms) / 1000.0);
		fflush(progress);
	}
	return ret == -EPIPE ? 0 : ret;
}

static void wait_blocking(struct sandbox *sb)
{
	while (waitpid(sb->pid, &sb->wstatus, 0) < 0 && errno == EINTR)
		;
}

/* A child already reaped by someone (SIGCHLD ignored) counts as a clean
 * exit. */
void sandbox_reap(struct sandbox *sb, bool kill_now)
{
	const struct timespec ms = { .tv_nsec = 1000000 };
	sb->wstatus = 0;
	while (!kill_now) {
		pid_t r = waitpid(sb->pid, &sb->wstatus, WNOHANG);
		if (r == sb->pid || (r < 0 && errno == ECHILD))
			goto out;
		if (now_ms() >= sb->deadline_ms) {
			sb->timed_out = true;
			break;
		}
		nanosleep(&ms, NULL);
	}
	kill(sb->pid, SIGKILL);
	wait_blocking(sb);
out:
	close(sb->rfd);
	sb->rfd = -1;
}

int sandbox_failure(const struct sandbox *sb, int rx, const char *why, char *reason, size_t reason_size)
{
	int st = sb->wstatus;
	if (sb->timed_out || rx == -ETIMEDOUT)
		snprintf(reason, reason_size, "the %s took longer than %d s and was stopped", sb->name,
			 (sb->timeout_ms + 999) / 1000);
	else if (rx == -EPROTO)
		snprintf(reason, reason_size, "the %s sent a malformed result (%s)", sb->name, why);
	else if (rx == -ENOMEM)
		snprintf(reason, reason_size, "%s", strerror(ENOMEM));
	else if (rx < 0 && rx != -EPIPE)
		snprintf(reason, reason_size, "reading the %s's result: %s", sb->name, strerror(-rx));
	else if (WIFSIGNALED(st) && WTERMSIG(st) == SIGXCPU)
		snprintf(reason, reason_size, "the %s used more than %u s of CPU time and was stopped", sb->name,
			 sb->cpu_s);
	else if (WIFSIGNALED(st))
		snprintf(reason, reason_size, "the %s crashed (signal %d)", sb->name, WTERMSIG(st));
	else if (WIFEXITED(st) && WEXITSTATUS(st) != 0)
		snprintf(reason, reason_size, "the %s failed (exit status %d)", sb->name, WEXITSTATUS(st));
	else if (rx == -EPIPE)
		snprintf(reason, reason_size, "the %s sent a malformed result (cut short)", sb->name);
	else
		return 0;
	return rx == -ENOMEM ? -ENOMEM : -EINVAL;
}

/* ---- the model loader ---- */

struct model_child {
	int fd;
	uint64_t size;
	const char *path;
	const struct model_companions *comp;
	const struct model_confine *confine;
};

static __attribute__((noreturn)) void model_child_main(void *arg, int out_fd)
{
	const struct model_child *m = arg;
	char why[512];
	struct model_mesh mesh;
	int in_fd = m->fd;
	int ret = model_confine_child(m->confine, &in_fd, &out_fd, why, sizeof(why));
	if (ret < 0)
		_exit(model_wire_send_error(out_fd, -ret, why) < 0 ? 1 : 0);
#ifdef SPINDLE_MODEL_TEST_HOOKS
	model_test_hook(in_fd, out_fd, model_wire_send_error);
#endif
	ret = model_import_fd(in_fd, m->size, m->path, m->comp, &mesh, why, sizeof(why));
	if (ret < 0)
		ret = model_wire_send_error(out_fd, -ret, why);
	else
		ret = model_wire_send_mesh(out_fd, &mesh);
	_exit(ret < 0 ? 1 : 0);
}

/* The whole message and the end of the pipe: 0, -ETIMEDOUT, -EPIPE (cut
 * short), -EPROTO (malformed: why filled), -ENOMEM or -errno. */
static int receive(struct sandbox *sb, struct model_wire_header *h, uint8_t **payload, char *why, size_t why_size)
{
	size_t len = 0;
	int ret = sandbox_read(sb, h, sizeof(*h));
	if (ret < 0)
		return ret;
	if (model_wire_check_header(h, &len, why, why_size) < 0)
		return -EPROTO;
	*payload = malloc(len ? len : 1);
	if (!*payload)
		return -ENOMEM;
	ret = sandbox_read(sb, *payload, len);
	return ret < 0 ? ret : sandbox_read_end(sb, why, why_size);
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
	struct sandbox sb = { .name = "model loader", .path = path, .timeout_ms = MODEL_LOADER_TIMEOUT_MS };
	struct model_wire_header h = { 0 };
	uint8_t *payload = NULL;
	char why[256] = "";

	model_confine_prepare(&c);
#ifdef SPINDLE_MODEL_TEST_HOOKS
	model_test_limits(&sb.timeout_ms, &c);
#endif
	sb.cpu_s = c.cpu_s;
	struct model_child child = { .fd = fd, .size = size, .path = path, .comp = comp, .confine = &c };
	int ret = sandbox_start(&sb, model_child_main, &child);
	if (ret < 0) {
		snprintf(reason, reason_size, "cannot start the model loader: %s", strerror(-ret));
		return ret;
	}
	int rx = receive(&sb, &h, &payload, why, sizeof(why));
	sandbox_reap(&sb, rx < 0 && rx != -EPIPE);
	ret = sandbox_failure(&sb, rx, why, reason, reason_size);
	if (ret == 0)
		ret = verdict(&h, payload, out, reason, reason_size);
	free(payload);
	return ret;
}
