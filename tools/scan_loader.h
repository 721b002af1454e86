/* Scans read for spindlectl show (docs/volumes.md, "spindlectl show of a
 * scan"), as models are (model_sandbox.h): the files are opened here with
 * the caller's rights (scan_open()), and read by a forked child that
 * confines itself first (model_confine.c: nobody when started as root,
 * no_new_privs, CPU and memory limits, a seccomp filter that allows
 * reading those fds and writing the result pipe, nothing opened). A
 * reader that crashes (GDCM's assert()s abort on some malformed DICOM),
 * hangs or sends a malformed result is an error naming the file, never a
 * crash of the caller.
 *
 * The child sends a checked header and the samples already in the
 * display's layout (scan_display.h: the parent computes the same layout
 * from the header and checks the rest against scan.h's limits before
 * allocating anything), which the parent reads straight into a memfd,
 * sealed then against shrinking, growing and writing, ready for
 * spindle_buffer_create_from_fd(): no copy of the samples in the parent.
 *
 * The message on the pipe, in host byte order (both ends are the same
 * program):
 *
 *   struct scan_wire_header
 *   status != 0: text_len bytes of a reason (not NUL-terminated)
 *   status == 0: data_size bytes: the samples in the order that
 *                scan_layout_of() gives for the header's dims, spacing
 *                and to_ras (display x fastest)
 *
 * and then the end of the pipe. */
#ifndef SPINDLE_TOOLS_SCAN_LOADER_H
#define SPINDLE_TOOLS_SCAN_LOADER_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "scan.h"
#include "scan_display.h"

/* The loader's limits: wall time, CPU time and memory (on top of what the
 * process had mapped when it forked: the largest scan, 2^31 float64
 * voxels read and converted in place, takes 16 GiB). */
#define SCAN_LOADER_TIMEOUT_MS 120000
#define SCAN_LOADER_CPU_S 60
#define SCAN_LOADER_MEMORY (20ull << 30)

#define SCAN_WIRE_MAGIC 0x4e435353u /* "SSCN" */
#define SCAN_WIRE_MAX_TEXT 1024u

struct scan_wire_header {
	uint32_t magic;
	uint32_t status;   /* 0, or an errno value */
	uint32_t text_len; /* status != 0: the reason's bytes */
	uint32_t type;     /* enum scan_type */
	uint32_t dims[3];  /* as read: i, j, k */
	uint32_t reserved; /* 0 */
	double spacing[3];
	double to_ras[16];
	uint64_t data_size;
	char what[160]; /* struct scan's, NUL-terminated */
};

/* A scan read and laid out for the display. */
struct scan_shown {
	enum scan_type type;
	struct scan_layout layout; /* dims and spacing along display x, y, z */
	uint32_t dims[3];          /* as read (i, j, k) */
	double to_ras[16];
	char what[160];   /* what the reader said it read, printable */
	int fd;           /* a sealed memfd of the samples in the layout's order */
	uint64_t size;    /* their bytes */
	const void *data; /* fd, mapped read-only */
};

/* Reads the scan at path (a .nii or .nii.gz file, a DICOM directory, or
 * with raw a raw file) in the sandboxed loader. 0, or -errno with a
 * one-line message naming the file in err ("DIR: the scan loader crashed
 * (signal 6)"): the errors of scan_open() (-ENOENT, ...), the readers'
 * (-EINVAL, -E2BIG, -ENODATA, -ENOMEM), -EINVAL for a loader that crashed,
 * timed out or sent a malformed result, -EPERM when it could not give up
 * its privileges. */
int scan_load(const char *path, const struct scan_raw *raw, struct scan_shown *out, char *err, size_t err_size);
/* Where a load that takes over a second says that it goes on (a line
 * every 2 s), or NULL: silent (the default). */
void scan_load_set_progress(FILE *f);
/* Unmaps and closes; accepts what a failed scan_load() left. */
void scan_shown_free(struct scan_shown *s);

#endif
