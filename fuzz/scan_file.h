/* The scan targets' input as a file (tools/scan.h reads paths, and
 * libnifti2 and GDCM open files by name): written to a file of the given
 * name in a directory of this process's own under $TMPDIR (or /tmp),
 * created at the first call and removed at exit. */
#ifndef SPINDLE_FUZZ_SCAN_FILE_H
#define SPINDLE_FUZZ_SCAN_FILE_H

#include <stddef.h>

/* Writes data to NAME (a plain file name, one of at most 8 names) and
 * returns its path, or NULL when that failed. */
const char *fuzz_scan_file(const char *name, const void *data, size_t size);

#endif
