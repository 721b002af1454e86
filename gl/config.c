#include "config.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static struct sgl_config config;
static pthread_once_t once = PTHREAD_ONCE_INIT;
static pthread_mutex_t log_lock = PTHREAD_MUTEX_INITIALIZER;
static FILE *trace_file;
static bool quiet;

static float env_float(const char *name, float def)
{
	const char *s = getenv(name);
	char *end;
	if (!s || !*s)
		return def;
	float v = strtof(s, &end);
	if (*end || !isfinite(v)) {
		fprintf(stderr, "spindle-gl: %s=%s is not a number: using %g\n", name, s, def);
		return def;
	}
	return v;
}

/* A count from the environment, clamped to lo..hi. */
static uint32_t env_count(const char *name, float def, float lo, float hi)
{
	float v = env_float(name, def);
	return (uint32_t)(v >= lo ? (v <= hi ? v : hi) : lo);
}

static void read_map(void)
{
	const char *m = getenv("SPINDLE_GL_MAP");
	config.map = SGL_MAP_FIT;
	if (!m || !*m || !strcmp(m, "fit"))
		return;
	if (!strcmp(m, "frustum"))
		config.map = SGL_MAP_FRUSTUM;
	else if (!strcmp(m, "fixed"))
		config.map = SGL_MAP_FIXED;
	else
		fprintf(stderr, "spindle-gl: SPINDLE_GL_MAP=%s: not fit, frustum or fixed: using fit\n", m);
	const char *o = getenv("SPINDLE_GL_OFFSET");
	if (o && *o && sscanf(o, "%f,%f,%f", &config.offset[0], &config.offset[1], &config.offset[2]) != 3) {
		fprintf(stderr, "spindle-gl: SPINDLE_GL_OFFSET=%s is not X,Y,Z: using 0,0,0\n", o);
		memset(config.offset, 0, sizeof(config.offset));
	}
	config.scale = env_float("SPINDLE_GL_SCALE", 1);
}

static void init(void)
{
	read_map();
	config.retry_ms = env_count("SPINDLE_GL_RETRY_MS", 1000, 10, 3600000);
	config.max_layers = env_count("SPINDLE_GL_MAX_LAYERS", 256, 0, 512);
	const char *q = getenv("SPINDLE_GL_QUIET");
	quiet = q && *q && strcmp(q, "0") != 0;
	const char *t = getenv("SPINDLE_GL_TRACE");
	if (t && *t) {
		trace_file = fopen(t, "we");
		if (trace_file)
			setvbuf(trace_file, NULL, _IOLBF, 0);
		else
			fprintf(stderr, "spindle-gl: cannot write the trace %s: %s\n", t, strerror(errno));
	}
	config.trace = trace_file != NULL;
}

const struct sgl_config *sgl_config(void)
{
	pthread_once(&once, init);
	return &config;
}

static void vtrace(const char *prefix, const char *fmt, va_list ap)
{
	if (!sgl_config()->trace)
		return;
	pthread_mutex_lock(&log_lock);
	fputs(prefix, trace_file);
	vfprintf(trace_file, fmt, ap);
	fputc('\n', trace_file);
	pthread_mutex_unlock(&log_lock);
}

void sgl_trace(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	vtrace("", fmt, ap);
	va_end(ap);
}

#define MAX_KEYS 64

void sgl_warn_once(const char *key, const char *fmt, ...)
{
	static const char *said[MAX_KEYS];
	static int n_said;
	bool first = true;
	pthread_mutex_lock(&log_lock);
	for (int i = 0; key && i < n_said && first; i++)
		first = strcmp(said[i], key) != 0;
	if (key && first && n_said < MAX_KEYS)
		said[n_said++] = key;
	pthread_mutex_unlock(&log_lock);
	if (!first)
		return;
	va_list ap;
	char text[512];
	va_start(ap, fmt);
	vsnprintf(text, sizeof(text), fmt, ap);
	va_end(ap);
	fprintf(stderr, "spindle-gl: %s\n", text);
	sgl_trace("warn %s: %s", key ? key : "-", text);
}

void sgl_note(const char *fmt, ...)
{
	va_list ap;
	char text[512];
	va_start(ap, fmt);
	vsnprintf(text, sizeof(text), fmt, ap);
	va_end(ap);
	if (!quiet)
		fprintf(stderr, "spindle-gl: %s\n", text);
	sgl_trace("note %s", text);
}

uint64_t sgl_now_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}
