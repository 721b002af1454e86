/* Medical and scientific volumes read from files: a 3-D grid of scalars or
 * RGBA8, its voxel spacing, and where it lies in patient space.
 *
 * Three sources (docs/volumes.md, "Reading scans"): a NIfTI-1 or NIfTI-2
 * file (.nii, or .nii.gz through zlib; scan_nifti.c, libnifti2), a directory
 * holding one DICOM series (scan_dicom.cpp, GDCM), or a raw file whose
 * layout the caller gives (scan.c). Every file is untrusted input: sizes are
 * checked against the limits below and against what the file holds before
 * anything that size is allocated, a file that holds less than its header
 * says is an error, never a partial volume, and every message names the
 * file. GDCM, though, aborts the process on some malformed DICOM files
 * (its assert()s): read untrusted directories in a sandboxed child
 * (docs/volumes.md, "Untrusted files and the libraries"), as spindlectl
 * does (tools/scan_loader.h): the files are opened first, with the
 * caller's rights (scan_open()), and read from their fds where nothing
 * may be opened (scan_read_files()).
 *
 * Stored values are rescaled as the file says (NIfTI's scl_slope and
 * scl_inter, DICOM's Rescale Slope and Intercept): the result is int16 when
 * the slope is 1, the intercept a whole number and every value still fits,
 * float32 otherwise; an identity rescale keeps the stored type. */
#ifndef SPINDLE_TOOLS_SCAN_H
#define SPINDLE_TOOLS_SCAN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Limits: at most SCAN_MAX_VOXELS voxels (2^31) and SCAN_MAX_DIM (4096) per axis. */
#define SCAN_MAX_VOXELS (UINT64_C(1) << 31)
#define SCAN_MAX_DIM 4096u

enum scan_type { SCAN_U8 = 1, SCAN_U16 = 2, SCAN_I16 = 3, SCAN_F32 = 4, SCAN_RGBA8 = 5 };

/* The layout of a raw file: dims[0] * dims[1] * dims[2] voxels of type, i
 * fastest, starting offset bytes into the file, in big- or little-endian
 * byte order. The volume gets a plain spacing diagonal as its to_ras. */
struct scan_raw {
	uint32_t dims[3];
	enum scan_type type;
	double spacing[3];
	bool big_endian;
	uint64_t offset;
};

struct scan {
	enum scan_type type;
	uint32_t dims[3];  /* i (fastest in data), j, k */
	double spacing[3]; /* mm between voxel centres along i, j, k (> 0, finite) */
	double to_ras[16]; /* column-major 4x4: voxel (i, j, k, 1) -> RAS+ mm (x right, y anterior, z superior) */
	void *data;        /* dims[0]*dims[1]*dims[2] voxels, i fastest, host endian */
	size_t size;       /* bytes of data */
	char what[160];    /* for messages, e.g. "NIfTI-1 256x256x128 int16, 0.9x0.9x2.5 mm" */
};

/* A DICOM directory: at most SCAN_MAX_FILES files (slices, and a few
 * others such as a DICOMDIR) holding at most SCAN_MAX_FILE_BYTES. */
#define SCAN_MAX_FILES (SCAN_MAX_DIM + 64u)
#define SCAN_MAX_FILE_BYTES (UINT64_C(8) << 30)

enum scan_kind { SCAN_KIND_NIFTI = 1, SCAN_KIND_DICOM = 2, SCAN_KIND_RAW = 3 };

/* One file of a scan, open for reading. */
struct scan_input {
	char *path;    /* for messages: the file, or DIR/NAME for a slice */
	int fd;        /* open for reading; -1 once closed */
	uint64_t size; /* its size when it was opened */
};

/* The files of a scan, opened by scan_open(). */
struct scan_files {
	enum scan_kind kind;
	const char *path;          /* as given to scan_open() (not a copy) */
	struct scan_input *inputs; /* one, or a directory's files */
	size_t count;
	uint64_t bytes; /* their sizes added */
};

/* Opens what path holds, with the caller's rights: the file of a raw
 * volume (raw not NULL), a .nii or .nii.gz file, or a directory's regular
 * files (symbolic links followed) whose names do not start with '.',
 * sorted by name; only regular files, never a FIFO or a device. Raises
 * RLIMIT_NOFILE's soft limit to the hard one when a directory needs it.
 * 0, or -errno with a message naming path: the errors of open(2), -EINVAL
 * (not a scan: a file not named .nii or .nii.gz without raw, or not a
 * regular file), -E2BIG (a directory over the limits above), -EMFILE. On
 * failure *out is zeroed and nothing is left open. */
int scan_open(const char *path, const struct scan_raw *raw, struct scan_files *out, char *err, size_t err_size);
/* Reads the scan from the fds of files, opening nothing (the readers run
 * where open() fails), and closes them (the fds become -1). raw is the
 * layout of a SCAN_KIND_RAW file. Returns as scan_read(). */
int scan_read_files(struct scan_files *files, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size);
/* Closes what is still open of files, frees its inputs and zeroes it. */
void scan_close(struct scan_files *files);

/* Reads path: a .nii or .nii.gz file (NIfTI-1 or -2), a directory holding
 * one DICOM series, or, when raw is not NULL, a raw file laid out as raw
 * says (scan_open(), then scan_read_files()). Returns 0, or -errno with a
 * message that names the file in err
 * (NUL-terminated, cut to err_size bytes; err may be NULL): the errors of
 * open(2) and read(2) (-ENOENT, -EACCES, -EIO), -EINVAL for a bad or
 * unsupported file, -E2BIG for a volume over the limits, -ENOMEM. On
 * failure *out is zeroed. */
int scan_read(const char *path, const struct scan_raw *raw, struct scan *out, char *err, size_t err_size);
/* Frees s's data and zeroes it; s may be zeroed already. */
void scan_free(struct scan *s);

/* Bytes per voxel of type (0 for an unknown type). */
size_t scan_type_size(enum scan_type type);
/* "uint8", "uint16", "int16", "float32", "RGBA8" ("unknown"). */
const char *scan_type_name(enum scan_type type);
/* Where voxel (i, j, k) lies: to_ras applied to it, in mm. */
void scan_voxel_to_ras(const struct scan *s, double i, double j, double k, double ras[3]);

#ifdef __cplusplus
}
#endif

#endif
