/* Protocol test suite harness: each test starts its own spindled on the
 * simulated device (small profile) on a private socket, talks to it with
 * libspindle or raw bytes, and reads back what was shown by capture. */
#ifndef SPINDLE_TEST_HARNESS_H
#define SPINDLE_TEST_HARNESS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/types.h>

#include "calibration.h"
#include "check.h"
#include "geometry.h"
#include "spindle/spindle.h"
#include "volume.h"

struct daemon {
	pid_t pid;
	char dir[64];
	char socket[128];
	char log[128];
	char renderer[16]; /* --renderer given, "" for the default */
	bool strict_gl;    /* a GL renderer must render every volume itself */
};

/* Copies the daemon's log to stdout (for a failure's report). */
void daemon_print_log(struct daemon *d);

/* Starts spindled (path in $SPINDLED) with --device sim --profile small,
 * and waits until its socket accepts connections. With
 * $SPINDLE_TEST_RENDERER set (egl, osmesa, cpu, auto) it passes --renderer
 * and, but for auto, checks that the daemon runs that renderer
 * (daemon_require_renderer(): skipped when it is unavailable here, failed
 * when another one runs); for egl and osmesa, daemon_stop() then also
 * checks that no run-time failure handed the rendering over to the CPU
 * renderer, unless $SPINDLE_GL_FAULT injects one. */
void daemon_start(struct daemon *d);
/* The same with an explicit --renderer (NULL: none), and no checks on
 * which renderer runs. */
void daemon_start_renderer(struct daemon *d, const char *renderer);
/* The same with the config file text config (the daemon's defaults and
 * renderer otherwise). */
void daemon_start_config(struct daemon *d, const char *config);
/* Checks that the daemon runs renderer name; exits 77 (skipped) when it
 * logged that the renderer is unavailable here (no EGL, no OSMesa). */
void daemon_require_renderer(struct daemon *d, const char *name);
/* SIGTERM, then checks it exited 0; removes its files. */
void daemon_stop(struct daemon *d);
/* The same, keeping its log to read (daemon_remove_files() after). */
void daemon_stop_keep_log(struct daemon *d);
void daemon_remove_files(struct daemon *d);
/* Whether the daemon's log (its stderr) holds text, so far. */
bool daemon_log_contains(struct daemon *d, const char *text);
/* True while the daemon process runs. */
bool daemon_alive(struct daemon *d);
/* Open fds of the daemon, from /proc (for leak checks). */
int daemon_fd_count(struct daemon *d);

struct spindle *client_connect(struct daemon *d);
/* A connected raw socket (no handshake). */
int raw_connect(struct daemon *d);
/* Sends a header + body; returns 0 or -errno. */
int raw_send(int fd, uint32_t object, uint16_t opcode, const void *body, uint32_t body_size);
/* Reads until EOF (or 3 s); returns whether an error event with the given
 * code came before the close (code 0: any error event). */
bool raw_expect_error_and_close(int fd, uint32_t code);

/* The next volume shown, through capture. */
struct volume *capture_volume(struct spindle *sp);

/* Draws vertices as one list on one layer with a colour, commits and waits
 * until shown. The objects stay alive until the connection is closed. */
void show_vertices(struct spindle *sp, int mode, const float *xyz, uint32_t count, uint8_t r, uint8_t g, uint8_t b);

/* The calibration the suite's daemons run with: $SPINDLE_TEST_CALIBRATION
 * as "PHASE,U,V,SCALE,OFFSET" (phase-offset, axis-offset-u, axis-offset-v,
 * vertical-scale, vertical-offset; calibration.h), else none. The
 * expectations below are shifted by it: the point turned by -PHASE about
 * the axis with its height y made SCALE y + OFFSET, its voxel then moved by
 * U columns and V rows. */
const struct calibration *test_calibration(void);
/* Where the calibration puts volume-space point (x, y, z) for rendering. */
void calibrated_point(double x, double y, double z, double out[3]);

/* Expectations from docs/design.md section 3 (computed here, not by spindled):
 * the volume image, column and row a point lights (under test_calibration(),
 * which must keep it inside the image). */
struct voxel {
	uint32_t k, u, v;
};
struct voxel expected_point(const struct geometry *g, double x, double y, double z);

/* Whether channel c has a lit voxel within radius voxels (u, v) of (k, u, v). */
bool lit_near(const struct volume *vol, uint32_t k, int u, int v, int c, int radius);

#endif
