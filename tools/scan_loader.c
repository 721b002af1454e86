/* The scan loader child and its parent's side (scan_loader.h), on the
 * sandbox of model_sandbox.c. */
#include "scan_loader.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "fdio.h"
#include "model_sandbox.h"
#include "model_wire.h"
#include "prefault.h"
#include "scan_priv.h"

_Static_assert(SCAN_MAX_FILES <= MODEL_CONFINE_MAX_INPUTS, "a DICOM directory's files are the loader's inputs");

/* ---- the child ---- */

struct scan_child {
	struct scan_files *files;
	const struct scan_raw *raw;
	const struct model_confine *confine;
	int *fds; /* room for files->count */
};

static int send_error(int fd, int status, const char *text)
{
	size_t len = strlen(text);
	struct scan_wire_header h = {
		.magic = SCAN_WIRE_MAGIC,
		.status = status > 0 ? (uint32_t)status : EINVAL,
		.text_len = len < SCAN_WIRE_MAX_TEXT ? (uint32_t)len : SCAN_WIRE_MAX_TEXT,
	};
	int ret = fd_write_all(fd, &h, sizeof(h));
	return ret == 0 ? fd_write_all(fd, text, h.text_len) : ret;
}

static int send_scan(int fd, const struct scan *s)
{
	struct scan_wire_header h = { .magic = SCAN_WIRE_MAGIC, .type = (uint32_t)s->type, .data_size = s->size };
	struct scan_layout l;
	memcpy(h.dims, s->dims, sizeof(h.dims));
	memcpy(h.spacing, s->spacing, sizeof(h.spacing));
	memcpy(h.to_ras, s->to_ras, sizeof(h.to_ras));
	memcpy(h.what, s->what, sizeof(h.what));
	h.what[sizeof(h.what) - 1] = '\0';
	scan_layout_of(s->dims, s->spacing, s->to_ras, &l);
	int ret = fd_write_all(fd, &h, sizeof(h));
	return ret == 0 ? scan_layout_write(s, &l, fd) : ret;
}

#ifdef SPINDLE_MODEL_TEST_HOOKS
/* The tests' build: $SPINDLE_MODEL_TEST_HOOK scan-huge, scan-singular,
 * scan-size, scan-short or scan-extra sends a 2x2x2 uint8 scan spoiled so:
 * 4096^3 voxels, a singular to_ras, a data size that is not the volume's,
 * half its samples, a byte after them. Else returns. */
static void scan_test_lie(int out_fd)
{
	const char *hook = getenv("SPINDLE_MODEL_TEST_HOOK");
	uint8_t samples[9] = { 0 };
	struct scan_wire_header h = {
		.magic = SCAN_WIRE_MAGIC,
		.type = SCAN_U8,
		.dims = { 2, 2, 2 },
		.spacing = { 1, 1, 1 },
		.data_size = 8,
	};
	size_t len = 8;
	if (!hook || strncmp(hook, "scan-", 5) != 0)
		return;
	for (int n = 0; n < 4; n++)
		h.to_ras[5 * n] = strcmp(hook, "scan-singular") == 0 && n < 3 ? 0 : 1;
	if (strcmp(hook, "scan-huge") == 0)
		h.dims[0] = h.dims[1] = h.dims[2] = 4096;
	if (strcmp(hook, "scan-size") == 0)
		h.data_size = 7;
	if (strcmp(hook, "scan-short") == 0)
		len = 4;
	if (strcmp(hook, "scan-extra") == 0)
		len = 9;
	int ret = fd_write_all(out_fd, &h, sizeof(h));
	_exit(ret == 0 && fd_write_all(out_fd, samples, len) == 0 ? 0 : 1);
}
#endif

static __attribute__((noreturn)) void child_main(void *arg, int out_fd)
{
	struct scan_child *c = arg;
	struct scan s;
	char why[512];
	for (size_t n = 0; n < c->files->count; n++)
		c->fds[n] = c->files->inputs[n].fd;
	int ret = model_confine_child_fds(c->confine, c->fds, (unsigned)c->files->count, &out_fd, why, sizeof(why));
	if (ret < 0)
		_exit(send_error(out_fd, -ret, why) < 0 ? 1 : 0);
#ifdef SPINDLE_MODEL_TEST_HOOKS
	scan_test_lie(out_fd);
	model_test_hook(c->fds[0], out_fd, send_error);
#endif
	for (size_t n = 0; n < c->files->count; n++)
		c->files->inputs[n].fd = c->fds[n];
	ret = scan_read_files(c->files, c->raw, &s, why, sizeof(why));
	ret = ret < 0 ? send_error(out_fd, -ret, why) : send_scan(out_fd, &s);
	_exit(ret < 0 ? 1 : 0);
}

/* ---- the parent ---- */

/* The header of a scan (status 0) checked as scan.h checks a result, the
 * layout made from it; why filled otherwise. */
static int check_header(const struct scan_wire_header *h, struct scan_shown *out, char *why, size_t why_size)
{
	struct scan g = { .type = (enum scan_type)h->type };
	if (h->text_len || h->reserved) {
		snprintf(why, why_size, "a bad header");
		return -EPROTO;
	}
	memcpy(g.dims, h->dims, sizeof(g.dims));
	memcpy(g.spacing, h->spacing, sizeof(g.spacing));
	memcpy(g.to_ras, h->to_ras, sizeof(g.to_ras));
	if (scan_check_geometry(&g, "header", why, why_size) != 0)
		return -EPROTO;
	uint64_t size = (uint64_t)g.dims[0] * g.dims[1] * g.dims[2] * scan_type_size(g.type);
	if (h->data_size != size) {
		snprintf(why, why_size, "%llu bytes of samples for %ux%ux%u %s", (unsigned long long)h->data_size,
			 g.dims[0], g.dims[1], g.dims[2], scan_type_name(g.type));
		return -EPROTO;
	}
	out->type = g.type;
	memcpy(out->dims, g.dims, sizeof(out->dims));
	memcpy(out->to_ras, g.to_ras, sizeof(out->to_ras));
	scan_layout_of(g.dims, g.spacing, g.to_ras, &out->layout);
	out->size = size;
	/* what: printable, NUL-terminated */
	size_t n = 0;
	for (; n < sizeof(out->what) - 1 && h->what[n]; n++)
		out->what[n] = h->what[n] >= 0x20 && h->what[n] < 0x7f ? h->what[n] : '?';
	out->what[n] = '\0';
	return 0;
}

/* The samples, read from the pipe into a new memfd (out->fd), which is
 * then sealed and mapped read-only (out->data). */
static int receive_samples(struct sandbox *sb, struct scan_shown *out)
{
	out->fd = memfd_create("spindle-scan", MFD_CLOEXEC | MFD_ALLOW_SEALING);
	if (out->fd < 0 || ftruncate(out->fd, (off_t)out->size) < 0)
		return -errno;
	void *map = mmap(NULL, out->size, PROT_READ | PROT_WRITE, MAP_SHARED, out->fd, 0);
	if (map == MAP_FAILED)
		return -errno;
	prefault_write(map, out->size); /* written whole below */
	int ret = sandbox_read(sb, map, out->size);
	munmap(map, out->size);
	if (ret < 0)
		return ret;
	if (fcntl(out->fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL) < 0)
		return -errno;
	map = mmap(NULL, out->size, PROT_READ, MAP_SHARED, out->fd, 0);
	if (map == MAP_FAILED)
		return -errno;
	out->data = map;
	return 0;
}

/* The whole message and the end of the pipe: 0 (*text set for an error
 * message), -ETIMEDOUT, -EPIPE (cut short), -EPROTO (malformed: why
 * filled), -ENOMEM or -errno. */
static int receive(struct sandbox *sb, struct scan_wire_header *h, struct scan_shown *out, char **text, char *why,
		   size_t why_size)
{
	int ret = sandbox_read(sb, h, sizeof(*h));
	if (ret < 0)
		return ret;
	if (h->magic != SCAN_WIRE_MAGIC) {
		snprintf(why, why_size, "bad magic 0x%08x", h->magic);
		return -EPROTO;
	}
	if (h->status != 0) {
		if (h->text_len > SCAN_WIRE_MAX_TEXT) {
			snprintf(why, why_size, "a bad error header");
			return -EPROTO;
		}
		*text = calloc(1, h->text_len + 1);
		if (!*text)
			return -ENOMEM;
		ret = sandbox_read(sb, *text, h->text_len);
	} else {
		ret = check_header(h, out, why, why_size);
		if (ret == 0)
			ret = receive_samples(sb, out);
	}
	return ret < 0 ? ret : sandbox_read_end(sb, why, why_size);
}

/* "PATH: reason", unless the reason names path already (the readers'
 * messages start with it, or with PATH/ for a file of a directory). */
static void name_file(const char *path, const char *reason, char *err, size_t err_size)
{
	size_t n = strlen(path);
	if (!strncmp(reason, path, n) && (reason[n] == ':' || reason[n] == '/'))
		snprintf(err, err_size, "%s", reason);
	else
		snprintf(err, err_size, "%s: %s", path, reason);
}

static int run_loader(struct scan_files *files, const struct scan_raw *raw, struct scan_shown *out, char *err,
		      size_t err_size)
{
	struct model_confine c;
	struct sandbox sb = { .name = "scan loader", .path = files->path, .timeout_ms = SCAN_LOADER_TIMEOUT_MS };
	struct scan_wire_header h = { 0 };
	char why[256] = "", reason[1100] = "", *text = NULL;

	model_confine_prepare(&c);
	c.cpu_s = SCAN_LOADER_CPU_S;
	c.memory = SCAN_LOADER_MEMORY;
#ifdef SPINDLE_MODEL_TEST_HOOKS
	model_test_limits(&sb.timeout_ms, &c);
#endif
	sb.cpu_s = c.cpu_s;
	struct scan_child child = { .files = files,
				    .raw = raw,
				    .confine = &c,
				    .fds = calloc(files->count, sizeof(int)) };
	int ret = child.fds ? sandbox_start(&sb, child_main, &child) : -ENOMEM;
	free(child.fds);
	if (ret < 0) {
		snprintf(reason, sizeof(reason), "cannot start the scan loader: %s", strerror(-ret));
		name_file(files->path, reason, err, err_size);
		return ret;
	}
	fcntl(sb.rfd, F_SETPIPE_SZ, 1 << 20); /* fewer, larger reads; a smaller pipe works too */
	int rx = receive(&sb, &h, out, &text, why, sizeof(why));
	sandbox_reap(&sb, rx < 0 && rx != -EPIPE);
	ret = sandbox_failure(&sb, rx, why, reason, sizeof(reason));
	if (ret == 0 && h.status != 0) {
		model_wire_error_text((const uint8_t *)text, h.text_len, reason, sizeof(reason));
		ret = -model_wire_error_errno(h.status);
	}
	free(text);
	if (ret < 0)
		name_file(files->path, reason, err, err_size);
	return ret;
}

int scan_load(const char *path, const struct scan_raw *raw, struct scan_shown *out, char *err, size_t err_size)
{
	struct scan_files files;
	memset(out, 0, sizeof(*out));
	out->fd = -1;
	int ret = scan_open(path, raw, &files, err, err_size);
	if (ret == 0 && files.count == 0) {
		struct scan s; /* an empty directory: nothing to parse, the reader's refusal */
		ret = scan_read_files(&files, raw, &s, err, err_size);
		scan_free(&s);
		ret = ret < 0 ? ret : -ENODATA;
	} else if (ret == 0) {
		ret = run_loader(&files, raw, out, err, err_size);
	}
	scan_close(&files);
	if (ret < 0) {
		scan_shown_free(out);
		out->fd = -1;
	}
	return ret;
}

void scan_load_set_progress(FILE *f)
{
	sandbox_set_progress(f);
}

void scan_shown_free(struct scan_shown *s)
{
	if (s->data)
		munmap((void *)s->data, s->size);
	if (s->fd >= 0)
		close(s->fd);
	memset(s, 0, sizeof(*s));
	s->fd = -1;
}
