#include "gltest.h"

#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static char trace_path[64], stderr_path[64];
static pid_t main_pid;

void gltest_setup(const char *map, const char *socket)
{
	snprintf(trace_path, sizeof(trace_path), "/tmp/spindle-gl-trace-XXXXXX");
	int fd = mkstemp(trace_path);
	CHECK(fd >= 0);
	close(fd);
	setenv("SPINDLE_GL_TRACE", trace_path, 1);
	if (map)
		setenv("SPINDLE_GL_MAP", map, 1);
	else
		unsetenv("SPINDLE_GL_MAP");
	setenv("SPINDLE_SOCKET", socket ? socket : "/nonexistent/spindle-gl-test.sock", 1);
	setenv("SPINDLE_GL_RETRY_MS", "50", 1);
	setenv("SPINDLE_GL_QUIET", "1", 1);
	unsetenv("LD_PRELOAD");
}

static void cleanup(void)
{
	if (getpid() != main_pid)
		return; /* a child the case forked */
	if (*trace_path)
		unlink(trace_path);
	if (*stderr_path)
		unlink(stderr_path);
}

void gltest_capture_stderr(void)
{
	snprintf(stderr_path, sizeof(stderr_path), "/tmp/spindle-gl-stderr-XXXXXX");
	int fd = mkstemp(stderr_path);
	CHECK(fd >= 0);
	CHECK(dup2(fd, 2) == 2);
	close(fd);
}

static char *slurp(const char *path)
{
	FILE *f = fopen(path, "r");
	CHECK(f != NULL);
	size_t cap = 1 << 16, n = 0;
	char *buf = malloc(cap);
	CHECK(buf != NULL);
	size_t r;
	while ((r = fread(buf + n, 1, cap - n - 1, f)) > 0) {
		n += r;
		if (cap - n - 1 == 0) {
			cap *= 2;
			buf = realloc(buf, cap);
			CHECK(buf != NULL);
		}
	}
	fclose(f);
	buf[n] = '\0';
	return buf;
}

char *gltest_trace(void)
{
	return slurp(trace_path);
}

static int count_lines(char *text, const char *needle, bool prefix)
{
	int n = 0;
	for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n"))
		n += prefix ? !strncmp(line, needle, strlen(needle)) : strstr(line, needle) != NULL;
	return n;
}

int gltest_stderr_count(const char *text)
{
	fflush(stderr);
	char *s = slurp(stderr_path);
	int n = count_lines(s, text, false);
	free(s);
	return n;
}

int gltest_trace_count(const char *prefix)
{
	char *s = gltest_trace();
	int n = count_lines(s, prefix, true);
	free(s);
	return n;
}

static void parse_frame(struct tframe *f, const char *line)
{
	float *m = f->map;
	int n = sscanf(line,
		       "frame ctx %u by %15s calls %u points %u lines %u triangles %u map %f %f %f %f %f %f %f %f "
		       "%f %f %f %f %15s",
		       &f->ctx, f->by, &f->calls, &f->n[0], &f->n[1], &f->n[2], &m[0], &m[4], &m[8], &m[12], &m[1],
		       &m[5], &m[9], &m[13], &m[2], &m[6], &m[10], &m[14], f->status);
	CHECK_MSG(n == 19, "bad frame line %s", line);
	m[3] = m[7] = m[11] = 0;
	m[15] = 1;
}

static void parse_call(struct tframe *f, const char *line)
{
	CHECK(f->n_c < TRACE_MAX);
	struct tcall *c = &f->c[f->n_c++];
	float *s = c->s;
	int n = sscanf(line, "call list %u segment %u colour %x s %f %f %f %f %f %f %f %f %f %f %f %f %f %f %f %f",
		       &c->list, &c->segment, &c->rgba, &s[0], &s[4], &s[8], &s[12], &s[1], &s[5], &s[9], &s[13], &s[2],
		       &s[6], &s[10], &s[14], &s[3], &s[7], &s[11], &s[15]);
	CHECK_MSG(n == 19, "bad call line %s", line);
}

static void parse_vertex(struct tframe *f, const char *line)
{
	CHECK(f->n_v < TRACE_MAX);
	struct tvertex *v = &f->v[f->n_v++];
	CHECK(sscanf(line, "v %d %f %f %f %x", &v->kind, &v->p[0], &v->p[1], &v->p[2], &v->rgba) == 5);
}

int gltest_frames(struct tframe **out)
{
	char *text = gltest_trace();
	int n = 0, cap = 16;
	struct tframe *frames = calloc((size_t)cap, sizeof(*frames)), cur = { 0 };
	CHECK(frames != NULL);
	for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
		if (!strncmp(line, "call ", 5)) {
			parse_call(&cur, line);
		} else if (!strncmp(line, "v ", 2)) {
			parse_vertex(&cur, line);
		} else if (!strncmp(line, "frame ", 6)) {
			parse_frame(&cur, line);
			if (n == cap) {
				cap *= 2;
				frames = realloc(frames, (size_t)cap * sizeof(*frames));
				CHECK(frames != NULL);
			}
			frames[n++] = cur;
			memset(&cur, 0, sizeof(cur));
		}
	}
	free(text);
	*out = frames;
	return n;
}

struct tframe gltest_last_frame(void)
{
	struct tframe *frames;
	int n = gltest_frames(&frames);
	CHECK(n > 0);
	struct tframe f = frames[n - 1];
	free(frames);
	return f;
}

struct tframe gltest_swap(void)
{
	glXSwapBuffers(NULL, 1);
	return gltest_last_frame();
}

bool gltest_near(float a, float b)
{
	return fabsf(a - b) <= 1e-4f * fmaxf(1, fabsf(b));
}

void gltest_sleep_ms(int ms)
{
	struct timespec ts = { ms / 1000, (ms % 1000) * 1000000L };
	nanosleep(&ts, NULL);
}

static const struct {
	const char *name;
	void (*fn)(void);
} cases[] = {
	{ "immediate", case_immediate },     { "colours", case_colours }, { "lists", case_lists },
	{ "matrices", case_matrices },       { "arrays", case_arrays },   { "buffers", case_buffers },
	{ "mapping", case_mapping },         { "frustum", case_frustum }, { "fixed", case_fixed },
	{ "frames", case_frames },           { "expand", case_expand },   { "offline", case_offline },
	{ "contexts", case_contexts },       { "threads", case_threads }, { "uncovered", case_uncovered },
	{ "procaddress", case_procaddress }, { "noswap", case_noswap },
};

int main(int argc, char **argv)
{
	if (argc != 2) {
		fprintf(stderr, "usage: %s CASE\n", argv[0]);
		return 2;
	}
	main_pid = getpid();
	atexit(cleanup);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		if (!strcmp(argv[1], cases[i].name)) {
			cases[i].fn();
			return check_done();
		}
	}
	fprintf(stderr, "no case %s\n", argv[1]);
	return 2;
}
