#include "config_edit.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fdio.h"
struct text {
	char *data;
	size_t len, cap;
};

static int text_add(struct text *t, const char *s, size_t n)
{
	if (t->len + n + 1 > t->cap) {
		size_t cap = (t->len + n + 1) * 2;
		char *d = realloc(t->data, cap);
		if (!d)
			return -ENOMEM;
		t->data = d;
		t->cap = cap;
	}
	memcpy(t->data + t->len, s, n);
	t->len += n;
	t->data[t->len] = '\0';
	return 0;
}

/* The whole file; a missing one is empty. */
static int read_file(const char *path, struct text *t, mode_t *mode, char *err, size_t err_size)
{
	*mode = 0644;
	int fd = open(path, O_RDONLY | O_CLOEXEC);
	if (fd < 0) {
		if (errno == ENOENT)
			return text_add(t, "", 0);
		int e = errno;
		snprintf(err, err_size, "cannot read %s: %s", path, strerror(e));
		return -e;
	}
	struct stat st;
	if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode) || st.st_size > CONFIG_EDIT_MAX) {
		snprintf(err, err_size, "%s: not a regular file of at most %u bytes", path, CONFIG_EDIT_MAX);
		close(fd);
		return -EINVAL;
	}
	int r = 0;
	*mode = st.st_mode & 07777;
	char buf[4096];
	ssize_t n;
	while (r == 0 && (n = read(fd, buf, sizeof(buf))) != 0) {
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0 || t->len + (size_t)n > CONFIG_EDIT_MAX) {
			r = n < 0 ? -errno : -EFBIG;
			snprintf(err, err_size, "cannot read %s: %s", path, strerror(-r));
		} else if (memchr(buf, '\0', (size_t)n)) {
			r = -EINVAL;
			snprintf(err, err_size, "%s: a NUL byte: not a config file", path);
		} else {
			r = text_add(t, buf, (size_t)n);
		}
	}
	close(fd);
	return r;
}

/* Whether line (up to end) sets key: "key = ..." before any '#'. */
static bool line_sets(const char *line, const char *end, const char *key)
{
	while (line < end && isspace((unsigned char)*line))
		line++;
	size_t n = strlen(key);
	if ((size_t)(end - line) < n || memcmp(line, key, n) != 0)
		return false;
	for (line += n; line < end && (*line == ' ' || *line == '\t'); line++)
		;
	return line < end && *line == '=';
}

/* src with every line of key rewritten, or the line appended. */
static int edit(const struct text *src, const char *key, const char *value, struct text *out)
{
	char setting[600];
	int len = snprintf(setting, sizeof(setting), "%s = %s", key, value);
	if (len < 0 || (size_t)len >= sizeof(setting))
		return -EINVAL;
	bool found = false;
	int r = 0;
	for (const char *p = src->data; r == 0 && p < src->data + src->len;) {
		const char *nl = memchr(p, '\n', (size_t)(src->data + src->len - p));
		const char *end = nl ? nl : src->data + src->len;
		const char *hash = memchr(p, '#', (size_t)(end - p));
		if (line_sets(p, hash ? hash : end, key)) {
			found = true;
			r = text_add(out, setting, (size_t)len);
			if (r == 0 && hash && (r = text_add(out, " ", 1)) == 0)
				r = text_add(out, hash, (size_t)(end - hash));
		} else {
			r = text_add(out, p, (size_t)(end - p));
		}
		if (r == 0 && nl)
			r = text_add(out, "\n", 1);
		p = nl ? nl + 1 : end;
	}
	if (r == 0 && !found) {
		if (out->len && out->data[out->len - 1] != '\n')
			r = text_add(out, "\n", 1);
		if (r == 0 && (r = text_add(out, setting, (size_t)len)) == 0)
			r = text_add(out, "\n", 1);
	}
	return r;
}

/* out written to a temporary file beside path, then renamed over it. */
static int replace_file(const char *path, const struct text *out, mode_t mode, char *err, size_t err_size)
{
	char tmp[4096];
	if (snprintf(tmp, sizeof(tmp), "%s.XXXXXX", path) >= (int)sizeof(tmp)) {
		snprintf(err, err_size, "%s: path too long", path);
		return -ENAMETOOLONG;
	}
	int fd = mkostemp(tmp, O_CLOEXEC);
	if (fd < 0) {
		int e = errno;
		snprintf(err, err_size, "cannot write beside %s: %s", path, strerror(e));
		return -e;
	}
	int r = fchmod(fd, mode) < 0 ? -errno : 0;
	if (r == 0)
		r = fd_write_all(fd, out->data, out->len);
	if (r == 0 && fsync(fd) < 0)
		r = -errno;
	if (close(fd) < 0 && r == 0)
		r = -errno;
	if (r == 0 && rename(tmp, path) < 0)
		r = -errno;
	if (r < 0) {
		unlink(tmp);
		snprintf(err, err_size, "cannot write %s: %s", path, strerror(-r));
	}
	return r;
}

int config_edit_set(const char *path, const char *key, const char *value, char *err, size_t err_size)
{
	struct text src = { 0 }, out = { 0 };
	mode_t mode;
	int r = read_file(path, &src, &mode, err, err_size);
	if (r == 0 && (r = edit(&src, key, value, &out)) < 0)
		snprintf(err, err_size, "%s: cannot set %s: %s", path, key, strerror(-r));
	if (r == 0)
		r = replace_file(path, &out, mode, err, err_size);
	free(src.data);
	free(out.data);
	return r;
}
