/* spindlectl's commands, one function each (spindlectl.c, ctl_status.c):
 * the parsed command line, the exit statuses and the helpers they share. */
#ifndef SPINDLE_CTL_H
#define SPINDLE_CTL_H

#include <stdbool.h>
#include <stdint.h>

#include <spindle/spindle.h>

/* Exit statuses (spindlectl(1), EXIT STATUS). */
enum {
	CTL_OK = 0,
	CTL_FAILED = 1,  /* a request failed, the connection broke, an output file could not be written */
	CTL_USAGE = 2,   /* bad command line */
	CTL_CONNECT = 3, /* no daemon at the socket, or no common protocol version */
	CTL_REFUSED = 4, /* the daemon refused: capture not allowed, a commit over quota or policy */
	CTL_INPUT = 5,   /* an input file that cannot be read or used: a model, an .svol */
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
};

/* A usage error (fmt with arg) on stderr; returns CTL_USAGE. */
int ctl_usage_error(const char *fmt, const char *arg);
/* The socket path libspindle will use, for messages. */
const char *ctl_socket_path(const struct ctl_args *a);
/* A connection to the daemon, or NULL after saying why. */
struct spindle *ctl_connect(const struct ctl_args *a);
/* "spindlectl: WHAT: why" from the connection's error or ret. */
void ctl_report_failure(struct spindle *sp, const char *what, int ret);

/* The commands of ctl_status.c: status [--json], calibrate. */
int cmd_status(const struct ctl_args *a);
int cmd_calibrate(const struct ctl_args *a);

#endif
