/* spindlectl's commands, one function each (spindlectl.c, ctl_status.c,
 * ctl_scan.c): the parsed command line, the exit statuses and the helpers
 * they share. */
#ifndef SPINDLE_CTL_H
#define SPINDLE_CTL_H

#include <stdbool.h>
#include <stdint.h>

#include <spindle/spindle.h>

#include "scan.h"

/* The fit of show: the model or scan fills 95 % of the display. */
#define CTL_FIT_MARGIN 0.95f

/* Exit statuses (spindlectl(1), EXIT STATUS). */
enum {
	CTL_OK = 0,
	CTL_FAILED = 1,  /* a request failed, the connection broke, an output file could not be written */
	CTL_USAGE = 2,   /* bad command line */
	CTL_CONNECT = 3, /* no daemon at the socket, or no common protocol version */
	CTL_REFUSED = 4, /* the daemon refused: capture not allowed, a commit over quota or policy */
	CTL_INPUT = 5,   /* an input file that cannot be read or used: a model, a scan, an .svol */
};

/* show of a scan (ctl_scan.c): the options, as given. */
struct ctl_scan_args {
	bool has_window;
	double window_center, window_width;
	const char *preset; /* NULL: chosen from the data */
	bool has_threshold;
	double threshold;
	bool has_sampling, nearest;
	bool has_dims, has_type, has_spacing, has_offset; /* a raw file's layout */
	struct scan_raw raw;
};

struct ctl_args {
	const char *socket; /* NULL: libspindle's default */
	const char *command;
	const char *operand[2];
	int operand_count;
	bool no_fit;
	bool has_color;
	uint8_t color[3];
	bool has_size;
	uint32_t size;
	bool json;
	bool save;          /* calibrate: write the value into the config file */
	const char *config; /* its path; NULL: /etc/spindle/spindled.conf */
	struct ctl_scan_args scan;
};

/* show's scan options (getopt_long values; spindlectl.c names them). */
enum {
	CTL_OPT_WINDOW = 512,
	CTL_OPT_PRESET,
	CTL_OPT_THRESHOLD,
	CTL_OPT_SAMPLING,
	CTL_OPT_DIMS,
	CTL_OPT_TYPE,
	CTL_OPT_SPACING,
	CTL_OPT_OFFSET,
	CTL_OPT_BIG_ENDIAN,
	CTL_OPT_SCAN_LAST = CTL_OPT_BIG_ENDIAN,
};

/* A usage error (fmt with arg) on stderr; returns CTL_USAGE. */
int ctl_usage_error(const char *fmt, const char *arg);
/* The socket path libspindle will use, for messages. */
const char *ctl_socket_path(const struct ctl_args *a);
/* A connection to the daemon, or NULL after saying why. */
struct spindle *ctl_connect(const struct ctl_args *a);
/* "spindlectl: WHAT: why" from the connection's error or ret. */
void ctl_report_failure(struct spindle *sp, const char *what, int ret);

/* Commits what the connection has drawn and waits until it is shown; then
 * prints "shown SEQ" and holds it there until SIGINT or SIGTERM. what
 * ("model", "scan") for the message of a refused commit. The exit status. */
int ctl_commit_and_hold(struct spindle *sp, const char *what);

/* ctl_scan.c: show of a scan. One of its options (CTL_OPT_*) with its
 * argument (NULL for --big-endian) into a: -1, or CTL_USAGE after saying
 * why. */
int ctl_scan_option(int opt, const char *arg, struct ctl_args *a);
/* Whether any of the scan options was given. */
bool ctl_scan_options_given(const struct ctl_args *a);
/* Whether show's FILE is a scan: a .nii or .nii.gz file, a directory (a
 * DICOM series), or a raw file (--dims given). */
bool ctl_is_scan(const struct ctl_args *a);
int cmd_show_scan(const struct ctl_args *a);

/* The commands of ctl_status.c: status [--json], calibrate. */
int cmd_status(const struct ctl_args *a);
int cmd_calibrate(const struct ctl_args *a);

#endif
