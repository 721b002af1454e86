#include "scan_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_NAMES 8

static char dir[3072];
static char names[MAX_NAMES][64];
static int name_count;

static void remove_files(void)
{
	char path[4096];
	for (int n = 0; n < name_count; n++) {
		snprintf(path, sizeof(path), "%s/%s", dir, names[n]);
		unlink(path);
	}
	rmdir(dir);
}

static bool make_dir(void)
{
	const char *tmp = getenv("TMPDIR");
	snprintf(dir, sizeof(dir), "%s/spindle-fuzz-scan-XXXXXX", tmp && *tmp ? tmp : "/tmp");
	if (!mkdtemp(dir)) {
		dir[0] = '\0';
		return false;
	}
	atexit(remove_files);
	return true;
}

/* Remembers name for the removal at exit. */
static bool note_name(const char *name)
{
	for (int n = 0; n < name_count; n++)
		if (!strcmp(names[n], name))
			return true;
	if (name_count == MAX_NAMES || strlen(name) >= sizeof(names[0]) || strchr(name, '/'))
		return false;
	strcpy(names[name_count++], name);
	return true;
}

static bool write_all(int fd, const void *data, size_t size)
{
	const char *p = data;
	while (size > 0) {
		ssize_t n = write(fd, p, size);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return false;
		p += n;
		size -= (size_t)n;
	}
	return true;
}

const char *fuzz_scan_file(const char *name, const void *data, size_t size)
{
	static char path[4096];
	if ((!dir[0] && !make_dir()) || !note_name(name))
		return NULL;
	snprintf(path, sizeof(path), "%s/%s", dir, name);
	int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
	if (fd < 0)
		return NULL;
	bool ok = write_all(fd, data, size);
	close(fd);
	return ok ? path : NULL;
}
