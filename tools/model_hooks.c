/* Test hooks of the model and scan loaders (model_sandbox.h), built only into the
 * tests' copy of the tools library (-DSPINDLE_MODEL_TEST_HOOKS): spindlectl
 * and everything installed never read these variables.
 *
 * $SPINDLE_MODEL_TEST_HOOK, in the confined child, instead of loading:
 *   segv, abort        crash (a write to an unmapped address; abort())
 *   hang, spin         block forever (futex), or burn CPU
 *   open, socket, exec, kill, write
 *                      try what the filter forbids (open a file, make a
 *                      socket, execve, signal the parent, write to stdout)
 *                      and send the result as an error: "test hook open:
 *                      Operation not permitted"
 *   ids                send the credentials it runs with as an error
 *   garbage, short, extra, index, nan
 *                      send a bad result: not a header, a mesh cut short,
 *                      bytes after it, an index out of range, a NaN vertex
 *                      (to the scan loader's parent all but garbage are cut
 *                      short; its own lies are in scan_loader.c)
 * $SPINDLE_MODEL_TEST_TIMEOUT_MS and $SPINDLE_MODEL_TEST_CPU_S set the
 * limits. */
#include <errno.h>
#include <fcntl.h>
#include <linux/futex.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "model_sandbox.h"
#include "model_wire.h"

void model_test_limits(int *timeout_ms, struct model_confine *c)
{
	const char *t = getenv("SPINDLE_MODEL_TEST_TIMEOUT_MS"), *cpu = getenv("SPINDLE_MODEL_TEST_CPU_S");
	if (t && atoi(t) > 0)
		*timeout_ms = atoi(t);
	if (cpu && atoi(cpu) > 0)
		c->cpu_s = (unsigned)atoi(cpu);
}

/* How the loader at hand sends an error: the model's wire, or the scan's. */
static model_test_send_error send_error = model_wire_send_error;

static __attribute__((noreturn)) void report(int out_fd, const char *hook, int result)
{
	char text[256];
	snprintf(text, sizeof(text), "test hook %s: %s", hook, result < 0 ? strerror(errno) : "allowed");
	send_error(out_fd, EINVAL, text);
	_exit(0);
}

static __attribute__((noreturn)) void send_ids(int out_fd)
{
	char text[256];
	snprintf(text, sizeof(text), "test hook ids: uid %u euid %u gid %u egid %u groups %d", (unsigned)getuid(),
		 (unsigned)geteuid(), (unsigned)getgid(), (unsigned)getegid(), getgroups(0, NULL));
	send_error(out_fd, EINVAL, text);
	_exit(0);
}

/* A triangle, spoiled as the hook says; then the end. */
static __attribute__((noreturn)) void send_lie(int out_fd, const char *hook)
{
	float v[9] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
	uint32_t idx[3] = { 0, 1, 2 };
	struct model_wire_header h = { .magic = MODEL_WIRE_MAGIC, .vertex_count = 3, .triangle_count = 1 };
	if (strcmp(hook, "index") == 0)
		idx[2] = 7;
	if (strcmp(hook, "nan") == 0)
		v[4] = NAN;
	if (strcmp(hook, "garbage") == 0) {
		uint8_t junk[1024]; /* longer than any loader's header */
		memset(junk, 0xab, sizeof(junk));
		_exit(write(out_fd, junk, sizeof(junk)) > 0 ? 0 : 1);
	}
	ssize_t n = write(out_fd, &h, sizeof(h));
	n += write(out_fd, v, sizeof(v));
	if (strcmp(hook, "short") != 0)
		n += write(out_fd, idx, sizeof(idx));
	if (strcmp(hook, "extra") == 0)
		n += write(out_fd, idx, sizeof(idx));
	_exit(n > 0 ? 0 : 1);
}

static __attribute__((noreturn)) void crash(const char *hook)
{
	if (strcmp(hook, "abort") == 0)
		abort();
	volatile uintptr_t addr = 16; /* the first page is never mapped */
	*(volatile int *)addr = 1;
	_exit(1);
}

static void try_forbidden(int out_fd, const char *hook)
{
	static char *const argv[] = { "true", NULL };
	if (strcmp(hook, "open") == 0)
		report(out_fd, hook, open("/etc/passwd", O_RDONLY));
	if (strcmp(hook, "socket") == 0)
		report(out_fd, hook, socket(AF_UNIX, SOCK_STREAM, 0));
	if (strcmp(hook, "exec") == 0)
		report(out_fd, hook, execve("/bin/true", argv, argv + 1));
	if (strcmp(hook, "kill") == 0)
		report(out_fd, hook, kill(getppid(), 0));
	if (strcmp(hook, "write") == 0)
		report(out_fd, hook, (int)write(STDOUT_FILENO, "x", 1));
}

void model_test_hook(int in_fd, int out_fd, model_test_send_error send)
{
	const char *hook = getenv("SPINDLE_MODEL_TEST_HOOK");
	send_error = send;
	static int never;
	if (!hook || !*hook)
		return;
	if (strcmp(hook, "segv") == 0 || strcmp(hook, "abort") == 0)
		crash(hook);
	if (strcmp(hook, "hang") == 0)
		for (;;)
			syscall(SYS_futex, &never, FUTEX_WAIT, 0, NULL, NULL, 0);
	if (strcmp(hook, "spin") == 0)
		for (;;)
			never++;
	if (strcmp(hook, "ids") == 0)
		send_ids(out_fd);
	try_forbidden(out_fd, hook);
	send_lie(out_fd, hook);
}
