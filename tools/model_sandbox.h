/* The model loader child: model_load() forks, the child confines itself
 * (model_confine.c), reads the file with model_import_fd() and sends the
 * mesh over a pipe (model_wire.h); the parent reads it within a deadline,
 * reaps the child and checks everything it sent. */
#ifndef SPINDLE_TOOLS_MODEL_SANDBOX_H
#define SPINDLE_TOOLS_MODEL_SANDBOX_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

#include "model.h"

/* The loader's limits: wall time (the parent kills it), CPU time
 * (RLIMIT_CPU: SIGXCPU, then SIGKILL a second later) and memory
 * (RLIMIT_AS, on top of what the process had mapped when it forked). */
#define MODEL_LOADER_TIMEOUT_MS 60000
#define MODEL_LOADER_CPU_S 30
#define MODEL_LOADER_MEMORY (4ull << 30)

/* Runs the loader on fd (open for reading, a regular file of size bytes;
 * path for the importer and messages), with the companion files read for
 * it (model_import.h; may be NULL). 0 with *out set, or -errno with
 * reason filled (without the path): a reason the loader gave, or what went
 * wrong with it ("the model loader crashed (signal 11)"). */
struct model_companions;
/* Where a load that takes over a second says that it goes on (every 2 s),
 * or NULL (the default): spindlectl passes stderr. */
void model_sandbox_set_progress(FILE *f);
int model_sandbox_load(int fd, uint64_t size, const char *path, const struct model_companions *comp, struct model **out,
		       char *reason, size_t reason_size);

/* ---- model_confine.c ---- */

struct model_confine {
	bool drop_user; /* started as root: become uid/gid, no groups */
	uid_t uid;
	gid_t gid;
	pid_t parent; /* to notice a parent that died before PR_SET_PDEATHSIG */
	unsigned cpu_s;
	uint64_t memory;
};

/* The parent's half: whom to become (nobody, when root), the limits. */
void model_confine_prepare(struct model_confine *c);

/* The child's half, in order: default signal actions, *in_fd and *out_fd
 * moved to 3 and up (the new numbers stored), fds 0 and 1 on /dev/null and
 * every other fd closed but 2; the user and groups dropped (checked), no
 * capabilities; RLIMIT_CORE 0, RLIMIT_CPU, RLIMIT_AS; no_new_privs, not
 * dumpable, killed with the parent; the seccomp filter. 0, or -errno with
 * why filled. */
int model_confine_child(const struct model_confine *c, int *in_fd, int *out_fd, char *why, size_t why_size);

/* ---- model_hooks.c: only in the tests' build (SPINDLE_MODEL_TEST_HOOKS) ---- */

/* $SPINDLE_MODEL_TEST_TIMEOUT_MS and $SPINDLE_MODEL_TEST_CPU_S override the
 * limits; $SPINDLE_MODEL_TEST_HOOK makes the confined child misbehave
 * instead of loading: crash, hang, spin, try what the filter forbids and
 * report the result, or send a lying result (see model_hooks.c). */
void model_test_limits(int *timeout_ms, struct model_confine *c);
/* Called in the confined child; returns only when no hook is set. */
void model_test_hook(int in_fd, int out_fd);

#endif
