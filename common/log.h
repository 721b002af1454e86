/* Daemon-side logging to stderr (journald picks it up under systemd, with the
 * sd-daemon <N> level prefix when SPINDLE_LOG_PREFIX or JOURNAL_STREAM is set). */
#ifndef SPINDLE_LOG_H
#define SPINDLE_LOG_H

#include <stdbool.h>
#include <stdint.h>

enum log_level { LOG_LEVEL_ERROR = 3, LOG_LEVEL_WARN = 4, LOG_LEVEL_INFO = 6, LOG_LEVEL_DEBUG = 7 };

void log_set_level(enum log_level level);
void log_msg(enum log_level level, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#define log_error(...) log_msg(LOG_LEVEL_ERROR, __VA_ARGS__)
#define log_warn(...) log_msg(LOG_LEVEL_WARN, __VA_ARGS__)
#define log_info(...) log_msg(LOG_LEVEL_INFO, __VA_ARGS__)
#define log_debug(...) log_msg(LOG_LEVEL_DEBUG, __VA_ARGS__)

/* CLOCK_MONOTONIC in nanoseconds. */
int64_t now_ns(void);

/* A message that may come in floods (refused clients, accept() out of
 * fds) is logged at most once an interval; the rest are counted. */
struct log_ratelimit {
	int64_t interval_ns;
	int64_t last_ns;     /* 0: never logged */
	uint64_t suppressed; /* since the last one logged */
};

/* Whether to log now. When it says yes, r->suppressed tells how many were
 * not logged before this one; the caller reads it, then it starts again. */
static inline bool log_ratelimit_ok(struct log_ratelimit *r)
{
	int64_t now = now_ns();
	if (r->last_ns && now - r->last_ns < r->interval_ns) {
		r->suppressed++;
		return false;
	}
	r->last_ns = now;
	return true;
}

#endif
