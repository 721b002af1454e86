/* Reading scans (scan.h): scan_read() picks the reader by what the path
 * is, the raw reader, and the checks that every reader's result passes. */
#include "scan.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "prefault.h"
#include "scan_priv.h"

int scan_fail(char *err, size_t err_size, int code, const char *path, const char *fmt, ...)
{
	if (!err || err_size == 0)
		return code;
	int n = snprintf(err, err_size, "%s: ", path ? path : "(null)");
	if (n >= 0 && (size_t)n < err_size) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(err + n, err_size - (size_t)n, fmt, ap);
		va_end(ap);
	}
	return code;
}

size_t scan_type_size(enum scan_type type)
{
	switch (type) {
	case SCAN_U8:
		return 1;
	case SCAN_U16:
	case SCAN_I16:
		return 2;
	case SCAN_F32:
	case SCAN_RGBA8:
		return 4;
	}
	return 0;
}

const char *scan_type_name(enum scan_type type)
{
	switch (type) {
	case SCAN_U8:
		return "uint8";
	case SCAN_U16:
		return "uint16";
	case SCAN_I16:
		return "int16";
	case SCAN_F32:
		return "float32";
	case SCAN_RGBA8:
		return "RGBA8";
	}
	return "unknown";
}

void scan_voxel_to_ras(const struct scan *s, double i, double j, double k, double ras[3])
{
	for (int r = 0; r < 3; r++)
		ras[r] = s->to_ras[r] * i + s->to_ras[4 + r] * j + s->to_ras[8 + r] * k + s->to_ras[12 + r];
}

void scan_free(struct scan *s)
{
	free(s->data);
	memset(s, 0, sizeof(*s));
}

int scan_check_dims(const char *path, const uint32_t dims[3], uint64_t *voxels, char *err, size_t err_size)
{
	if (dims[0] == 0 || dims[1] == 0 || dims[2] == 0)
		return scan_fail(err, err_size, -EINVAL, path, "a volume of %" PRIu32 "x%" PRIu32 "x%" PRIu32 " voxels",
				 dims[0], dims[1], dims[2]);
	if (dims[0] > SCAN_MAX_DIM || dims[1] > SCAN_MAX_DIM || dims[2] > SCAN_MAX_DIM)
		return scan_fail(err, err_size, -E2BIG, path,
				 "%" PRIu32 "x%" PRIu32 "x%" PRIu32 " voxels: over %u along an axis", dims[0], dims[1],
				 dims[2], SCAN_MAX_DIM);
	/* Each factor is at most 2^12, so the product fits in 36 bits. */
	*voxels = (uint64_t)dims[0] * dims[1] * dims[2];
	if (*voxels > SCAN_MAX_VOXELS)
		return scan_fail(err, err_size, -E2BIG, path,
				 "%" PRIu32 "x%" PRIu32 "x%" PRIu32 " voxels: over 2^31 in all", dims[0], dims[1],
				 dims[2]);
	return 0;
}

int scan_check_spacing(const char *path, const double spacing[3], char *err, size_t err_size)
{
	for (int a = 0; a < 3; a++)
		if (!(isfinite(spacing[a]) && spacing[a] > 0))
			return scan_fail(err, err_size, -EINVAL, path, "voxel spacing %g x %g x %g mm: not > 0",
					 spacing[0], spacing[1], spacing[2]);
	return 0;
}

/* The determinant of to_ras's upper 3x3 (columns i, j, k). */
static double det3(const double *m)
{
	return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
	       m[8] * (m[1] * m[6] - m[5] * m[2]);
}

static bool ras_ok(const struct scan *s)
{
	for (int n = 0; n < 16; n++)
		if (!isfinite(s->to_ras[n]))
			return false;
	if (s->to_ras[3] != 0 || s->to_ras[7] != 0 || s->to_ras[11] != 0 || s->to_ras[15] != 1)
		return false;
	/* Not singular: relative to the product of the column lengths. */
	return fabs(det3(s->to_ras)) > 1e-6 * s->spacing[0] * s->spacing[1] * s->spacing[2];
}

int scan_check_geometry(const struct scan *s, const char *path, char *err, size_t err_size)
{
	uint64_t voxels;
	if (scan_type_size(s->type) == 0)
		return scan_fail(err, err_size, -EINVAL, path, "unknown voxel type %d", (int)s->type);
	int ret = scan_check_dims(path, s->dims, &voxels, err, err_size);
	if (ret == 0)
		ret = scan_check_spacing(path, s->spacing, err, err_size);
	if (ret == 0 && !ras_ok(s))
		ret = scan_fail(err, err_size, -EINVAL, path,
				"the voxel to patient transform is not finite or is singular");
	return ret;
}

int scan_check(const struct scan *s, const char *path, char *err, size_t err_size)
{
	int ret = scan_check_geometry(s, path, err, err_size);
	if (ret != 0)
		return ret;
	size_t bytes = (size_t)s->dims[0] * s->dims[1] * s->dims[2] * scan_type_size(s->type);
	if (!s->data || s->size != bytes)
		return scan_fail(err, err_size, -EINVAL, path, "a volume without the data its size says");
	return 0;
}

void scan_set_diagonal(struct scan *s)
{
	memset(s->to_ras, 0, sizeof(s->to_ras));
	s->to_ras[0] = s->spacing[0];
	s->to_ras[5] = s->spacing[1];
	s->to_ras[10] = s->spacing[2];
	s->to_ras[15] = 1;
}

void scan_describe(struct scan *s, const char *format, const char *extra)
{
	snprintf(s->what, sizeof(s->what), "%s %" PRIu32 "x%" PRIu32 "x%" PRIu32 " %s, %.4gx%.4gx%.4g mm%s%s", format,
		 s->dims[0], s->dims[1], s->dims[2], scan_type_name(s->type), s->spacing[0], s->spacing[1],
		 s->spacing[2], extra ? ", " : "", extra ? extra : "");
}

/* ---- raw files ---- */

static enum scan_stored raw_stored(enum scan_type type)
{
	switch (type) {
	case SCAN_U8:
		return SCAN_STORED_U8;
	case SCAN_U16:
		return SCAN_STORED_U16;
	case SCAN_I16:
		return SCAN_STORED_I16;
	case SCAN_F32:
		return SCAN_STORED_F32;
	case SCAN_RGBA8:
		break;
	}
	return SCAN_STORED_RGBA32;
}

/* Reads exactly len bytes at offset: 0, -errno, or -EINVAL for a file that
 * ended first (it shrank since it was measured). */
static int pread_all(int fd, void *buf, size_t len, uint64_t offset)
{
	uint8_t *p = buf;
	while (len > 0) {
		size_t chunk = len < (1u << 30) ? len : (1u << 30);
		ssize_t n = pread(fd, p, chunk, (off_t)offset);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0)
			return -errno;
		if (n == 0)
			return -EINVAL;
		p += n;
		len -= (size_t)n;
		offset += (uint64_t)n;
	}
	return 0;
}

/* The layout's own checks, and that the file holds the bytes it needs. */
static int raw_check(const struct scan_input *in, const struct scan_raw *raw, size_t *size, char *err, size_t err_size)
{
	uint64_t voxels;
	size_t per = scan_type_size(raw->type);
	if (per == 0)
		return scan_fail(err, err_size, -EINVAL, in->path, "unknown voxel type %d", (int)raw->type);
	int ret = scan_check_dims(in->path, raw->dims, &voxels, err, err_size);
	if (ret == 0)
		ret = scan_check_spacing(in->path, raw->spacing, err, err_size);
	if (ret != 0)
		return ret;
	*size = (size_t)(voxels * per);
	if (raw->offset > in->size || in->size - raw->offset < *size)
		return scan_fail(err, err_size, -EINVAL, in->path,
				 "holds %" PRIu64 " bytes; %" PRIu32 "x%" PRIu32 "x%" PRIu32
				 " %s voxels need %zu from offset %" PRIu64,
				 in->size, raw->dims[0], raw->dims[1], raw->dims[2], scan_type_name(raw->type), *size,
				 raw->offset);
	return 0;
}

void *scan_samples_alloc(size_t size)
{
	void *p = malloc(size ? size : 1);
	if (p)
		prefault_write(p, size);
	return p;
}

int scan_read_raw(const struct scan_input *in, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size)
{
	size_t size = 0;
	int ret = raw_check(in, raw, &size, err, err_size);
	void *buf = ret == 0 ? scan_samples_alloc(size) : NULL;
	if (ret == 0 && !buf)
		ret = scan_fail(err, err_size, -ENOMEM, in->path, "out of memory for %zu bytes", size);
	if (ret == 0 && (ret = pread_all(in->fd, buf, size, raw->offset)) != 0)
		scan_fail(err, err_size, ret, in->path, "%s", ret == -EINVAL ? "the file ended early" : strerror(-ret));
	if (ret != 0) {
		free(buf);
		return ret;
	}
	size_t per = scan_type_size(raw->type);
	if (per > 1 && raw->type != SCAN_RGBA8 && raw->big_endian != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__))
		scan_swap_bytes(buf, size / per, per);
	memcpy(out->dims, raw->dims, sizeof(out->dims));
	memcpy(out->spacing, raw->spacing, sizeof(out->spacing));
	scan_set_diagonal(out);
	ret = scan_finish(out, raw_stored(raw->type), buf, NULL, 0, in->path, err, err_size);
	if (ret == 0)
		scan_describe(out, "raw", raw->big_endian ? "big-endian" : NULL);
	return ret;
}

/* ---- opening ---- */

static bool ends_with(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

/* name (under dir when dir_fd is not AT_FDCWD) opened for reading: a
 * regular file only, so that a FIFO or a device cannot block. 0 with
 * *fd and *size, 1 for a file that is not regular, or -errno. */
static int open_regular(int dir_fd, const char *name, int *fd, uint64_t *size)
{
	struct stat st;
	*fd = openat(dir_fd, name, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
	if (*fd < 0)
		return -errno;
	int ret = fstat(*fd, &st) != 0 ? -errno : S_ISREG(st.st_mode) ? 0 : 1;
	if (ret != 0) {
		close(*fd);
		*fd = -1;
		return ret;
	}
	*size = (uint64_t)st.st_size;
	return 0;
}

static int compare_names(const void *a, const void *b)
{
	return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The names of dir's regular files not starting with '.', sorted: at
 * most SCAN_MAX_FILES. */
static int list_dir(int dir_fd, const char *path, char ***names, size_t *count, char *err, size_t err_size)
{
	int fd = dup(dir_fd);
	DIR *d = fd < 0 ? NULL : fdopendir(fd);
	if (!d) {
		int e = errno;
		if (fd >= 0)
			close(fd);
		return scan_fail(err, err_size, -e, path, "%s", strerror(e));
	}
	int ret = 0;
	*names = calloc(SCAN_MAX_FILES + 1, sizeof(**names));
	*count = 0;
	if (!*names)
		ret = scan_fail(err, err_size, -ENOMEM, path, "out of memory");
	for (struct dirent *e; ret == 0 && (e = readdir(d));) {
		struct stat st;
		if (e->d_name[0] == '.' || fstatat(dir_fd, e->d_name, &st, 0) != 0 || !S_ISREG(st.st_mode))
			continue;
		if (*count == SCAN_MAX_FILES)
			ret = scan_fail(err, err_size, -E2BIG, path,
					"more than %u files: not read as one DICOM series (at most %u slices)",
					SCAN_MAX_FILES, SCAN_MAX_DIM);
		else if (!((*names)[(*count)++] = strdup(e->d_name)))
			ret = scan_fail(err, err_size, -ENOMEM, path, "out of memory");
	}
	closedir(d);
	if (ret == 0)
		qsort(*names, *count, sizeof(**names), compare_names);
	return ret;
}

/* Room for count more fds: RLIMIT_NOFILE's soft limit raised as far as the
 * hard one when it is short. */
static void make_room_for_fds(size_t count)
{
	struct rlimit rl;
	rlim_t want = (rlim_t)count * 2 + 64; /* the loader copies them once */
	if (getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur >= want)
		return;
	rl.rlim_cur = rl.rlim_max == RLIM_INFINITY || rl.rlim_max > want ? want : rl.rlim_max;
	setrlimit(RLIMIT_NOFILE, &rl);
}

static int add_input(struct scan_files *f, const char *dir, const char *name, int fd, uint64_t size)
{
	struct scan_input *in = &f->inputs[f->count];
	size_t len = strlen(dir) + 1 + strlen(name) + 1;
	in->path = malloc(len);
	if (!in->path)
		return -ENOMEM;
	size_t d = strlen(dir);
	snprintf(in->path, len, "%s%s%s", dir, d > 0 && dir[d - 1] == '/' ? "" : "/", name);
	in->fd = fd;
	in->size = size;
	f->count++;
	f->bytes += size;
	return 0;
}

/* Every listed file opened, within SCAN_MAX_FILE_BYTES. */
static int open_dir_files(int dir_fd, const char *path, char **names, size_t count, struct scan_files *f, char *err,
			  size_t err_size)
{
	make_room_for_fds(count);
	f->inputs = calloc(count ? count : 1, sizeof(*f->inputs));
	if (!f->inputs)
		return scan_fail(err, err_size, -ENOMEM, path, "out of memory");
	for (size_t n = 0; n < count; n++) {
		int fd;
		uint64_t size = 0;
		int ret = open_regular(dir_fd, names[n], &fd, &size);
		if (ret == 1)
			continue; /* replaced since it was listed */
		if (ret == -EMFILE || ret == -ENFILE)
			return scan_fail(err, err_size, ret, path, "%zu files: more than this process may open at once",
					 count);
		if (ret < 0)
			return scan_fail(err, err_size, ret, path, "%s: %s", names[n], strerror(-ret));
		if (size > SCAN_MAX_FILE_BYTES - f->bytes) {
			close(fd);
			return scan_fail(err, err_size, -E2BIG, path,
					 "its files hold more than %" PRIu64 " GiB: not read as one DICOM series",
					 SCAN_MAX_FILE_BYTES >> 30);
		}
		if (add_input(f, path, names[n], fd, size) < 0) {
			close(fd);
			return scan_fail(err, err_size, -ENOMEM, path, "out of memory");
		}
	}
	return 0;
}

static int open_dir(const char *path, struct scan_files *f, char *err, size_t err_size)
{
	char **names = NULL;
	size_t count = 0;
	int dir_fd = open(path, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
	if (dir_fd < 0)
		return scan_fail(err, err_size, -errno, path, "%s", strerror(errno));
	int ret = list_dir(dir_fd, path, &names, &count, err, err_size);
	if (ret == 0)
		ret = open_dir_files(dir_fd, path, names, count, f, err, err_size);
	for (size_t n = 0; names && n < count; n++)
		free(names[n]);
	free(names);
	close(dir_fd);
	return ret;
}

static int open_file(const char *path, struct scan_files *f, char *err, size_t err_size)
{
	int fd;
	uint64_t size = 0;
	int ret = open_regular(AT_FDCWD, path, &fd, &size);
	if (ret != 0)
		return scan_fail(err, err_size, ret < 0 ? ret : -EINVAL, path, "%s",
				 ret < 0 ? strerror(-ret) : "not a regular file");
	f->inputs = calloc(1, sizeof(*f->inputs));
	if (f->inputs)
		f->inputs[0].path = strdup(path);
	if (!f->inputs || !f->inputs[0].path) {
		close(fd);
		return scan_fail(err, err_size, -ENOMEM, path, "out of memory");
	}
	f->inputs[0].fd = fd;
	f->inputs[0].size = size;
	f->count = 1;
	f->bytes = size;
	return 0;
}

static int open_by_kind(const char *path, const struct scan_raw *raw, struct scan_files *f, char *err, size_t err_size)
{
	struct stat st;
	if (raw) {
		f->kind = SCAN_KIND_RAW;
		return open_file(path, f, err, err_size);
	}
	if (stat(path, &st) != 0)
		return scan_fail(err, err_size, -errno, path, "%s", strerror(errno));
	if (S_ISDIR(st.st_mode)) {
		f->kind = SCAN_KIND_DICOM;
		return open_dir(path, f, err, err_size);
	}
	if (ends_with(path, ".nii") || ends_with(path, ".nii.gz")) {
		f->kind = SCAN_KIND_NIFTI;
		return open_file(path, f, err, err_size);
	}
	return scan_fail(err, err_size, -EINVAL, path,
			 "not a .nii or .nii.gz file or a DICOM directory (a raw file needs its layout)");
}

int scan_open(const char *path, const struct scan_raw *raw, struct scan_files *out, char *err, size_t err_size)
{
	memset(out, 0, sizeof(*out));
	if (err && err_size > 0)
		err[0] = '\0';
	if (!path)
		return scan_fail(err, err_size, -EINVAL, path, "no path");
	out->path = path;
	int ret = open_by_kind(path, raw, out, err, err_size);
	if (ret != 0)
		scan_close(out);
	return ret;
}

void scan_close(struct scan_files *files)
{
	for (size_t n = 0; files->inputs && n < files->count; n++) {
		if (files->inputs[n].fd >= 0)
			close(files->inputs[n].fd);
		free(files->inputs[n].path);
	}
	free(files->inputs);
	memset(files, 0, sizeof(*files));
}

/* ---- reading ---- */

static int read_by_kind(struct scan_files *f, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size)
{
	switch (f->kind) {
	case SCAN_KIND_RAW:
		if (!raw || f->count != 1)
			break;
		return scan_read_raw(&f->inputs[0], raw, out, err, err_size);
	case SCAN_KIND_NIFTI:
		if (f->count != 1)
			break;
		return scan_read_nifti(&f->inputs[0], out, err, err_size);
	case SCAN_KIND_DICOM:
		return scan_read_dicom(f->path, f->inputs, f->count, out, err, err_size);
	}
	return scan_fail(err, err_size, -EINVAL, f->path, "no files to read");
}

int scan_read_files(struct scan_files *files, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size)
{
	memset(out, 0, sizeof(*out));
	if (err && err_size > 0)
		err[0] = '\0';
	int ret = read_by_kind(files, raw, out, err, err_size);
	if (ret == 0)
		ret = scan_check(out, files->path, err, err_size);
	if (ret != 0)
		scan_free(out);
	for (size_t n = 0; n < files->count; n++) {
		if (files->inputs[n].fd >= 0)
			close(files->inputs[n].fd);
		files->inputs[n].fd = -1;
	}
	return ret;
}

int scan_read(const char *path, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size)
{
	struct scan_files files;
	memset(out, 0, sizeof(*out));
	int ret = scan_open(path, raw, &files, err, err_size);
	if (ret == 0)
		ret = scan_read_files(&files, raw, out, err, err_size);
	scan_close(&files);
	return ret;
}
