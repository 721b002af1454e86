/* What the scan readers share (scan.h): messages, the checks of a layout
 * before anything is allocated, and scan_finish(), which turns the voxels
 * as a file stores them into those of a struct scan (rescaled, converted to
 * the nearest type scan.h has). C, also included by scan_dicom.cpp. */
#ifndef SPINDLE_TOOLS_SCAN_PRIV_H
#define SPINDLE_TOOLS_SCAN_PRIV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "scan.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Voxels as files store them (host byte order once read). */
enum scan_stored {
	SCAN_STORED_U8,
	SCAN_STORED_I8,
	SCAN_STORED_U16,
	SCAN_STORED_I16,
	SCAN_STORED_U32,
	SCAN_STORED_I32,
	SCAN_STORED_F32,
	SCAN_STORED_F64,
	SCAN_STORED_RGB24,
	SCAN_STORED_RGBA32,
};

/* value = stored * slope + inter, for one slice or for all. */
struct scan_rescale {
	double slope, inter;
};

/* Writes "PATH: message" into err (when err is not NULL) and returns code. */
int scan_fail(char *err, size_t err_size, int code, const char *path, const char *fmt, ...)
	__attribute__((format(printf, 5, 6)));

/* Bytes per stored voxel. */
size_t scan_stored_size(enum scan_stored stored);

/* Checks dims (each 1 to SCAN_MAX_DIM, at most SCAN_MAX_VOXELS in all)
 * and gives the voxel count. 0, -EINVAL (a zero dimension) or -E2BIG. */
int scan_check_dims(const char *path, const uint32_t dims[3], uint64_t *voxels, char *err, size_t err_size);
/* Checks that every spacing is finite and > 0. 0 or -EINVAL. */
int scan_check_spacing(const char *path, const double spacing[3], char *err, size_t err_size);
/* The checks every result passes (scan_read() makes them): dims, spacing,
 * a finite, invertible to_ras with (0, 0, 0, 1) as its last row, and data
 * of the size dims and type give. 0 or -EINVAL. */
int scan_check(const struct scan *s, const char *path, char *err, size_t err_size);
/* The same but for the data: a known type, dims, spacing, to_ras. */
int scan_check_geometry(const struct scan *s, const char *path, char *err, size_t err_size);

/* Reverses the bytes of count units of width bytes (2, 4 or 8). */
void scan_swap_bytes(void *data, size_t count, size_t width);

/* size bytes (at least 1) for samples about to be read into them whole,
 * their pages made present at once (prefault.h); NULL when out of
 * memory. Free with free(). */
void *scan_samples_alloc(size_t size);
/* to_ras := diag(spacing[0], spacing[1], spacing[2], 1). */
void scan_set_diagonal(struct scan *s);
/* s->what := "FORMAT WxHxD TYPE, SXxSYxSZ mm" and then extra (may be NULL). */
void scan_describe(struct scan *s, const char *format, const char *extra);

/* Takes buf (malloc'd: s->dims voxels of stored, i fastest, host order)
 * and makes it s->data, rescaled by r: count entries, 1 for the whole
 * volume or one per slice (s->dims[2]). RGB stored types ignore r and
 * become RGBA8. Integer voxels with slope 1 and whole intercepts become
 * int16 when every value fits, the stored type when r is the identity and
 * the type is one of scan.h's (int8 becomes int16; 32-bit integers the
 * smallest of int16, uint16 and float32 that holds their range); anything
 * else becomes float32. buf is freed (or owned by s) whatever the result.
 * 0, -ENOMEM or -EINVAL (a bad rescale: slope 0 or not finite). */
int scan_finish(struct scan *s, enum scan_stored stored, void *buf, const struct scan_rescale *r, uint32_t count,
		const char *path, char *err, size_t err_size);

/* The readers, called by scan_read_files() (scan.c) with out zeroed, on
 * open files: they read their fds (pread, or read and lseek), and nothing
 * else of the file system. Each fills in everything but leaves the final
 * checks to scan_read_files(). The NIfTI reader closes its fd (zlib's
 * gzclose() does); the others leave them to their caller. */
int scan_read_raw(const struct scan_input *in, const struct scan_raw *raw, struct scan *out, char *err,
		  size_t err_size);
int scan_read_nifti(struct scan_input *in, struct scan *out, char *err, size_t err_size);
/* dir for messages; its files, sorted by name. */
int scan_read_dicom(const char *dir, const struct scan_input *files, size_t count, struct scan *out, char *err,
		    size_t err_size);

#ifdef __cplusplus
}
#endif

#endif
