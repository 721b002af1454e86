/* The model loader's sandbox, through its test hooks (tools/model_hooks.c):
 * a loader that crashes, hangs, spins or sends a lying result is an error
 * naming the file; what the seccomp filter forbids fails with EPERM; the
 * child runs without privileges; nothing is left behind (no child, no fd).
 * Also the parent's checks of a result header. argv[1]: tests/data. */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "model.h"
#include "model_wire.h"
#include "testvol.h"

static char bunny[4096];

static int count_fds(void)
{
	int n = 0;
	DIR *d = opendir("/proc/self/fd");
	CHECK(d);
	while (readdir(d))
		n++;
	closedir(d);
	return n;
}

/* Loads the bunny with the hook set; the load must fail with errno want
 * and a message starting with the path and containing needle. */
static void expect_failure(const char *hook, int want, const char *needle)
{
	char err[512] = "";
	setenv("SPINDLE_MODEL_TEST_HOOK", hook, 1);
	errno = 0;
	struct model *m = model_load(bunny, err, sizeof(err));
	int e = errno;
	unsetenv("SPINDLE_MODEL_TEST_HOOK");
	printf("%-8s -> %s\n", hook, err);
	CHECK(m == NULL);
	CHECK(e == want);
	CHECK(strncmp(err, bunny, strlen(bunny)) == 0 && err[strlen(bunny)] == ':');
	CHECK(strstr(err, needle) != NULL);
}

static void test_crashes(void)
{
	expect_failure("segv", EINVAL, ": the model loader crashed (signal 11)");
	expect_failure("abort", EINVAL, ": the model loader crashed (signal 6)");

	setenv("SPINDLE_MODEL_TEST_TIMEOUT_MS", "300", 1);
	expect_failure("hang", EINVAL, ": the model loader took longer than 1 s and was stopped");
	unsetenv("SPINDLE_MODEL_TEST_TIMEOUT_MS");

	setenv("SPINDLE_MODEL_TEST_CPU_S", "1", 1);
	expect_failure("spin", EINVAL, ": the model loader used more than 1 s of CPU time and was stopped");
	unsetenv("SPINDLE_MODEL_TEST_CPU_S");
}

static void test_filter(void)
{
	static const char *const hooks[] = { "open", "socket", "exec", "kill", "write" };
	char want[64];
	for (size_t i = 0; i < sizeof(hooks) / sizeof(hooks[0]); i++) {
		snprintf(want, sizeof(want), "test hook %s: %s", hooks[i], strerror(EPERM));
		expect_failure(hooks[i], EINVAL, want);
	}
	if (getuid() == 0)
		expect_failure("ids", EINVAL, "uid 65534 euid 65534 gid 65534 egid 65534 groups 0");
}

static void test_lies(void)
{
	expect_failure("garbage", EINVAL, "the model loader sent a malformed result (bad magic");
	expect_failure("short", EINVAL, "the model loader sent a malformed result (cut short)");
	expect_failure("extra", EINVAL, "malformed result (more bytes than it announced)");
	expect_failure("index", EINVAL, "malformed result (an index out of range)");
	expect_failure("nan", EINVAL, "malformed result (a vertex coordinate is not finite)");
}

static void test_headers(void)
{
	char why[128];
	size_t payload = 0;
	struct model_wire_header h = { .magic = MODEL_WIRE_MAGIC, .vertex_count = 3, .triangle_count = 1 };
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == 0 && payload == 36 + 12);
	h.flags = MODEL_WIRE_COLORS;
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == 0 && payload == 48 + 12);
	h.vertex_count = MODEL_MAX_VERTICES + 1ull;
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == -EINVAL);
	h.vertex_count = 3;
	h.triangle_count = UINT64_MAX;
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == -EINVAL);
	h.triangle_count = h.line_count = h.point_count = MODEL_MAX_PRIMITIVES / 2;
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == -EINVAL);
	h = (struct model_wire_header){ .magic = MODEL_WIRE_MAGIC, .status = EINVAL, .text_len = MODEL_MAX_TEXT + 1 };
	CHECK(model_wire_check_header(&h, &payload, why, sizeof(why)) == -EINVAL);

	char text[8];
	model_wire_error_text((const uint8_t *)"a\033[2Jb\n", 7, text, sizeof(text));
	CHECK(strcmp(text, "a?[2Jb?") == 0);
}

int main(int argc, char **argv)
{
	char err[512];
	CHECK(argc == 2);
	snprintf(bunny, sizeof(bunny), "%s/bunny.ply", argv[1]);
	int fds = count_fds();

	test_crashes();
	test_filter();
	test_lies();
	test_headers();

	struct model *m = model_load(bunny, err, sizeof(err));
	CHECK(m && m->triangle_count == 3674);
	model_destroy(m);
	CHECK(count_fds() == fds);
	CHECK(waitpid(-1, NULL, WNOHANG) < 0 && errno == ECHILD);
	return 0;
}
