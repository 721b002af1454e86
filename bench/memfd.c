/* A large buffer reaching the daemon (issue #6): a 1M-vertex buffer of
 * float xyz (12 MB) should reach spindled in under 5 ms, as a memfd, with
 * no copy on the socket.
 *
 * Starts spindled on the simulated device (profile small, renderer cpu: the
 * profile does not matter here, nothing is committed) or uses a running
 * one, and times, R times each (default 100) after one warm-up run:
 *
 *   from_fd     spindle_buffer_create_from_fd() of a memfd the benchmark
 *               made, filled and sealed against shrinking (not timed), then
 *               spindle_roundtrip(): the daemon has received the fd, checked
 *               its seals and size and mapped it
 *   create      spindle_buffer_create() of the same bytes in memory (the
 *               library copies them into a sealed memfd), then a roundtrip
 *   draw        spindle_list_points() of all the vertices of a buffer
 *               just created (not timed), then a roundtrip: the daemon
 *               copies the vertices when it takes the draw
 *   roundtrip   spindle_roundtrip() alone, for scale
 *
 * and prints a Markdown table of the median, p99 (nearest rank) and max,
 * with the daemon's CPU time per run (utime + stime of /proc/PID/stat over
 * all the runs, divided: the ticks are 10 ms). That includes what is not
 * timed: destroying the buffer after each run (unmapping it, and freeing
 * its pages when the daemon held the last reference), and for draw,
 * creating it.
 *
 * Usage: memfd-bench [--runs R] [--vertices N] [--header] SPINDLED|SOCKET */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "daemon.h"
#include "spindle/spindle.h"

static const char prog[] = "memfd-bench";

struct options {
	int runs;
	uint32_t vertices;
	bool header;
	const char *target;
};

struct bench {
	struct options opt;
	struct spindle *sp;
	pid_t pid;
	float *xyz; /* the vertices, in memory */
	size_t size;
	int64_t *ns;
};

/* One measured case: what it is, and the cost of each run. */
struct result {
	const char *name, *what;
	int64_t p50, p99, max;
	double daemon_ms; /* daemon CPU per run, ms */
};

static void die(const char *what, int err)
{
	bench_die(prog, what, err);
}

static void spindle_die(struct bench *b, const char *what, int err)
{
	const char *why = spindle_get_error(b->sp);
	fprintf(stderr, "%s: %s: %s\n", prog, what, why ? why : strerror(err));
	exit(1);
}

/* Points uniform-ish in the cylinder: a fixed pattern, no randomness needed. */
static void fill_vertices(float *v, uint32_t n)
{
	for (uint32_t i = 0; i < n; i++) {
		double a = 2.399963 * i, r = 0.95 * sqrt((i + 0.5) / n);
		v[3 * i] = (float)(r * cos(a));
		v[3 * i + 1] = (float)(1.9 * ((i * 0.618034) - floor(i * 0.618034)) - 0.95);
		v[3 * i + 2] = (float)(r * sin(a));
	}
}

/* A memfd holding the vertices, sealed against shrinking. */
static int sealed_memfd(const struct bench *b)
{
	int fd = memfd_create("memfd-bench", MFD_CLOEXEC | MFD_ALLOW_SEALING);
	if (fd < 0)
		die("memfd_create", errno);
	if (ftruncate(fd, (off_t)b->size) < 0)
		die("ftruncate", errno);
	void *map = mmap(NULL, b->size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
	if (map == MAP_FAILED)
		die("mmap", errno);
	memcpy(map, b->xyz, b->size);
	munmap(map, b->size);
	if (fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK) < 0)
		die("F_ADD_SEALS", errno);
	return fd;
}

static void roundtrip(struct bench *b)
{
	int r = spindle_roundtrip(b->sp);
	if (r < 0)
		spindle_die(b, "roundtrip", -r);
}

/* Outside the measured time: the daemon unmaps the buffer, and the kernel
 * frees its pages when that was the last reference, which costs about as
 * much as what is measured. */
static void destroy(struct bench *b, struct spindle_buffer *buf)
{
	spindle_buffer_destroy(buf);
	roundtrip(b);
}

static int64_t time_from_fd(struct bench *b)
{
	int fd = sealed_memfd(b);
	int64_t t0 = bench_mono_ns();
	struct spindle_buffer *buf = spindle_buffer_create_from_fd(b->sp, fd, b->size);
	if (!buf)
		spindle_die(b, "spindle_buffer_create_from_fd", errno);
	roundtrip(b);
	int64_t t = bench_mono_ns() - t0;
	destroy(b, buf);
	close(fd);
	return t;
}

static int64_t time_create(struct bench *b)
{
	int64_t t0 = bench_mono_ns();
	struct spindle_buffer *buf = spindle_buffer_create(b->sp, b->xyz, b->size);
	if (!buf)
		spindle_die(b, "spindle_buffer_create", errno);
	roundtrip(b);
	int64_t t = bench_mono_ns() - t0;
	destroy(b, buf);
	return t;
}

/* The list of the draw case, made once. */
static struct spindle_list *draw_list;

/* A new buffer each run (made before the clock starts), so that the daemon
 * reads through a new mapping, as for any mesh drawn once. */
static int64_t time_draw(struct bench *b)
{
	struct spindle_buffer *buf = spindle_buffer_create(b->sp, b->xyz, b->size);
	if (!buf)
		spindle_die(b, "spindle_buffer_create", errno);
	if (spindle_list_clear(draw_list) < 0)
		spindle_die(b, "clear", EPIPE);
	roundtrip(b); /* the previous draw's copy is freed before the clock starts */
	int64_t t0 = bench_mono_ns();
	if (spindle_list_points(draw_list, buf, 0, b->opt.vertices, 0) < 0)
		spindle_die(b, "points", EPIPE);
	roundtrip(b);
	int64_t t = bench_mono_ns() - t0;
	destroy(b, buf);
	return t;
}

static int64_t time_roundtrip(struct bench *b)
{
	int64_t t0 = bench_mono_ns();
	roundtrip(b);
	return bench_mono_ns() - t0;
}

static int compare_i64(const void *a, const void *b)
{
	int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
	return (x > y) - (x < y);
}

/* Nearest rank, of a sorted array. */
static int64_t percentile(const int64_t *v, int n, double p)
{
	int rank = (int)ceil(p / 100.0 * n);
	return v[rank ? rank - 1 : 0];
}

/* One warm-up run, then the measured ones. */
static void measure(struct bench *b, int64_t (*run)(struct bench *), struct result *out)
{
	run(b);
	double cpu0 = bench_cpu_seconds(prog, b->pid);
	for (int i = 0; i < b->opt.runs; i++)
		b->ns[i] = run(b);
	out->daemon_ms = 1e3 * (bench_cpu_seconds(prog, b->pid) - cpu0) / b->opt.runs;
	qsort(b->ns, (size_t)b->opt.runs, sizeof(*b->ns), compare_i64);
	out->p50 = percentile(b->ns, b->opt.runs, 50);
	out->p99 = percentile(b->ns, b->opt.runs, 99);
	out->max = b->ns[b->opt.runs - 1];
}

static void print_table(const struct bench *b, const struct result *res, int n)
{
	if (b->opt.header) {
		printf("| case | what is timed | runs | median ms | p99 ms | max ms | daemon CPU ms/run |\n");
		printf("|---|---|--:|--:|--:|--:|--:|\n");
	}
	for (int i = 0; i < n; i++)
		printf("| %s | %s | %d | %.2f | %.2f | %.2f | %.2f |\n", res[i].name, res[i].what, b->opt.runs,
		       (double)res[i].p50 / 1e6, (double)res[i].p99 / 1e6, (double)res[i].max / 1e6, res[i].daemon_ms);
	fflush(stdout);
}

static void run_all(struct bench *b)
{
	char what[4][128];
	double mb = (double)b->size / 1e6;
	snprintf(what[0], sizeof(what[0]), "buffer_create_from_fd + roundtrip, %.1f MB memfd", mb);
	snprintf(what[1], sizeof(what[1]), "buffer_create (copy into a memfd) + roundtrip, %.1f MB", mb);
	snprintf(what[2], sizeof(what[2]), "list_points of %u vertices + roundtrip (daemon copies)", b->opt.vertices);
	snprintf(what[3], sizeof(what[3]), "roundtrip alone");
	struct result res[4] = {
		{ .name = "from_fd", .what = what[0] },
		{ .name = "create", .what = what[1] },
		{ .name = "draw", .what = what[2] },
		{ .name = "roundtrip", .what = what[3] },
	};
	measure(b, time_from_fd, &res[0]);
	measure(b, time_create, &res[1]);
	draw_list = spindle_list_create(b->sp);
	if (!draw_list)
		spindle_die(b, "spindle_list_create", errno);
	measure(b, time_draw, &res[2]);
	spindle_list_destroy(draw_list);
	measure(b, time_roundtrip, &res[3]);
	print_table(b, res, 4);
}

static void usage(void)
{
	fprintf(stderr, "usage: memfd-bench [--runs R] [--vertices N] [--header] SPINDLED|SOCKET\n");
	exit(2);
}

static void parse_options(int argc, char **argv, struct options *o)
{
	*o = (struct options){ 100, 1000000, false, NULL };
	for (int i = 1; i < argc; i++) {
		const char *a = argv[i];
		bool more = i + 1 < argc;
		if (!strcmp(a, "--runs") && more)
			o->runs = atoi(argv[++i]);
		else if (!strcmp(a, "--vertices") && more)
			o->vertices = (uint32_t)strtoul(argv[++i], NULL, 10);
		else if (!strcmp(a, "--header"))
			o->header = true;
		else if (a[0] != '-' && !o->target)
			o->target = a;
		else
			usage();
	}
	if (!o->target || o->runs < 1 || o->vertices < 1 || o->vertices > (1u << 26))
		usage();
}

int main(int argc, char **argv)
{
	struct bench b = { 0 };
	parse_options(argc, argv, &b.opt);
	b.size = (size_t)b.opt.vertices * 12;
	b.xyz = malloc(b.size);
	b.ns = calloc((size_t)b.opt.runs, sizeof(*b.ns));
	if (!b.xyz || !b.ns)
		die("malloc", errno);
	fill_vertices(b.xyz, b.opt.vertices);
	struct bench_daemon d = { 0 };
	bench_daemon_start(&d, prog, b.opt.target, "small", "cpu");
	b.sp = bench_daemon_connect(&d);
	if (!b.sp)
		die("connect", errno);
	b.pid = bench_daemon_pid(&d, b.sp);
	run_all(&b);
	spindle_disconnect(b.sp);
	bench_daemon_stop(&d);
	free(b.ns);
	free(b.xyz);
	return 0;
}
