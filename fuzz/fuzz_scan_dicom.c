/* Fuzz target "scan-dicom": one DICOM file through the per-file reading of
 * a series (tools/scan_dicom.cpp: GDCM reads the tags up to the pixel
 * data, which are checked; then GDCM reads the image and its pixels are
 * taken). GDCM is a system library, not instrumented. Checks: no memory
 * error, leak, hang or undefined behaviour, and no exception out of the
 * reader; an accepted slice keeps the rules of scan_dicom.h (sizes,
 * positive spacing, unit orthogonal orientation, finite position and
 * rescale, a NUL-terminated series UID); its pixels, read into a buffer of
 * exactly their size, stay within Bits Stored; no fd left open.
 *
 * Input: the file's bytes. fuzz/gen_scan_corpus.py writes the seeds. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "scan_dicom.h"
#include "scan_file.h"

#define MAX_PIXELS (1u << 20)

static double dot(const double *a, const double *b)
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void check_slice(const struct scan_dicom_slice *s)
{
	const double *o = s->orientation;
	if (s->rows < 1 || s->rows > SCAN_MAX_DIM || s->columns < 1 || s->columns > SCAN_MAX_DIM)
		fuzz_fail("%u rows, %u columns", s->rows, s->columns);
	if (!(s->pixel_spacing[0] > 0 && s->pixel_spacing[1] > 0 && isfinite(s->pixel_spacing[0]) &&
	      isfinite(s->pixel_spacing[1])))
		fuzz_fail("pixel spacing %g, %g", s->pixel_spacing[0], s->pixel_spacing[1]);
	if (fabs(dot(o, o) - 1) > 1e-9 || fabs(dot(o + 3, o + 3) - 1) > 1e-9 || fabs(dot(o, o + 3)) > 1e-3)
		fuzz_fail("an orientation that is not two orthogonal unit vectors");
	if (!isfinite(dot(s->position, s->position)) || !isfinite(s->rescale.slope) || s->rescale.slope == 0 ||
	    !isfinite(s->rescale.inter))
		fuzz_fail("a position or rescale that is not finite");
	if (!memchr(s->series, 0, sizeof(s->series)) || !s->series[0])
		fuzz_fail("no series UID");
	if ((s->bits_allocated != 8 && s->bits_allocated != 16) || s->bits_stored < 1 ||
	    s->bits_stored > s->bits_allocated)
		fuzz_fail("%u bits stored of %u", s->bits_stored, s->bits_allocated);
}

/* Every pixel within the range of Bits Stored. */
static void check_pixels(const struct scan_dicom_slice *s, const void *buf, size_t n)
{
	enum scan_stored stored = scan_dicom_stored(s);
	int64_t lo = s->is_signed ? -(INT64_C(1) << (s->bits_stored - 1)) : 0;
	int64_t hi = s->is_signed ? (INT64_C(1) << (s->bits_stored - 1)) - 1 : (INT64_C(1) << s->bits_stored) - 1;
	for (size_t i = 0; i < n; i++) {
		int64_t v = stored == SCAN_STORED_U8    ? ((const uint8_t *)buf)[i]
			    : stored == SCAN_STORED_U16 ? ((const uint16_t *)buf)[i]
							: ((const int16_t *)buf)[i];
		if (v < lo || v > hi)
			fuzz_fail("pixel %zu is %lld, outside %u bits stored", i, (long long)v, s->bits_stored);
	}
}

static void read_pixels(const char *path, const struct scan_dicom_slice *s)
{
	size_t n = (size_t)s->rows * s->columns;
	char err[512];
	if (n > MAX_PIXELS)
		return;
	void *buf = malloc(n * scan_stored_size(scan_dicom_stored(s)));
	if (!buf)
		return;
	if (scan_dicom_read_pixels(path, s, buf, err, sizeof(err)) == 0)
		check_pixels(s, buf, n);
	else if (fuzz_verbose())
		fprintf(stderr, "pixels refused: %s\n", err);
	free(buf);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_resources before;
	struct scan_dicom_slice s;
	char err[512];
	const char *path = fuzz_scan_file("input.dcm", data, size);
	if (!path)
		return 0;
	fuzz_resources_take(&before);
	int ret = scan_dicom_read_slice(path, &s, err, sizeof(err));
	if (ret == 0) {
		check_slice(&s);
		read_pixels(path, &s);
	} else if (ret < 0 && !strstr(err, path)) {
		fuzz_fail("a refusal (%d) that does not name the file: %s", ret, err);
	} else if (fuzz_verbose()) {
		fprintf(stderr, "refused (%d): %s\n", ret, err);
	}
	fuzz_resources_check(&before);
	return 0;
}
