/* The files a model names that its importer reads (model_import.h): read
 * here, in the parent, with the caller's rights, into memory that the
 * loader child inherits; the child itself may open nothing. Only an OBJ's
 * `mtllib` names are followed, only to plain names beside the model. The
 * model is untrusted text: lines are read into a bounded buffer and
 * anything odd is skipped. */
#include <errno.h>
#include <fcntl.h>
#include <libgen.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "model_import.h"

#define SCAN_MAX (16u << 20) /* the mtllib lines come first in practice */
#define LINE_MAX_BYTES 1024

static bool is_obj(const char *path)
{
	const char *dot = strrchr(path, '.');
	return dot && strcasecmp(dot, ".obj") == 0;
}

/* A plain file name in the model's folder: no path, nothing hidden. */
static bool plain_name(const char *name)
{
	size_t n = strlen(name);
	return n > 0 && n < sizeof(((struct model_companion *)0)->name) && name[0] != '.' && !strchr(name, '/') &&
	       !strchr(name, '\\');
}

/* The whole of a regular file of at most MODEL_COMPANION_MAX bytes. */
static uint8_t *read_small(int dir, const char *name, size_t *size)
{
	int fd = openat(dir, name, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK | O_NOFOLLOW);
	struct stat st;
	uint8_t *data = NULL;
	if (fd >= 0 && fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size <= MODEL_COMPANION_MAX &&
	    (data = malloc(st.st_size ? (size_t)st.st_size : 1))) {
		*size = (size_t)st.st_size;
		for (size_t got = 0; got < *size;) {
			ssize_t n = pread(fd, data + got, *size - got, (off_t)got);
			if (n <= 0 && !(n < 0 && errno == EINTR)) {
				free(data);
				data = NULL;
				break;
			}
			got += n > 0 ? (size_t)n : 0;
		}
	}
	if (fd >= 0)
		close(fd);
	return data;
}

static void add(struct model_companions *comp, int dir, const char *name)
{
	if (comp->count == MODEL_COMPANIONS || !plain_name(name))
		return;
	for (unsigned i = 0; i < comp->count; i++)
		if (!strcmp(comp->file[i].name, name))
			return;
	struct model_companion *c = &comp->file[comp->count];
	if (!(c->data = read_small(dir, name, &c->size)))
		return;
	strcpy(c->name, name);
	comp->count++;
}

/* "mtllib a.mtl b.mtl": each name after the keyword. */
static void take_line(struct model_companions *comp, int dir, char *line)
{
	if (strncmp(line, "mtllib", 6) != 0 || (line[6] != ' ' && line[6] != '\t'))
		return;
	char *save = NULL;
	for (char *tok = strtok_r(line + 6, " \t\r", &save); tok; tok = strtok_r(NULL, " \t\r", &save))
		add(comp, dir, tok);
}

void model_companions_read(int fd, uint64_t size, const char *path, struct model_companions *comp)
{
	memset(comp, 0, sizeof(*comp));
	char *copy = strdup(path);
	int dir = copy && is_obj(path) ? open(dirname(copy), O_RDONLY | O_DIRECTORY | O_CLOEXEC) : -1;
	free(copy);
	if (dir < 0)
		return;
	char buf[65536], line[LINE_MAX_BYTES];
	size_t len = 0;
	bool overlong = false;
	uint64_t end = size < SCAN_MAX ? size : SCAN_MAX;
	for (uint64_t off = 0; off < end;) {
		ssize_t n = pread(fd, buf, end - off < sizeof(buf) ? (size_t)(end - off) : sizeof(buf), (off_t)off);
		if (n <= 0)
			break;
		off += (uint64_t)n;
		for (ssize_t i = 0; i < n; i++) {
			if (buf[i] != '\n') {
				overlong |= len == sizeof(line) - 1;
				line[len < sizeof(line) - 1 ? len++ : len] = buf[i];
				continue;
			}
			line[len] = '\0';
			if (!overlong)
				take_line(comp, dir, line);
			len = 0;
			overlong = false;
		}
	}
	line[len] = '\0';
	if (len && !overlong) /* a last line without its newline */
		take_line(comp, dir, line);
	close(dir);
}

void model_companions_free(struct model_companions *comp)
{
	for (unsigned i = 0; i < comp->count; i++)
		free(comp->file[i].data);
	comp->count = 0;
}
