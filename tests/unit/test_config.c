/* daemon/config: config_load() on files written to a temporary directory:
 * values, comments, line endings, and the line length limit (511 bytes, a
 * longer line is an error, never read as two lines). */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "config.h"

#define LINE_MAX_BYTES 511 /* docs/man/spindled.8 */

static char dir[256];
static char errors[8192]; /* what the last load() logged */

/* Writes len bytes of text to a new file in dir and loads it into cfg
 * (from the defaults), with stderr caught in errors. */
static int load(const void *text, size_t len, struct config *cfg)
{
	char path[300];
	snprintf(path, sizeof(path), "%s/spindled.conf", dir);
	FILE *f = fopen(path, "we");
	CHECK(f);
	CHECK(fwrite(text, 1, len, f) == len);
	CHECK(fclose(f) == 0);

	char log_path[300];
	snprintf(log_path, sizeof(log_path), "%s/log.XXXXXX", dir);
	int log_fd = mkstemp(log_path);
	CHECK(log_fd >= 0);
	fflush(stderr);
	int saved = dup(2);
	CHECK(saved >= 0 && dup2(log_fd, 2) == 2);

	config_defaults(cfg);
	int r = config_load(cfg, path, true);

	fflush(stderr);
	CHECK(dup2(saved, 2) == 2);
	close(saved);
	ssize_t n = pread(log_fd, errors, sizeof(errors) - 1, 0);
	CHECK(n >= 0);
	errors[n] = '\0';
	close(log_fd);
	unlink(log_path);
	unlink(path);
	return r;
}

static int load_str(const char *text, struct config *cfg)
{
	return load(text, strlen(text), cfg);
}

/* A line of exactly len bytes (no ending) that starts with head and ends
 * with tail, '#' padding in between: "head #####...tail". */
static char *padded(const char *head, size_t len, const char *tail)
{
	size_t h = strlen(head), t = strlen(tail);
	CHECK(h + t + 1 <= len);
	char *s = malloc(len + 1);
	CHECK(s);
	memcpy(s, head, h);
	memset(s + h, '#', len - h - t);
	memcpy(s + len - t, tail, t);
	s[len] = '\0';
	return s;
}

static void test_good(void)
{
	struct config cfg;
	CHECK_EQ(load_str("# spindled.conf\n"
			  "\n"
			  "   \t\n"
			  "  # indented comment\n"
			  "max-clients = 7\n"
			  "profile=small   # trailing comment\n"
			  "  exclusive   =   any  \n"
			  "admin-group =\n"
			  "sync-active-low = yes\n"
			  "max-buffer-bytes = 1048576\n",
			  &cfg),
		 0);
	CHECK_MSG(!errors[0], "%s", errors);
	CHECK_EQ(cfg.max_clients, 7);
	CHECK(!strcmp(cfg.profile, "small"));
	CHECK_EQ(cfg.exclusive, POLICY_ANY);
	CHECK(!strcmp(cfg.admin_group, ""));
	CHECK(cfg.sync_active_low);
	CHECK_EQ(cfg.max_buffer_bytes, 1048576);
	CHECK_EQ(cfg.max_objects, 4096); /* untouched: the default */

	/* An empty file, and one of comments only. */
	CHECK_EQ(load_str("", &cfg), 0);
	CHECK_EQ(cfg.max_clients, 64);
	CHECK_EQ(load_str("#\n# max-clients = 1\n\n", &cfg), 0);
	CHECK_EQ(cfg.max_clients, 64);
}

static void test_line_endings(void)
{
	struct config cfg;
	/* No newline at the end of the last line. */
	CHECK_EQ(load_str("profile = small\nmax-clients = 9", &cfg), 0);
	CHECK_EQ(cfg.max_clients, 9);
	CHECK_EQ(load_str("max-clients = 10 # no newline", &cfg), 0);
	CHECK_EQ(cfg.max_clients, 10);

	/* CRLF: the '\r' is no part of the value. */
	CHECK_EQ(load_str("# dos\r\n\r\nmax-clients = 12\r\nprofile = small\r\nexclusive = none\r\n", &cfg), 0);
	CHECK_MSG(!errors[0], "%s", errors);
	CHECK_EQ(cfg.max_clients, 12);
	CHECK(!strcmp(cfg.profile, "small"));
	CHECK_EQ(cfg.exclusive, POLICY_NONE);
	CHECK_EQ(load_str("max-clients = 13\r", &cfg), 0);
	CHECK_EQ(cfg.max_clients, 13);
}

static void test_line_length(void)
{
	struct config cfg;
	char text[2048];

	/* 511 bytes: fine, with "\n", "\r\n" or no ending. */
	char *line = padded("max-clients = 5 ", LINE_MAX_BYTES, "");
	CHECK_EQ(strlen(line), LINE_MAX_BYTES);
	static const char *const endings[] = { "\n", "\r\n", "" };
	for (int i = 0; i < 3; i++) {
		snprintf(text, sizeof(text), "profile = small\n%s%s", line, endings[i]);
		CHECK_EQ(load_str(text, &cfg), 0);
		CHECK_MSG(!errors[0], "%s", errors);
		CHECK_EQ(cfg.max_clients, 5);
	}
	free(line);

	/* 512 bytes and more: an error that names the file and the line, with
	 * any ending; the lines around it are still read. */
	static const size_t lengths[] = { LINE_MAX_BYTES + 1, LINE_MAX_BYTES + 2, 1000, 1500 };
	for (size_t l = 0; l < sizeof(lengths) / sizeof(lengths[0]); l++) {
		for (int i = 0; i < 3; i++) {
			line = padded("max-objects = 5 ", lengths[l], "");
			snprintf(text, sizeof(text), "profile = small\n%s%s", line, endings[i]);
			free(line);
			CHECK_EQ(load_str(text, &cfg), -EINVAL);
			CHECK_MSG(strstr(errors, "spindled.conf:2: longer than 511 bytes"), "%s", errors);
			CHECK(!strcmp(cfg.profile, "small"));
			CHECK_EQ(cfg.max_objects, 4096);
		}
	}

	/* The line after a long one keeps its number. */
	line = padded("# ", 700, "");
	snprintf(text, sizeof(text), "# one\n%s\n\nno-such-key = 1\nmax-clients = 3\n", line);
	free(line);
	CHECK_EQ(load_str(text, &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:2: longer than 511 bytes"), "%s", errors);
	CHECK_MSG(strstr(errors, "spindled.conf:4: unknown key 'no-such-key'"), "%s", errors);
	CHECK_EQ(cfg.max_clients, 3);
}

/* A long line whose tail (past 511 bytes) reads as a line of its own must not
 * set anything: fgets() into 512 bytes would have read it as a second line. */
static void test_smuggled_key(void)
{
	struct config cfg;
	char text[2048];
	static const char *const heads[] = { "# ", "admin-group = staff ", "profile = small " };
	for (int h = 0; h < 3; h++) {
		for (size_t len = LINE_MAX_BYTES; len <= LINE_MAX_BYTES + 2; len++) {
			char *head = padded(heads[h], len, "");
			snprintf(text, sizeof(text), "%smax-clients = 1\nprojector-buffers = 2\n", head);
			free(head);
			CHECK_EQ(load_str(text, &cfg), -EINVAL);
			CHECK_MSG(strstr(errors, "spindled.conf:1: longer than 511 bytes"), "%s", errors);
			CHECK_EQ(cfg.max_clients, 64);
			CHECK(!strcmp(cfg.admin_group, "spindle-admin"));
			CHECK(!strcmp(cfg.profile, "perspecta"));
			CHECK_EQ(cfg.projector_buffers, 2); /* the next line is read */
		}
	}
}

static void test_nul(void)
{
	struct config cfg;
	static const char a[] = "profile = small\nmax-clients = 3\0 = 4\nmax-objects = 10\n";
	CHECK_EQ(load(a, sizeof(a) - 1, &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:2: NUL byte"), "%s", errors);
	CHECK_EQ(cfg.max_clients, 64);
	CHECK_EQ(cfg.max_objects, 10);

	/* In a comment too, and at the end of a file without a newline. */
	static const char b[] = "# \0\n";
	CHECK_EQ(load(b, sizeof(b) - 1, &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:1: NUL byte"), "%s", errors);
	static const char c[] = "\nmax-clients = 3\0";
	CHECK_EQ(load(c, sizeof(c) - 1, &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:2: NUL byte"), "%s", errors);
	CHECK_EQ(cfg.max_clients, 64);
}

static void test_errors(void)
{
	struct config cfg;
	CHECK_EQ(load_str("max-clients = 5\nno-such-key = 1\n", &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:2: unknown key 'no-such-key'"), "%s", errors);
	CHECK_EQ(load_str("max-clients = 0\n", &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:1: bad value for 'max-clients'"), "%s", errors);
	CHECK_EQ(load_str("\nmax-clients 5\n", &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "spindled.conf:2: expected key = value"), "%s", errors);
	CHECK_EQ(load_str("sim-faults = no-such-fault\n", &cfg), -EINVAL);
	CHECK_MSG(strstr(errors, "bad value for 'sim-faults'"), "%s", errors);

	/* A missing file: fine unless it was asked for. */
	char path[300];
	snprintf(path, sizeof(path), "%s/missing.conf", dir);
	config_defaults(&cfg);
	CHECK_EQ(config_load(&cfg, path, false), 0);
	fprintf(stderr, "(an error about %s is expected next)\n", path);
	CHECK_EQ(config_load(&cfg, path, true), -ENOENT);
}

/* The calibration keys (calibration.h): values and ranges. */
static void test_calibration(void)
{
	struct config cfg;
	CHECK_EQ(load_str("phase-offset = -2.5\naxis-offset-u = 3\naxis-offset-v=-1\nvertical-scale = 1.05\n"
			  "vertical-offset = 0.25\n",
			  &cfg),
		 0);
	CHECK(cfg.calibration.phase_deg == -2.5f && cfg.calibration.axis_u == 3 && cfg.calibration.axis_v == -1);
	CHECK(cfg.calibration.vertical_scale == 1.05f && cfg.calibration.vertical_offset == 0.25f);
	static const char *const bad[] = { "axis-offset-u = 1.5\n", "axis-offset-v = 5000\n", "phase-offset = 200\n",
					   "vertical-scale = 0\n",  "vertical-offset = -1\n", "phase-offset = nan\n",
					   "vertical-scale = 1x\n" };
	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		CHECK_EQ(load_str(bad[i], &cfg), -EINVAL);
		CHECK_MSG(strstr(errors, "spindled.conf:1: bad value for '"), "%s", errors);
	}
	config_defaults(&cfg);
	CHECK(cfg.calibration.phase_deg == 0.0f && cfg.calibration.axis_u == 0 &&
	      cfg.calibration.vertical_scale == 1.0f);
}

int main(void)
{
	const char *tmp = getenv("TMPDIR");
	snprintf(dir, sizeof(dir), "%s/test-config.XXXXXX", tmp && *tmp ? tmp : "/tmp");
	CHECK(mkdtemp(dir));
	test_good();
	test_line_endings();
	test_line_length();
	test_smuggled_key();
	test_nul();
	test_errors();
	test_calibration();
	CHECK(rmdir(dir) == 0);
	return check_done();
}
