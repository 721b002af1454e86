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

/* ---- the loader child, whatever it reads (model_sandbox.c) ----
 *
 * What model_sandbox_load() and the scan loader (tools/scan_loader.c)
 * share: a child forked (not executed) that confines itself and writes
 * its result into a pipe, which the parent reads within a deadline,
 * saying every second or two that a slow load goes on; the child is
 * always reaped (killed when the exchange failed), and what went wrong
 * with it becomes a reason naming the loader ("the scan loader crashed
 * (signal 6)"). */

struct sandbox {
	const char *name; /* "model loader", "scan loader": for reasons */
	const char *path; /* for progress lines */
	int timeout_ms;   /* wall time; then the child is killed */
	unsigned cpu_s;   /* its RLIMIT_CPU, for the reason */
	/* set by sandbox_start() and the calls after it */
	pid_t pid;
	int rfd; /* the read end of the result pipe */
	int64_t start_ms, note_ms, deadline_ms;
	int wstatus;
	bool timed_out;
};

/* The child's side: runs in the child with the write end of the result
 * pipe; must not return (it leaves with _exit()). */
typedef void (*sandbox_child_fn)(void *arg, int out_fd);

/* Forks the child running fn(arg, out_fd). 0, or -errno. */
int sandbox_start(struct sandbox *sb, sandbox_child_fn fn, void *arg);
/* Exactly len bytes of the result before the deadline: 0, -ETIMEDOUT,
 * -EPIPE (the pipe ended first) or -errno. */
int sandbox_read(struct sandbox *sb, void *buf, size_t len);
/* The end of the pipe, now: 0, -EPROTO (more bytes: why filled) or as
 * sandbox_read(). */
int sandbox_read_end(struct sandbox *sb, char *why, size_t why_size);
/* Reaps the child: waits for it until the deadline, then kills it; with
 * kill_now, kills it first. Closes the pipe. */
void sandbox_reap(struct sandbox *sb, bool kill_now);
/* After sandbox_reap(), given the result of the exchange rx (0, -EPIPE
 * for a result that ended where it should, else what sandbox_read() or
 * the caller's checks gave, -EPROTO with why), what went wrong with the
 * child itself: 0 (nothing: its message stands), or -EINVAL (-ENOMEM for
 * rx -ENOMEM) with reason filled. */
int sandbox_failure(const struct sandbox *sb, int rx, const char *why, char *reason, size_t reason_size);
/* Where sandboxed loads that take over a second say that they go on
 * (every 2 s), or NULL (the default): spindlectl passes stderr. */
void sandbox_set_progress(FILE *f);
/* The progress stream (NULL: none), for the "read in N s" line. */
FILE *sandbox_progress(void);

/* ---- model_confine.c ---- */

/* At most this many input fds (a DICOM directory's files). */
#define MODEL_CONFINE_MAX_INPUTS 8192u

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
/* The same with count input fds (1 to MODEL_CONFINE_MAX_INPUTS): moved to
 * 3, 4, ... in their order (in_fds gets the new numbers), the pipe after
 * them; the filter allows reading any of them. */
int model_confine_child_fds(const struct model_confine *c, int *in_fds, unsigned count, int *out_fd, char *why,
			    size_t why_size);

/* ---- model_hooks.c: only in the tests' build (SPINDLE_MODEL_TEST_HOOKS) ---- */

/* $SPINDLE_MODEL_TEST_TIMEOUT_MS and $SPINDLE_MODEL_TEST_CPU_S override the
 * limits; $SPINDLE_MODEL_TEST_HOOK makes the confined child misbehave
 * instead of loading: crash, hang, spin, try what the filter forbids and
 * report the result, or send a lying result (see model_hooks.c). */
void model_test_limits(int *timeout_ms, struct model_confine *c);
/* Called in the confined child, with how its loader sends an error
 * message (model_wire_send_error(), or the scan loader's); returns only
 * when no hook is set. */
typedef int (*model_test_send_error)(int fd, int status, const char *text);
void model_test_hook(int in_fd, int out_fd, model_test_send_error send);

#endif
