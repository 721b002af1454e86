/* config_edit_set() (spindlectl calibrate --save): the key's lines
 * rewritten with their comments, every other line kept byte for byte
 * (comments, a key that only starts alike, the key in a comment, CRLF, no
 * newline at the end), the line appended when missing, a missing file
 * created 0644, the file's mode kept, and files it must not touch (a NUL
 * byte, over CONFIG_EDIT_MAX, a directory) left as they were with an error
 * naming them. */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "config_edit.h"

static char dir[256], path[300], err[600];

static void write_file(const char *text, size_t n, mode_t mode)
{
	unlink(path);
	int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, mode);
	CHECK(fd >= 0 && write(fd, text, n) == (ssize_t)n && fchmod(fd, mode) == 0 && close(fd) == 0);
}

static char *read_file(size_t *n)
{
	static char buf[1 << 16];
	int fd = open(path, O_RDONLY);
	CHECK(fd >= 0);
	ssize_t r = read(fd, buf, sizeof(buf) - 1);
	CHECK(r >= 0);
	close(fd);
	buf[r] = '\0';
	*n = (size_t)r;
	return buf;
}

static void check_edit(const char *before, const char *key, const char *value, const char *after)
{
	write_file(before, strlen(before), 0640);
	CHECK_MSG(config_edit_set(path, key, value, err, sizeof(err)) == 0, "%s", err);
	size_t n;
	const char *got = read_file(&n);
	CHECK_MSG(n == strlen(after) && !memcmp(got, after, n), "got:\n%s\nwant:\n%s", got, after);
	struct stat st;
	CHECK(stat(path, &st) == 0 && (st.st_mode & 07777) == 0640);
}

static void test_edits(void)
{
	check_edit("# spindled.conf\nprofile = small\naxis-offset-u = 9   # measured\n", "axis-offset-u", "-3",
		   "# spindled.conf\nprofile = small\naxis-offset-u = -3 # measured\n");
	/* Every line of the key, none of the look-alikes. */
	check_edit("axis-offset-u=1\n  axis-offset-u\t= 2\naxis-offset-uu = 3\n# axis-offset-u = 4\n", "axis-offset-u",
		   "5", "axis-offset-u = 5\naxis-offset-u = 5\naxis-offset-uu = 3\n# axis-offset-u = 4\n");
	/* Appended, after a last line without a newline. */
	check_edit("profile = small", "phase-offset", "1.5", "profile = small\nphase-offset = 1.5\n");
	check_edit("", "phase-offset", "1.5", "phase-offset = 1.5\n");
	/* CRLF lines stay CRLF where untouched. */
	check_edit("profile = small\r\nvertical-scale = 1\r\n", "vertical-scale", "1.1",
		   "profile = small\r\nvertical-scale = 1.1\n");
}

static void test_missing_file(void)
{
	unlink(path);
	CHECK_MSG(config_edit_set(path, "axis-offset-v", "-2", err, sizeof(err)) == 0, "%s", err);
	size_t n;
	CHECK(!strcmp(read_file(&n), "axis-offset-v = -2\n"));
	struct stat st;
	CHECK(stat(path, &st) == 0 && (st.st_mode & 07777) == 0644);
}

static void check_refused(const char *what)
{
	CHECK_MSG(config_edit_set(path, "axis-offset-u", "1", err, sizeof(err)) < 0, "%s", what);
	CHECK_MSG(strstr(err, path) != NULL, "%s: the error names the file: %s", what, err);
}

static void test_refused(void)
{
	static const char nul[] = "profile = small\n\0axis-offset-u = 2\n";
	write_file(nul, sizeof(nul) - 1, 0644);
	check_refused("a NUL byte");
	size_t n;
	const char *got = read_file(&n);
	CHECK(n == sizeof(nul) - 1 && !memcmp(got, nul, n));
	char *big = malloc(CONFIG_EDIT_MAX + 2);
	CHECK(big != NULL);
	memset(big, '#', CONFIG_EDIT_MAX + 1);
	write_file(big, CONFIG_EDIT_MAX + 1, 0644);
	free(big);
	check_refused("over CONFIG_EDIT_MAX");
	unlink(path);
	CHECK(mkdir(path, 0755) == 0);
	check_refused("a directory");
	CHECK(rmdir(path) == 0);
	/* Nothing left behind: no temporary files. */
	CHECK(rmdir(dir) == 0 && mkdir(dir, 0755) == 0);
}

int main(void)
{
	const char *tmp = getenv("TMPDIR");
	snprintf(dir, sizeof(dir), "%s/test-config-edit.XXXXXX", tmp && *tmp ? tmp : "/tmp");
	CHECK(mkdtemp(dir));
	snprintf(path, sizeof(path), "%s/spindled.conf", dir);
	test_edits();
	test_missing_file();
	test_refused();
	unlink(path);
	CHECK(rmdir(dir) == 0);
	return check_done();
}
