/* Fuzz target "scan-nifti": NIfTI files read by scan_read() (tools/scan.h,
 * tools/scan_nifti.c: libnifti2 decodes the header, zlib reads the file,
 * compressed or not, the voxels are rescaled and converted). libnifti2 and
 * zlib are system libraries, not instrumented. Checks: no memory error,
 * leak, hang or undefined behaviour; an accepted file gives a volume that
 * passes scan.h's checks (scan_read() makes them), whose every byte can be
 * read, with a description; a refused one leaves the result zeroed and a
 * message naming the file; no fd left open.
 *
 * Input: the file's bytes, read as FILE.nii (gzip data is read as a
 * .nii.gz is). fuzz/gen_scan_corpus.py writes the seeds. */
#include <stdio.h>
#include <string.h>

#include "harness.h"
#include "scan.h"
#include "scan_file.h"

/* Every byte of the volume, read: ASan checks the buffer is all there. */
static unsigned touch(const struct scan *s)
{
	const uint8_t *p = s->data;
	unsigned sum = 0;
	for (size_t n = 0; n < s->size; n++)
		sum += p[n];
	return sum;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_resources before;
	struct scan s;
	char err[512];
	const char *path = fuzz_scan_file("input.nii", data, size);
	if (!path)
		return 0;
	fuzz_resources_take(&before);
	int ret = scan_read(path, NULL, &s, err, sizeof(err));
	if (ret == 0) {
		unsigned sum = touch(&s);
		if (!s.what[0] || s.size != (size_t)s.dims[0] * s.dims[1] * s.dims[2] * scan_type_size(s.type))
			fuzz_fail("a volume without a description or with the wrong size");
		if (fuzz_verbose())
			fprintf(stderr, "read: %s (sum %u)\n", s.what, sum);
		scan_free(&s);
	} else {
		if (s.data || s.size || !strstr(err, path))
			fuzz_fail("a refusal (%d) that left data or did not name the file: %s", ret, err);
		if (fuzz_verbose())
			fprintf(stderr, "refused: %s\n", err);
	}
	fuzz_resources_check(&before);
	return 0;
}
