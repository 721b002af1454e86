/* spindle-gl: settings from the environment (read once, at the first GL
 * call), warnings (each once, on stderr) and the trace file. */
#ifndef SPINDLE_GL_CONFIG_H
#define SPINDLE_GL_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

enum sgl_map {
	SGL_MAP_FIT,     /* eye space, the geometry's bounds fitted into the cylinder */
	SGL_MAP_FRUSTUM, /* the clip volume onto the cylinder */
	SGL_MAP_FIXED,   /* eye space, scaled and offset */
};

struct sgl_config {
	enum sgl_map map;
	float scale, offset[3]; /* fixed: volume = scale * eye + offset */
	uint32_t retry_ms;      /* between connection attempts */
	uint32_t max_layers;    /* list calls shown by reference per frame */
	bool trace;
};

const struct sgl_config *sgl_config(void);

/* Prints "spindle-gl: <message>" on stderr the first time key (a string
 * constant) is given, and traces it; key NULL: every time. */
void sgl_warn_once(const char *key, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A message that is not a warning (on stderr unless SPINDLE_GL_QUIET). */
void sgl_note(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* One line to the trace file ($SPINDLE_GL_TRACE), if any. */
void sgl_trace(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
uint64_t sgl_now_ns(void);

#endif
