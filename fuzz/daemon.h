/* The fuzz targets' in-process spindled (small profile, simulated device,
 * CPU renderer, low quotas), serving clients over socketpairs; the target
 * runs its event loop itself. */
#ifndef SPINDLE_FUZZ_DAEMON_H
#define SPINDLE_FUZZ_DAEMON_H

#include <stdbool.h>

#include "server.h"

/* A spindled in this process, its clients served over socketpairs. */
struct fuzz_server {
	struct server srv;
	bool up;
};

/* Starts a server with the harness's configuration, then the "key",
 * "value" pairs of extra (NULL-terminated, may be NULL). Aborts on
 * failure: without a server there is nothing to fuzz. */
void fuzz_server_start(struct fuzz_server *fs, const char *const *extra);
/* A new client: returns the client's end of a socketpair (blocking,
 * close-on-exec) whose other end the server serves. */
int fuzz_server_connect(struct fuzz_server *fs);
/* Runs the event loop until nothing is ready to run (no waiting). */
void fuzz_server_run(struct fuzz_server *fs);
/* Stops the server; every fd and thread it made is gone after. */
void fuzz_server_stop(struct fuzz_server *fs);

#endif
