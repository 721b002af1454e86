/* From `spindlectl show` of a CT-sized scan to its first shown volume, and
 * the daemon's memory for it (issue #22, item 8): a 150 MB scan should be
 * on the display within 1 s of the command, and cost the daemon at most
 * 1.1x its size.
 *
 * Makes the scan once, before anything is timed: a 512 x 512 x 300 int16
 * NIfTI-1 file (157 MB of samples, 0.5 x 0.5 x 0.6 mm: a CT of a head) of
 * the 3-D Shepp-Logan phantom in Hounsfield units, written by
 * scripts/make-phantom into a directory under /tmp that is removed at the
 * end (it is in the page cache from then on: a file read from disk adds
 * its read). Starts spindled on the simulated device at the perspecta
 * profile with the cpu renderer (or uses a running one), and N times
 * (--warmup, default 1: the daemon's first render allocates its working
 * volumes), then R times (default 5), measured:
 *
 *   spawns `spindlectl --socket SOCK show FILE` and times, from just before
 *   the fork, the line spindlectl prints on what it shows (the sandboxed
 *   loader has read the file, laid the samples out and sent them into a
 *   memfd, and the window's statistics are taken) and then `shown SEQ`
 *   (connected, the memfd sent, the daemon's create_volume copied it into
 *   the renderers' layout, the commit rendered and shown); then SIGTERM
 *   (spindlectl catches it once it has printed `shown`) and waits for it:
 *   exit status 0 expected.
 *
 * The daemon's memory: VmRSS before the spawn and just after `shown`, and
 * VmHWM, the peak, reset before each run (5 into /proc/PID/clear_refs)
 * when the kernel lets us; (shown - before) / the scan's sample bytes is
 * the "x its size" figure, (peak - before) / sample bytes the transient
 * one. The daemon's own wall time of the render that showed it is
 * spindle_get_status()'s render_us, read just after `shown`. After each
 * run it waits until the daemon has let spindlectl go (as many clients
 * and as much memory_used as at the start) and has rendered the scene
 * without the scan, and reads VmRSS again: what the scan left behind.
 *
 * Prints one Markdown row (medians, and the max of the total); progress
 * and each run on stderr. Exits 1 when something fails, not when a
 * target is missed.
 *
 * Usage: show-bench [--runs R] [--warmup N] [--size NX,NY,NZ]
 *                   [--spindlectl PATH] [--header] SPINDLED|SOCKET */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "daemon.h"
#include "spindle/spindle.h"

#ifndef BENCH_MAKE_PHANTOM
#define BENCH_MAKE_PHANTOM "scripts/make-phantom"
#endif

static const char prog[] = "show-bench";

/* Waiting for spindlectl's lines, and for the daemon to be idle again. */
#define SHOW_TIMEOUT_MS 120000
#define IDLE_TIMEOUT_MS 10000

struct options {
	int runs, warmup;
	uint32_t size[3];
	const char *spindlectl;
	bool header;
	const char *target;
};

/* One run. Times in ns from just before the fork; memory in KiB. */
struct run {
	int64_t loaded, shown;
	uint64_t rss_before, rss_shown, hwm, rss_after;
	uint32_t render_us;
	uint64_t rendered; /* volumes_rendered when it was shown */
};

struct bench {
	struct options opt;
	struct spindle *sp;
	const char *socket;
	pid_t pid;
	char dir[64];   /* the scan's temporary directory */
	char scan[128]; /* the scan */
	uint64_t sample_bytes;
	uint32_t clients0;     /* clients and memory_used when idle */
	uint64_t memory_used0; /* (0 when the daemon does not say) */
	bool hwm_reset;        /* clear_refs worked: VmHWM is this run's */
	struct run *runs;
};

static void die(const char *what, int err)
{
	bench_die(prog, what, err);
}

static void get_status(struct bench *b, struct spindle_status *st)
{
	int r = spindle_get_status(b->sp, st);
	if (r < 0) {
		const char *why = spindle_get_error(b->sp);
		fprintf(stderr, "%s: status: %s\n", prog, why ? why : strerror(-r));
		exit(1);
	}
}

/* ---- the scan ---- */

static void remove_scan(struct bench *b)
{
	if (b->scan[0])
		unlink(b->scan);
	if (b->dir[0])
		rmdir(b->dir);
	b->scan[0] = b->dir[0] = '\0';
}

/* Removed or stopped at exit, a failure's too: the scan, and a daemon
 * started here (main() clears cleanup_daemon before bench_daemon_stop()). */
static struct bench *cleanup_bench;
static struct bench_daemon *cleanup_daemon;

static void cleanup_at_exit(void)
{
	if (cleanup_bench)
		remove_scan(cleanup_bench);
	/* (Unless bench_daemon_connect() has reaped it already.) */
	if (cleanup_daemon && cleanup_daemon->ours && waitpid(cleanup_daemon->pid, NULL, WNOHANG) == 0) {
		kill(cleanup_daemon->pid, SIGTERM);
		waitpid(cleanup_daemon->pid, NULL, 0);
		fprintf(stderr, "%s: spindled stopped; its log is in %s\n", prog, cleanup_daemon->dir);
	}
}

/* Runs argv, its stdout to our stderr; 0 when it exited with status 0. */
static int run_quietly(char *const argv[])
{
	pid_t pid = fork();
	if (pid < 0)
		die("fork", errno);
	if (pid == 0) {
		dup2(2, 1);
		execv(argv[0], argv);
		fprintf(stderr, "%s: %s: %s\n", prog, argv[0], strerror(errno));
		_exit(127);
	}
	int status;
	while (waitpid(pid, &status, 0) < 0)
		if (errno != EINTR)
			die("waitpid", errno);
	return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : -1;
}

/* The phantom as a CT, by scripts/make-phantom (Python, a few seconds). */
static void make_scan(struct bench *b)
{
	snprintf(b->dir, sizeof(b->dir), "/tmp/spindle-show-bench-XXXXXX");
	if (!mkdtemp(b->dir))
		die("mkdtemp", errno);
	cleanup_bench = b;
	atexit(cleanup_at_exit);
	snprintf(b->scan, sizeof(b->scan), "%s/ct.nii", b->dir);
	char size[48];
	snprintf(size, sizeof(size), "%u,%u,%u", b->opt.size[0], b->opt.size[1], b->opt.size[2]);
	char *argv[] = { BENCH_MAKE_PHANTOM, "--size", size, "--spacing", "0.5,0.5,0.6", "--nii", b->scan, NULL };
	int64_t t0 = bench_mono_ns();
	if (run_quietly(argv) < 0) {
		fprintf(stderr, "%s: %s --size %s failed\n", prog, BENCH_MAKE_PHANTOM, size);
		exit(1);
	}
	struct stat st;
	if (stat(b->scan, &st) < 0)
		die(b->scan, errno);
	if ((uint64_t)st.st_size < b->sample_bytes + 352) {
		fprintf(stderr, "%s: %s holds %lld bytes, fewer than its samples\n", prog, b->scan,
			(long long)st.st_size);
		exit(1);
	}
	fprintf(stderr, "%s: %s: %ux%ux%u int16, %.1f MB of samples, made in %.1f s\n", prog, b->scan, b->opt.size[0],
		b->opt.size[1], b->opt.size[2], (double)b->sample_bytes / 1e6, (double)(bench_mono_ns() - t0) / 1e9);
}

/* ---- one run ---- */

/* spindlectl show, its stdout and stderr on the pipes out[0], err[0]. */
static pid_t spawn_show(const struct bench *b, int out[2], int err[2])
{
	if (pipe2(out, O_CLOEXEC) < 0 || pipe2(err, O_CLOEXEC) < 0)
		die("pipe2", errno);
	pid_t pid = fork();
	if (pid < 0)
		die("fork", errno);
	if (pid == 0) {
		dup2(out[1], 1);
		dup2(err[1], 2);
		unsetenv("SPINDLE_SOCKET");
		execl(b->opt.spindlectl, b->opt.spindlectl, "--socket", b->socket, "show", b->scan, (char *)NULL);
		fprintf(stderr, "%s: %s: %s\n", prog, b->opt.spindlectl, strerror(errno));
		_exit(127);
	}
	close(out[1]);
	close(err[1]);
	return pid;
}

/* A pipe read line by line. */
struct lines {
	int fd;
	char buf[4096];
	size_t len;
};

/* Reads what is there; calls line() for each whole line (and the rest at
 * the end of the pipe). false at the end of the pipe. */
static bool read_lines(struct lines *l, void (*line)(void *, const char *, int64_t), void *arg)
{
	ssize_t n = read(l->fd, l->buf + l->len, sizeof(l->buf) - 1 - l->len);
	if (n < 0 && (errno == EINTR || errno == EAGAIN))
		return true;
	int64_t now = bench_mono_ns();
	if (n > 0)
		l->len += (size_t)n;
	char *start = l->buf, *nl;
	l->buf[l->len] = '\0';
	while ((nl = memchr(start, '\n', l->len - (size_t)(start - l->buf)))) {
		*nl = '\0';
		line(arg, start, now);
		start = nl + 1;
	}
	l->len -= (size_t)(start - l->buf);
	memmove(l->buf, start, l->len);
	if (n <= 0 || l->len == sizeof(l->buf) - 1) { /* the end, or a line too long: as it is */
		if (l->len) {
			l->buf[l->len] = '\0';
			line(arg, l->buf, now);
		}
		l->len = 0;
	}
	return n > 0;
}

struct show_state {
	int64_t t0, loaded, shown;
	const char *name; /* "run N", "warm-up" */
};

static void stdout_line(void *arg, const char *line, int64_t now)
{
	struct show_state *s = arg;
	if (!strncmp(line, "shown ", 6) && !s->shown)
		s->shown = now - s->t0;
	else if (!s->loaded)
		s->loaded = now - s->t0;
	fprintf(stderr, "%s: %s: %7.3f s: %s\n", prog, s->name, (double)(now - s->t0) / 1e9, line);
}

static void stderr_line(void *arg, const char *line, int64_t now)
{
	struct show_state *s = arg;
	fprintf(stderr, "%s: %s: %7.3f s: (stderr) %s\n", prog, s->name, (double)(now - s->t0) / 1e9, line);
}

/* While the scan is shown: the daemon's memory, and its render's time,
 * into r. */
static void note_shown(struct bench *b, struct run *r)
{
	struct bench_memory m;
	struct spindle_status st;
	bench_memory(prog, b->pid, &m);
	get_status(b, &st);
	r->rss_shown = m.rss_kib;
	r->hwm = m.hwm_kib;
	r->render_us = st.render_us;
	r->rendered = st.volumes_rendered;
}

/* Waits for spindlectl to exit. 0 when it showed the scan and exited
 * with status 0. */
static int reap_show(pid_t pid, const struct show_state *s)
{
	int status;
	while (waitpid(pid, &status, 0) < 0)
		if (errno != EINTR)
			die("waitpid", errno);
	if (!s->shown)
		return -1;
	if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
		fprintf(stderr, "%s: %s: spindlectl exited with status %d (signal %d) after SIGTERM\n", prog, s->name,
			WIFEXITED(status) ? WEXITSTATUS(status) : -1, WIFSIGNALED(status) ? WTERMSIG(status) : 0);
		return -1;
	}
	return 0;
}

/* Until both pipes end; stops spindlectl once `shown` came (or on the
 * timeout). 0 when it showed the scan and exited with status 0. */
static int follow(struct bench *b, pid_t pid, struct show_state *s, struct run *r, int out_fd, int err_fd)
{
	struct lines lo = { .fd = out_fd }, le = { .fd = err_fd };
	struct pollfd fds[2] = { { .fd = out_fd, .events = POLLIN }, { .fd = err_fd, .events = POLLIN } };
	bool stopped = false;
	while (fds[0].fd >= 0 || fds[1].fd >= 0) {
		int64_t left_ms = SHOW_TIMEOUT_MS - (bench_mono_ns() - s->t0) / 1000000;
		if (!stopped && left_ms <= 0) {
			fprintf(stderr, "%s: %s: nothing shown in %d s\n", prog, s->name, SHOW_TIMEOUT_MS / 1000);
			kill(pid, SIGKILL);
			stopped = true;
		}
		if (poll(fds, 2, stopped ? -1 : (int)(left_ms > 0 ? left_ms : 0)) < 0 && errno != EINTR)
			die("poll", errno);
		if (fds[0].fd >= 0 && fds[0].revents && !read_lines(&lo, stdout_line, s))
			fds[0].fd = -1;
		if (fds[1].fd >= 0 && fds[1].revents && !read_lines(&le, stderr_line, s))
			fds[1].fd = -1;
		if (s->shown && !stopped) {
			note_shown(b, r);
			kill(pid, SIGTERM); /* spindlectl catches it from `shown` on */
			stopped = true;
		}
	}
	close(out_fd);
	close(err_fd);
	return reap_show(pid, s);
}

/* Until the daemon has dropped the last run's client and volume (as many
 * clients and as much memory_used as at the start) and, given rendered,
 * has rendered a volume after that many (the scene without the scan; up
 * to 2 s, as a daemon that renders nothing more is no failure). */
static void wait_idle(struct bench *b, const uint64_t *rendered)
{
	int64_t t0 = bench_mono_ns();
	for (;;) {
		struct spindle_status st;
		get_status(b, &st);
		int64_t ms = (bench_mono_ns() - t0) / 1000000;
		if (st.clients <= b->clients0 && st.limits.memory_used <= b->memory_used0 &&
		    (!rendered || st.volumes_rendered > *rendered || ms > 2000))
			return;
		if (ms > IDLE_TIMEOUT_MS) {
			fprintf(stderr, "%s: the daemon still holds %u clients and %llu bytes after %d s\n", prog,
				st.clients, (unsigned long long)st.limits.memory_used, IDLE_TIMEOUT_MS / 1000);
			exit(1);
		}
		bench_sleep_ms(5);
	}
}

/* VmHWM back to VmRSS, so that it is this run's peak (Linux 4.0 on). */
static bool reset_hwm(pid_t pid)
{
	char path[64];
	snprintf(path, sizeof(path), "/proc/%d/clear_refs", (int)pid);
	int fd = open(path, O_WRONLY | O_CLOEXEC);
	bool ok = fd >= 0 && write(fd, "5", 1) == 1;
	if (fd >= 0)
		close(fd);
	return ok;
}

/* Run i of the warm-ups and the measured runs, in that order. */
static void run_once(struct bench *b, int i)
{
	struct run *r = &b->runs[i];
	char name[32];
	if (i < b->opt.warmup)
		snprintf(name, sizeof(name), "warm-up %d", i + 1);
	else
		snprintf(name, sizeof(name), "run %d", i - b->opt.warmup + 1);
	if (i == 0)
		wait_idle(b, NULL);
	b->hwm_reset = reset_hwm(b->pid) && b->hwm_reset;
	struct bench_memory m;
	bench_memory(prog, b->pid, &m);
	r->rss_before = m.rss_kib;
	int out[2], err[2];
	struct show_state s = { .name = name };
	s.t0 = bench_mono_ns();
	pid_t pid = spawn_show(b, out, err);
	if (follow(b, pid, &s, r, out[0], err[0]) < 0) {
		fprintf(stderr, "%s: %s failed\n", prog, name);
		exit(1);
	}
	r->loaded = s.loaded;
	r->shown = s.shown;
	wait_idle(b, &r->rendered);
	bench_memory(prog, b->pid, &m);
	r->rss_after = m.rss_kib;
	double mb = (double)b->sample_bytes;
	fprintf(stderr,
		"%s: %s: shown after %.3f s (loaded %.3f s, then %.3f s; the daemon's render %.3f s); "
		"daemon RSS %.1f -> %.1f MB (%.2fx the samples), peak %.1f MB (%.2fx), %.1f MB once it is gone\n",
		prog, name, (double)r->shown / 1e9, (double)r->loaded / 1e9, (double)(r->shown - r->loaded) / 1e9,
		r->render_us / 1e6, r->rss_before * 1024 / 1e6, r->rss_shown * 1024 / 1e6,
		((double)r->rss_shown - (double)r->rss_before) * 1024 / mb, r->hwm * 1024 / 1e6,
		((double)r->hwm - (double)r->rss_before) * 1024 / mb, r->rss_after * 1024 / 1e6);
}

/* ---- the row ---- */

static int compare_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* The median (the lower of the middle two) and the max of n values
 * get(run) over the runs. */
static double stat_of(const struct bench *b, double (*get)(const struct bench *, const struct run *), bool max)
{
	int n = b->opt.runs;
	double *v = malloc((size_t)n * sizeof(*v));
	if (!v)
		die("malloc", errno);
	for (int i = 0; i < n; i++)
		v[i] = get(b, &b->runs[b->opt.warmup + i]);
	qsort(v, (size_t)n, sizeof(*v), compare_double);
	double out = max ? v[n - 1] : v[(n - 1) / 2];
	free(v);
	return out;
}

static double get_total(const struct bench *b, const struct run *r)
{
	(void)b;
	return (double)r->shown / 1e9;
}

static double get_loaded(const struct bench *b, const struct run *r)
{
	(void)b;
	return (double)r->loaded / 1e9;
}

static double get_after_load(const struct bench *b, const struct run *r)
{
	(void)b;
	return (double)(r->shown - r->loaded) / 1e9;
}

static double get_render(const struct bench *b, const struct run *r)
{
	(void)b;
	return r->render_us / 1e6;
}

static double get_grown(const struct bench *b, const struct run *r)
{
	(void)b;
	return ((double)r->rss_shown - (double)r->rss_before) * 1024 / 1e6;
}

static double get_ratio(const struct bench *b, const struct run *r)
{
	return ((double)r->rss_shown - (double)r->rss_before) * 1024 / (double)b->sample_bytes;
}

static double get_peak_ratio(const struct bench *b, const struct run *r)
{
	return ((double)r->hwm - (double)r->rss_before) * 1024 / (double)b->sample_bytes;
}

static double get_left(const struct bench *b, const struct run *r)
{
	(void)b;
	return ((double)r->rss_after - (double)r->rss_before) * 1024 / 1e6;
}

static void print_row(const struct bench *b)
{
	if (b->opt.header) {
		printf("| scan | runs | to shown, median s | max s | loaded s | then shown s | daemon render s "
		       "| daemon RSS at start MB | shown - before MB | / samples | peak - before / samples "
		       "| left once gone MB |\n");
		printf("|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
	}
	printf("| %ux%ux%u int16 NIfTI, %.1f MB | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f | %.0f | %.2fx "
	       "| %.2fx%s | %.0f |\n",
	       b->opt.size[0], b->opt.size[1], b->opt.size[2], (double)b->sample_bytes / 1e6, b->opt.runs,
	       stat_of(b, get_total, false), stat_of(b, get_total, true), stat_of(b, get_loaded, false),
	       stat_of(b, get_after_load, false), stat_of(b, get_render, false),
	       (double)b->runs[0].rss_before * 1024 / 1e6, stat_of(b, get_grown, false), stat_of(b, get_ratio, false),
	       stat_of(b, get_peak_ratio, false), b->hwm_reset ? "" : " (VmHWM not reset: since the start)",
	       stat_of(b, get_left, false));
	fflush(stdout);
	double total = stat_of(b, get_total, false), ratio = stat_of(b, get_ratio, false);
	fprintf(stderr,
		"%s: target <= 1 s to the first shown volume: %s (median %.2f s); "
		"daemon memory <= 1.1x the scan: %s (%.2fx)\n",
		prog, total <= 1.0 ? "met" : "missed", total, ratio <= 1.1 ? "met" : "missed", ratio);
}

/* ---- options ---- */

static void usage(void)
{
	fprintf(stderr, "usage: show-bench [--runs R] [--warmup N] [--size NX,NY,NZ] [--spindlectl PATH] [--header] "
			"SPINDLED|SOCKET\n");
	exit(2);
}

static bool parse_size(const char *s, uint32_t out[3])
{
	char *end;
	for (int a = 0; a < 3; a++) {
		errno = 0;
		unsigned long v = strtoul(s, &end, 10);
		if (errno || end == s || v < 1 || v > 4096 || *end != (a < 2 ? ',' : '\0'))
			return false;
		out[a] = (uint32_t)v;
		s = end + 1;
	}
	return true;
}

/* spindlectl beside this program in the build tree: ../tools/spindlectl. */
static const char *default_spindlectl(void)
{
	static char path[PATH_MAX];
	ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 32);
	if (n <= 0)
		return "spindlectl";
	path[n] = '\0';
	char *slash = strrchr(path, '/');
	snprintf(slash ? slash + 1 : path, 32, "../tools/spindlectl");
	return path;
}

static void parse_options(int argc, char **argv, struct options *o)
{
	*o = (struct options){ 5, 1, { 512, 512, 300 }, NULL, false, NULL };
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		bool more = i + 1 < argc;
		if (!strcmp(a, "--runs") && more)
			o->runs = atoi(argv[++i]);
		else if (!strcmp(a, "--warmup") && more)
			o->warmup = atoi(argv[++i]);
		else if (!strcmp(a, "--size") && more) {
			if (!parse_size(argv[++i], o->size))
				usage();
		} else if (!strcmp(a, "--spindlectl") && more)
			o->spindlectl = argv[++i];
		else if (!strcmp(a, "--header"))
			o->header = true;
		else if (a[0] != '-' && !o->target)
			o->target = a;
		else
			usage();
	}
	if (!o->target || o->runs < 1 || o->runs > 1000 || o->warmup < 0 || o->warmup > 100)
		usage();
	if (!o->spindlectl)
		o->spindlectl = default_spindlectl();
}

int main(int argc, char **argv)
{
	struct bench b = { .hwm_reset = true };
	parse_options(argc, argv, &b.opt);
	if (access(b.opt.spindlectl, X_OK) < 0)
		die(b.opt.spindlectl, errno);
	b.sample_bytes = (uint64_t)b.opt.size[0] * b.opt.size[1] * b.opt.size[2] * 2;
	b.runs = calloc((size_t)(b.opt.warmup + b.opt.runs), sizeof(*b.runs));
	if (!b.runs)
		die("calloc", errno);
	make_scan(&b);

	struct bench_daemon d = { 0 };
	bench_daemon_start(&d, prog, b.opt.target, "perspecta", "cpu");
	cleanup_daemon = &d;
	b.sp = bench_daemon_connect(&d);
	if (!b.sp)
		die("connect", errno);
	b.socket = d.socket;
	b.pid = bench_daemon_pid(&d, b.sp);
	struct spindle_status st;
	get_status(&b, &st);
	b.clients0 = st.clients;
	b.memory_used0 = st.limits.memory_used;
	const struct spindle_device_info *info = spindle_get_device_info(b.sp);
	fprintf(stderr, "%s: %s (%ux%u, N = %u%s)\n", prog, info->name, info->width, info->height, info->images_per_rev,
		info->mirrored ? ", mirrored" : "");

	for (int i = 0; i < b.opt.warmup + b.opt.runs; i++)
		run_once(&b, i);
	print_row(&b);

	spindle_disconnect(b.sp);
	cleanup_daemon = NULL;
	bench_daemon_stop(&d);
	remove_scan(&b);
	free(b.runs);
	return 0;
}
