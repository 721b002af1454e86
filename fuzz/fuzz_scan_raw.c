/* Fuzz target "scan-raw": raw files with the layout the input gives, read
 * by scan_read() (tools/scan.c). Checks: no memory error, leak or
 * undefined behaviour; the reader accepts exactly the layouts that are
 * valid and that the file holds (a model of the rules of scan.h: a known
 * type, every size 1 to 4096 and at most 2^31 voxels, finite spacings
 * > 0, the voxels within the file), and then gives the file's bytes from
 * the offset, swapped to host order when their byte order differs; no fd
 * left open.
 *
 * Input: dims[3] as fuzz_num(), type: u8, spacing[3]: u8 each (0: 0,
 * 254: infinity, 255: NaN, else v / 16 mm), flags: u8 (bit 0: big-endian),
 * offset: fuzz_num64(), then the file's bytes. fuzz/gen_scan_corpus.py
 * writes the seeds. */
#include <errno.h>
#include <math.h>
#include <string.h>

#include "harness.h"
#include "scan.h"
#include "scan_file.h"

static double spacing_of(uint8_t v)
{
	return v == 255 ? NAN : v == 254 ? INFINITY : v / 16.0;
}

/* Whether raw is a valid layout for a file of size bytes. */
static bool valid(const struct scan_raw *raw, size_t size)
{
	size_t per = scan_type_size(raw->type);
	uint64_t voxels = 1;
	if (per == 0)
		return false;
	for (int a = 0; a < 3; a++) {
		if (raw->dims[a] < 1 || raw->dims[a] > SCAN_MAX_DIM ||
		    !(raw->spacing[a] > 0 && isfinite(raw->spacing[a])))
			return false;
		voxels *= raw->dims[a];
	}
	return voxels <= SCAN_MAX_VOXELS && raw->offset <= size && size - raw->offset >= voxels * per;
}

/* The volume holds the file's bytes, in host order. */
static void check_data(const struct scan *s, const struct scan_raw *raw, const uint8_t *file)
{
	size_t per = scan_type_size(raw->type);
	bool swap = per > 1 && raw->type != SCAN_RGBA8 && raw->big_endian != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__);
	const uint8_t *got = s->data, *want = file + raw->offset;
	if (s->type != raw->type || s->size != (size_t)raw->dims[0] * raw->dims[1] * raw->dims[2] * per)
		fuzz_fail("type %d and size %zu, not %d", (int)s->type, s->size, (int)raw->type);
	for (size_t n = 0; n < s->size; n++)
		if (got[n] != want[swap ? n - n % per + (per - 1 - n % per) : n])
			fuzz_fail("byte %zu differs from the file's", n);
	for (int a = 0; a < 3; a++)
		if (s->spacing[a] != raw->spacing[a] || s->to_ras[5 * a] != raw->spacing[a])
			fuzz_fail("spacing %d differs", a);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_input in = { .data = data, .size = size };
	struct fuzz_resources before;
	struct scan_raw raw = { 0 };
	struct scan s;
	char err[512];
	for (int a = 0; a < 3; a++)
		raw.dims[a] = fuzz_num(&in);
	raw.type = (enum scan_type)fuzz_u8(&in);
	for (int a = 0; a < 3; a++)
		raw.spacing[a] = spacing_of(fuzz_u8(&in));
	raw.big_endian = fuzz_u8(&in) & 1;
	raw.offset = fuzz_num64(&in);
	size_t n;
	const uint8_t *file = fuzz_bytes(&in, size, &n);
	const char *path = fuzz_scan_file("input.raw", file, n);
	if (!path)
		return 0;
	fuzz_resources_take(&before);
	int ret = scan_read(path, &raw, &s, err, sizeof(err));
	if ((ret == 0) != valid(&raw, n))
		fuzz_fail("scan_read() gave %d (%s) for a layout that is %s", ret, err, ret ? "valid" : "not");
	if (ret == 0)
		check_data(&s, &raw, file);
	else if (ret != -EINVAL && ret != -E2BIG)
		fuzz_fail("scan_read() gave %d: %s", ret, err);
	scan_free(&s);
	fuzz_resources_check(&before);
	return 0;
}
