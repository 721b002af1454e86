/* Daemon-side logging to stderr (journald picks it up under systemd, with the
 * sd-daemon <N> level prefix when SPINDLE_LOG_PREFIX or JOURNAL_STREAM is set). */
#ifndef SPINDLE_LOG_H
#define SPINDLE_LOG_H

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

#endif
