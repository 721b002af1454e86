/* Benchmark scene S0 at daemon level: an unchanged scene.
 *
 * Starts spindled on the simulated perspecta device on a private socket (or
 * connects to a running daemon), shows a torus of a few thousand triangles,
 * then for S seconds commits the unchanged state with a frame callback, the
 * next commit as soon as the previous callback is done (one a revolution),
 * and then stays idle for as long without a request. Prints one Markdown
 * table row: commits, callbacks answered, volumes rendered and bytes
 * uploaded during the commit phase (from display.status), the daemon's CPU
 * use in each phase (utime + stime of /proc/PID/stat, all threads) and the
 * longest time from a commit to its done event.
 *
 * Usage: unchanged [--seconds S] [--header] SPINDLED|SOCKET */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon.h"
#include "spindle/spindle.h"

#define TORUS_RINGS 64
#define TORUS_SIDES 32 /* 2 * 64 * 32 = 4096 triangles */

static const char prog[] = "unchanged";

_Noreturn static void die(const char *what, int err)
{
	bench_die(prog, what, err);
}

/* ---- the scene ---- */

static void torus_point(float *out, int ring, int side)
{
	const double big = 0.6, small = 0.25;
	double a = 2 * M_PI * ring / TORUS_RINGS, b = 2 * M_PI * side / TORUS_SIDES;
	double r = big + small * cos(b);
	out[0] = (float)(r * cos(a));
	out[1] = (float)(small * sin(b));
	out[2] = (float)(r * sin(a));
}

/* Two triangles per quad; returns the vertex count. */
static uint32_t torus(float *v)
{
	uint32_t n = 0;
	for (int i = 0; i < TORUS_RINGS; i++)
		for (int j = 0; j < TORUS_SIDES; j++) {
			static const int quad[6][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 0 }, { 1, 1 }, { 0, 1 } };
			for (int k = 0; k < 6; k++, n++)
				torus_point(v + 3 * n, i + quad[k][0], j + quad[k][1]);
		}
	return n;
}

static uint64_t show_scene(struct spindle *sp)
{
	static float v[TORUS_RINGS * TORUS_SIDES * 18];
	uint32_t n = torus(v);
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, (size_t)n * 12);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	if (!buf || !list || !layer)
		die("creating the scene", errno);
	spindle_list_set_color(list, 255, 160, 0, 255);
	spindle_list_triangles(list, buf, 0, n, 0);
	spindle_layer_set_list(layer, list);
	struct spindle_frame f;
	int r = spindle_commit_and_wait(sp, &f);
	if (r < 0)
		die("showing the scene", -r);
	return f.volume_seq;
}

/* ---- the phases ---- */

struct commit_phase {
	uint64_t commits, answered;
	int64_t max_latency_ns;
	uint64_t early; /* done times before their commit: a daemon bug */
	struct spindle_status before, after;
	double cpu;
};

struct pending_frame {
	bool done;
	struct spindle_frame frame;
};

static void on_frame(void *data, const struct spindle_frame *frame)
{
	struct pending_frame *pf = data;
	pf->frame = *frame;
	pf->done = true;
}

/* Waits up to 2 s for pf. */
static bool wait_frame(struct spindle *sp, struct pending_frame *pf)
{
	int64_t deadline = bench_mono_ns() + 2000000000;
	while (!pf->done && bench_mono_ns() < deadline) {
		struct pollfd p = { spindle_get_fd(sp), POLLIN, 0 };
		if (spindle_flush(sp) < 0 || poll(&p, 1, 100) < 0 || spindle_dispatch(sp) < 0)
			return false;
	}
	return pf->done;
}

/* One unchanged commit with a frame callback, waited for. */
static void commit_once(struct spindle *sp, struct commit_phase *ph)
{
	struct pending_frame pf = { 0 };
	int64_t t0 = bench_mono_ns();
	if (spindle_request_frame(sp, on_frame, &pf) < 0 || spindle_commit(sp) < 0)
		die("commit", EPIPE);
	ph->commits++;
	if (!wait_frame(sp, &pf))
		return;
	int64_t latency = bench_mono_ns() - t0;
	ph->answered++;
	ph->early += (int64_t)pf.frame.time_ns < t0;
	if (latency > ph->max_latency_ns)
		ph->max_latency_ns = latency;
}

static void get_status(struct spindle *sp, struct spindle_status *st)
{
	int r = spindle_get_status(sp, st);
	if (r < 0)
		die("status", -r);
}

static void run_commits(struct spindle *sp, pid_t pid, double seconds, struct commit_phase *ph)
{
	get_status(sp, &ph->before);
	double cpu0 = bench_cpu_seconds(prog, pid);
	int64_t start = bench_mono_ns(), end = start + (int64_t)(seconds * 1e9);
	while (bench_mono_ns() < end)
		commit_once(sp, ph);
	ph->cpu = 100.0 * (bench_cpu_seconds(prog, pid) - cpu0) / ((double)(bench_mono_ns() - start) / 1e9);
	get_status(sp, &ph->after);
}

static double run_idle(pid_t pid, double seconds)
{
	double cpu0 = bench_cpu_seconds(prog, pid);
	int64_t start = bench_mono_ns();
	bench_sleep_ms((int)(seconds * 1000));
	return 100.0 * (bench_cpu_seconds(prog, pid) - cpu0) / ((double)(bench_mono_ns() - start) / 1e9);
}

static void print_row(const struct commit_phase *ph, double idle_cpu, bool header)
{
	if (header) {
		printf("| scene | commits | callbacks answered | volumes rendered | bytes uploaded | "
		       "daemon CPU %% | max done latency (ms) | idle daemon CPU %% |\n");
		printf("|---|---|---|---|---|---|---|---|\n");
	}
	printf("| S0 unchanged | %llu | %llu | %llu | %llu | %.2f | %.1f | %.2f |\n", (unsigned long long)ph->commits,
	       (unsigned long long)ph->answered,
	       (unsigned long long)(ph->after.volumes_rendered - ph->before.volumes_rendered),
	       (unsigned long long)(ph->after.bytes_uploaded - ph->before.bytes_uploaded), ph->cpu,
	       (double)ph->max_latency_ns / 1e6, idle_cpu);
}

static void usage(void)
{
	fprintf(stderr, "usage: unchanged [--seconds S] [--header] SPINDLED|SOCKET\n");
	exit(2);
}

int main(int argc, char **argv)
{
	double seconds = 10;
	bool header = false;
	const char *target = NULL;
	for (int i = 1; i < argc; i++) {
		if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc)
			seconds = atof(argv[++i]);
		else if (strcmp(argv[i], "--header") == 0)
			header = true;
		else if (argv[i][0] != '-' && !target)
			target = argv[i];
		else
			usage();
	}
	if (!target || !(seconds > 0))
		usage();
	struct bench_daemon d = { 0 };
	bench_daemon_start(&d, prog, target, "perspecta", NULL);
	struct spindle *sp = bench_daemon_connect(&d);
	if (!sp)
		die("connect", errno);
	pid_t pid = bench_daemon_pid(&d, sp);
	uint64_t seq = show_scene(sp);
	struct commit_phase ph = { 0 };
	run_commits(sp, pid, seconds, &ph);
	double idle = run_idle(pid, seconds);
	print_row(&ph, idle, header);
	if (ph.early || ph.answered < ph.commits)
		fprintf(stderr, "unchanged: %llu callbacks unanswered, %llu done before their commit\n",
			(unsigned long long)(ph.commits - ph.answered), (unsigned long long)ph.early);
	fprintf(stderr, "unchanged: scene shown by volume %llu; %.1f commits/s\n", (unsigned long long)seq,
		(double)ph.commits / seconds);
	spindle_disconnect(sp);
	bench_daemon_stop(&d);
	return ph.early || ph.answered < ph.commits ? 1 : 0;
}
