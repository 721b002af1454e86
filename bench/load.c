/* Load at daemon level: many clients committing fast (issue #6).
 *
 * Starts spindled on the simulated device (profile small by default, renderer
 * cpu) on a private socket, or uses a running one, and connects 64 clients.
 * Each owns a layer with a small list (a square outline: 4 line segments)
 * that it moves on every commit, and commits at twice the revolution rate
 * (the rpm of the device info) for S seconds, each commit with a frame
 * callback. The commits of the clients are spread evenly over the half
 * revolution. Then it waits a grace period for the frames still due.
 *
 * One thread drives all the clients: a ppoll() over their sockets, with
 * spindle_dispatch() and spindle_flush(), and each client's commit when it
 * is due. What this costs (its CPU time, and how late commits went out
 * against their schedule) is printed on stderr, so that the clients are
 * seen not to be the bottleneck.
 *
 * Prints one Markdown table row (--header: with the header): commits,
 * frames, lost (no frame by the end of the grace period), duplicated (a
 * frame delivered twice), reordered (a client's frames arriving out of
 * commit order, its volume sequence or time going back, or a time before
 * the commit was sent), commit-to-shown latency (frame time - send time)
 * p50/p99/max in ms and in revolution periods, the daemon's CPU over the
 * commit phase (utime + stime of /proc/PID/stat, % of one core) and its
 * VmRSS and VmHWM at the end. Exits 1 when a frame was lost, duplicated or
 * reordered. Two commits shown by the same volume both name it: that is
 * the protocol (display.frame), not a duplicate.
 *
 * Usage: load [--seconds S] [--clients N] [--profile P] [--renderer R]
 *             [--grace S] [--header] SPINDLED|SOCKET */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "daemon.h"
#include "spindle/spindle.h"

#define MAX_CLIENTS 64 /* the daemon's default max-clients */
#define SQUARE_VERTICES 8

static const char prog[] = "load";

struct options {
	double seconds, grace;
	int clients;
	const char *profile, *renderer, *target;
	bool header;
};

struct load_client;

/* One commit: when it was sent and what its frame said. */
struct record {
	struct load_client *client;
	uint32_t index;
	uint32_t deliveries;
	int64_t sent_ns;
	struct spindle_frame frame;
};

/* What went wrong, over all clients. */
struct faults {
	uint64_t duplicated, out_of_order, seq_back, time_back, early, refused;
};

struct load_client {
	struct spindle *sp;
	struct spindle_buffer *buf;
	struct spindle_list *list;
	struct spindle_layer *layer;
	int id;
	bool want_write; /* a flush left requests queued */
	struct record *recs;
	uint32_t commits, cap, frames;
	int64_t next_ns;    /* the next commit is due then */
	int64_t last_index; /* of the last frame that arrived, -1 for none */
	struct spindle_frame last;
	struct faults *faults;
};

struct load {
	struct options opt;
	struct bench_daemon daemon;
	pid_t pid;
	struct load_client clients[MAX_CLIENTS];
	struct pollfd fds[MAX_CLIENTS];
	struct faults faults;
	int64_t period_ns, interval_ns;
	int64_t *lag_ns; /* send time - due time, each commit */
	uint64_t lags;
	double daemon_cpu, client_cpu; /* % of one core over the commit phase */
	struct spindle_status before, after;
	struct bench_memory mem;
};

static void die(const char *what, int err)
{
	bench_die(prog, what, err);
}

static void client_die(struct load_client *c, const char *what, int err)
{
	const char *why = spindle_get_error(c->sp);
	fprintf(stderr, "%s: client %d: %s: %s\n", prog, c->id, what, why ? why : strerror(err));
	exit(1);
}

/* ---- one client ---- */

/* A refused commit keeps its frame request for the next one: that shows as
 * a frame lost, and is said here. */
static void on_refused(void *data, enum spindle_refusal code, uint32_t object, const char *message)
{
	struct load_client *c = data;
	c->faults->refused++;
	fprintf(stderr, "%s: client %d: commit refused (%d, object %u): %s\n", prog, c->id, (int)code, object, message);
}

static const struct spindle_listener listener = { .refused = on_refused };

static void on_frame(void *data, const struct spindle_frame *frame)
{
	struct record *r = data;
	struct load_client *c = r->client;
	if (r->deliveries++) {
		c->faults->duplicated++;
		return;
	}
	r->frame = *frame;
	c->frames++;
	c->faults->out_of_order += (int64_t)r->index < c->last_index;
	c->faults->seq_back += frame->volume_seq < c->last.volume_seq;
	c->faults->time_back += frame->time_ns < c->last.time_ns;
	c->faults->early += (int64_t)frame->time_ns < r->sent_ns;
	c->last_index = r->index;
	c->last = *frame;
}

/* The outline of a square of side 0.1 in the x-y plane. */
static void square(float v[SQUARE_VERTICES * 3])
{
	static const float corner[4][2] = { { -1, -1 }, { 1, -1 }, { 1, 1 }, { -1, 1 } };
	for (int i = 0; i < 4; i++)
		for (int end = 0; end < 2; end++) {
			const float *p = corner[(i + end) % 4];
			float *out = v + 3 * (2 * i + end);
			out[0] = 0.05f * p[0];
			out[1] = 0.05f * p[1];
			out[2] = 0;
		}
}

/* Client c's square for commit k: on a ring of radius 0.6 at the client's
 * own angle, at a height that changes on every commit. */
static void record_list(struct load_client *c, uint32_t k)
{
	double a = 2 * M_PI * c->id / MAX_CLIENTS, y = 0.6 * sin(0.05 * k + c->id);
	float m[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0 };
	m[12] = (float)(0.6 * cos(a));
	m[13] = (float)y;
	m[14] = (float)(0.6 * sin(a));
	m[15] = 1;
	if (spindle_list_clear(c->list) < 0 || spindle_list_set_color(c->list, 255, 160, 0, 255) < 0 ||
	    spindle_list_set_transform(c->list, m) < 0 ||
	    spindle_list_lines(c->list, c->buf, 0, SQUARE_VERTICES, 0) < 0)
		client_die(c, "recording the list", EPIPE);
}

static void client_init(struct load *ld, struct load_client *c, int id)
{
	float v[SQUARE_VERTICES * 3];
	c->id = id;
	c->faults = &ld->faults;
	c->last_index = -1;
	c->sp = bench_daemon_connect(&ld->daemon);
	if (!c->sp)
		die("connect", errno);
	spindle_set_listener(c->sp, &listener, c);
	square(v);
	c->buf = spindle_buffer_create(c->sp, v, sizeof(v));
	c->list = spindle_list_create(c->sp);
	c->layer = spindle_layer_create(c->sp);
	if (!c->buf || !c->list || !c->layer)
		client_die(c, "creating the objects", errno);
	if (spindle_layer_set_list(c->layer, c->list) < 0)
		client_die(c, "set_list", EPIPE);
	record_list(c, 0);
}

/* Commit k+1: the square moves, and a frame is asked for. */
static void client_commit(struct load *ld, struct load_client *c, int64_t now)
{
	if (c->commits == c->cap)
		return;
	struct record *r = &c->recs[c->commits];
	r->client = c;
	r->index = c->commits++;
	record_list(c, r->index + 1);
	ld->lag_ns[ld->lags++] = now - c->next_ns;
	r->sent_ns = bench_mono_ns();
	if (spindle_request_frame(c->sp, on_frame, r) < 0 || spindle_commit(c->sp) < 0)
		client_die(c, "commit", EPIPE);
	/* spindle_commit() flushes; what a full socket left is flushed on POLLOUT. */
	c->want_write = spindle_flush(c->sp) == -EAGAIN;
	c->next_ns += ld->interval_ns;
}

/* ---- all of them ---- */

/* Timing from the device info. */
static void set_timing(struct load *ld, const struct spindle_device_info *info)
{
	if (!(info->rpm > 0))
		die("the device reports no rpm", EINVAL);
	ld->period_ns = (int64_t)(60e9 / info->rpm);
	ld->interval_ns = ld->period_ns / 2;
}

/* Room for every commit of the commit phase, and their lags. */
static void alloc_records(struct load *ld)
{
	uint32_t cap = (uint32_t)(ld->opt.seconds * 1e9 / (double)ld->interval_ns) + 16;
	for (int i = 0; i < ld->opt.clients; i++) {
		ld->clients[i].cap = cap;
		ld->clients[i].recs = calloc(cap, sizeof(struct record));
		if (!ld->clients[i].recs)
			die("calloc", errno);
	}
	ld->lag_ns = calloc((size_t)ld->opt.clients * cap, sizeof(*ld->lag_ns));
	if (!ld->lag_ns)
		die("calloc", errno);
}

static void connect_all(struct load *ld)
{
	for (int i = 0; i < ld->opt.clients; i++) {
		client_init(ld, &ld->clients[i], i);
		if (i == 0) {
			set_timing(ld, spindle_get_device_info(ld->clients[0].sp));
			ld->pid = bench_daemon_pid(&ld->daemon, ld->clients[0].sp);
		}
		if (i + 1 < ld->opt.clients && spindle_commit(ld->clients[i].sp) < 0)
			client_die(&ld->clients[i], "commit", EPIPE);
	}
	/* The last commit's frame shows everyone's first state. */
	int r = spindle_commit_and_wait(ld->clients[ld->opt.clients - 1].sp, NULL);
	if (r < 0)
		client_die(&ld->clients[ld->opt.clients - 1], "first commit", -r);
}

static void handle_events(struct load *ld, int n)
{
	for (int i = 0; i < n; i++) {
		struct load_client *c = &ld->clients[i];
		short ev = ld->fds[i].revents;
		if (ev & POLLOUT) {
			int r = spindle_flush(c->sp);
			if (r < 0 && r != -EAGAIN)
				client_die(c, "flush", -r);
			c->want_write = r == -EAGAIN;
		}
		if (ev & (POLLIN | POLLHUP | POLLERR)) {
			int r = spindle_dispatch(c->sp);
			if (r < 0)
				client_die(c, "dispatch", -r);
		}
	}
}

/* Waits for events until deadline (at most), and handles them. */
static void poll_until(struct load *ld, int64_t deadline)
{
	int n = ld->opt.clients;
	for (int i = 0; i < n; i++) {
		ld->fds[i].fd = spindle_get_fd(ld->clients[i].sp);
		ld->fds[i].events = POLLIN | (ld->clients[i].want_write ? POLLOUT : 0);
	}
	int64_t wait = deadline - bench_mono_ns();
	if (wait < 0)
		wait = 0;
	struct timespec ts = { wait / 1000000000, wait % 1000000000 };
	if (ppoll(ld->fds, (nfds_t)n, &ts, NULL) < 0) {
		if (errno == EINTR)
			return;
		die("ppoll", errno);
	}
	handle_events(ld, n);
}

/* Every client's commits until end; returns the next time one is due. */
static int64_t commit_due(struct load *ld, int64_t end)
{
	int64_t now = bench_mono_ns(), next = end;
	for (int i = 0; i < ld->opt.clients; i++) {
		struct load_client *c = &ld->clients[i];
		if (c->next_ns <= now && c->next_ns < end)
			client_commit(ld, c, now);
		if (c->next_ns < next)
			next = c->next_ns;
	}
	return next;
}

static double process_cpu_seconds(void)
{
	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) / 1e6;
}

static void run_commits(struct load *ld)
{
	int64_t start = bench_mono_ns(), end = start + (int64_t)(ld->opt.seconds * 1e9);
	for (int i = 0; i < ld->opt.clients; i++)
		ld->clients[i].next_ns = start + ld->interval_ns * i / ld->opt.clients;
	double cpu0 = bench_cpu_seconds(prog, ld->pid), own0 = process_cpu_seconds();
	int64_t next = start;
	while (next < end) {
		poll_until(ld, next);
		next = commit_due(ld, end);
	}
	double wall = (double)(bench_mono_ns() - start) / 1e9;
	ld->daemon_cpu = 100.0 * (bench_cpu_seconds(prog, ld->pid) - cpu0) / wall;
	ld->client_cpu = 100.0 * (process_cpu_seconds() - own0) / wall;
}

static uint64_t frames_missing(const struct load *ld)
{
	uint64_t n = 0;
	for (int i = 0; i < ld->opt.clients; i++)
		n += ld->clients[i].commits - ld->clients[i].frames;
	return n;
}

/* Waits for the frames still due, up to the grace period. */
static void run_grace(struct load *ld)
{
	int64_t end = bench_mono_ns() + (int64_t)(ld->opt.grace * 1e9);
	while (frames_missing(ld) && bench_mono_ns() < end)
		poll_until(ld, end);
}

static void disconnect_all(struct load *ld)
{
	for (int i = 0; i < ld->opt.clients; i++) {
		spindle_disconnect(ld->clients[i].sp);
		free(ld->clients[i].recs);
	}
}

/* ---- the results ---- */

static int compare_i64(const void *a, const void *b)
{
	int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
	return (x > y) - (x < y);
}

/* Nearest rank, of a sorted array. */
static int64_t percentile(const int64_t *v, uint64_t n, double p)
{
	if (!n)
		return 0;
	uint64_t rank = (uint64_t)ceil(p / 100.0 * (double)n);
	return v[rank ? rank - 1 : 0];
}

struct latency {
	uint64_t n;
	int64_t p50, p99, max;
};

/* Sorts v in place. */
static void summarise(int64_t *v, uint64_t n, struct latency *out)
{
	qsort(v, n, sizeof(*v), compare_i64);
	*out = (struct latency){ n, percentile(v, n, 50), percentile(v, n, 99), n ? v[n - 1] : 0 };
}

/* Commit-to-shown latencies of every frame that arrived. */
static void frame_latency(const struct load *ld, struct latency *out)
{
	uint64_t total = 0, n = 0;
	for (int i = 0; i < ld->opt.clients; i++)
		total += ld->clients[i].commits;
	int64_t *v = malloc((total ? total : 1) * sizeof(*v));
	if (!v)
		die("malloc", errno);
	for (int i = 0; i < ld->opt.clients; i++) {
		const struct load_client *c = &ld->clients[i];
		for (uint32_t k = 0; k < c->commits; k++)
			if (c->recs[k].deliveries)
				v[n++] = (int64_t)c->recs[k].frame.time_ns - c->recs[k].sent_ns;
	}
	summarise(v, n, out);
	free(v);
}

static uint64_t reordered(const struct faults *f)
{
	return f->out_of_order + f->seq_back + f->time_back + f->early;
}

static void print_header(void)
{
	printf("| profile | renderer | clients | s | commits | frames | lost | dup | reordered | "
	       "latency p50 / p99 / max ms | in revolutions | daemon CPU %% | VmRSS / VmHWM MiB | "
	       "volumes rendered | underruns |\n");
	printf("|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n");
}

static void print_row(const struct load *ld, const struct latency *lat)
{
	uint64_t commits = 0, frames = 0;
	for (int i = 0; i < ld->opt.clients; i++) {
		commits += ld->clients[i].commits;
		frames += ld->clients[i].frames;
	}
	double ms = 1e6, rev = (double)ld->period_ns;
	printf("| %s | %s | %d | %.0f | %llu | %llu | %llu | %llu | %llu | %.1f / %.1f / %.1f | %.2f / %.2f / %.2f | "
	       "%.1f | %.1f / %.1f | %llu | %llu |\n",
	       ld->opt.profile, ld->opt.renderer, ld->opt.clients, ld->opt.seconds, (unsigned long long)commits,
	       (unsigned long long)frames, (unsigned long long)(commits - frames),
	       (unsigned long long)ld->faults.duplicated, (unsigned long long)reordered(&ld->faults),
	       (double)lat->p50 / ms, (double)lat->p99 / ms, (double)lat->max / ms, (double)lat->p50 / rev,
	       (double)lat->p99 / rev, (double)lat->max / rev, ld->daemon_cpu, ld->mem.rss_kib / 1024.0,
	       ld->mem.hwm_kib / 1024.0, (unsigned long long)(ld->after.volumes_rendered - ld->before.volumes_rendered),
	       (unsigned long long)(ld->after.underruns - ld->before.underruns));
	fflush(stdout);
}

/* The details, on stderr: the faults by kind, and what the clients cost. */
static void print_details(struct load *ld, const struct latency *lat)
{
	const struct faults *f = &ld->faults;
	struct latency lag;
	summarise(ld->lag_ns, ld->lags, &lag);
	fprintf(stderr,
		"%s: revolution %.2f ms, a commit every %.2f ms per client; %llu frames measured\n"
		"%s: reordered: %llu out of commit order, %llu volume_seq back, %llu time_ns back, "
		"%llu time_ns before the commit; %llu commits refused\n"
		"%s: volumes shown %llu, skipped %llu during the commit phase\n"
		"%s: the clients (this process, one thread): %.1f%% of one core; commits sent late by "
		"p50 %.3f, p99 %.3f, max %.3f ms\n",
		prog, (double)ld->period_ns / 1e6, (double)ld->interval_ns / 1e6, (unsigned long long)lat->n, prog,
		(unsigned long long)f->out_of_order, (unsigned long long)f->seq_back, (unsigned long long)f->time_back,
		(unsigned long long)f->early, (unsigned long long)f->refused, prog,
		(unsigned long long)(ld->after.volumes_shown - ld->before.volumes_shown),
		(unsigned long long)(ld->after.volumes_skipped - ld->before.volumes_skipped), prog, ld->client_cpu,
		(double)lag.p50 / 1e6, (double)lag.p99 / 1e6, (double)lag.max / 1e6);
	double p99_rev = (double)lat->p99 / (double)ld->period_ns;
	fprintf(stderr, "%s: target 0 lost, p99 <= 2 revolutions: %s (lost %llu, p99 %.2f)\n", prog,
		frames_missing(ld) == 0 && p99_rev <= 2 ? "met" : "NOT met", (unsigned long long)frames_missing(ld),
		p99_rev);
}

/* ---- options and main ---- */

static void usage(void)
{
	fprintf(stderr, "usage: load [--seconds S] [--clients N] [--profile P] [--renderer R] [--grace S] "
			"[--header] SPINDLED|SOCKET\n");
	exit(2);
}

static void parse_options(int argc, char **argv, struct options *o)
{
	*o = (struct options){ 60, 2, MAX_CLIENTS, "small", "cpu", NULL, false };
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		bool more = i + 1 < argc;
		if (!strcmp(a, "--seconds") && more)
			o->seconds = atof(argv[++i]);
		else if (!strcmp(a, "--grace") && more)
			o->grace = atof(argv[++i]);
		else if (!strcmp(a, "--clients") && more)
			o->clients = atoi(argv[++i]);
		else if (!strcmp(a, "--profile") && more)
			o->profile = argv[++i];
		else if (!strcmp(a, "--renderer") && more)
			o->renderer = argv[++i];
		else if (!strcmp(a, "--header"))
			o->header = true;
		else if (a[0] != '-' && !o->target)
			o->target = a;
		else
			usage();
	}
	if (!o->target || !(o->seconds > 0) || !(o->grace >= 0) || o->clients < 1 || o->clients > MAX_CLIENTS)
		usage();
}

static void get_status(struct load *ld, struct spindle_status *st)
{
	int r = spindle_get_status(ld->clients[0].sp, st);
	if (r < 0)
		client_die(&ld->clients[0], "status", -r);
}

int main(int argc, char **argv)
{
	static struct load ld;
	parse_options(argc, argv, &ld.opt);
	signal(SIGPIPE, SIG_IGN);
	bench_daemon_start(&ld.daemon, prog, ld.opt.target, ld.opt.profile, ld.opt.renderer);
	connect_all(&ld);
	alloc_records(&ld);
	get_status(&ld, &ld.before);
	run_commits(&ld);
	get_status(&ld, &ld.after);
	run_grace(&ld);
	bench_memory(prog, ld.pid, &ld.mem);
	struct latency lat;
	frame_latency(&ld, &lat);
	if (ld.opt.header)
		print_header();
	print_row(&ld, &lat);
	print_details(&ld, &lat);
	bool bad = frames_missing(&ld) || ld.faults.duplicated || reordered(&ld.faults);
	disconnect_all(&ld);
	free(ld.lag_ns);
	bench_daemon_stop(&ld.daemon);
	return bad ? 1 : 0;
}
