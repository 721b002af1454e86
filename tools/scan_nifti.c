/* NIfTI-1 and NIfTI-2 files (.nii, .nii.gz) for scan.h. libnifti2 decodes
 * the header (nifti_convert_n1hdr2nim() and _n2hdr2nim(): the byte order,
 * the dimensions, the qform's quaternion and the sform as matrices); the
 * file itself is read here through zlib, which reads an uncompressed file
 * as it is. Only single-file NIfTI (magic "n+1" or "n+2") is read: the
 * .img of a header pair is never opened (nor anything else: the file
 * comes open, scan_open() opened it), and header extensions are
 * skipped, not parsed. The voxel data is read into a buffer that grows
 * with what the file holds, so a header that claims more than the file
 * has costs no more memory than the file, and is an error. */
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <nifti2_io.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "scan_priv.h"

#define HEADER_MAX 540          /* sizeof(nifti_2_header) */
#define FIRST_CHUNK (64u << 20) /* the buffer's first size for compressed data */

/* Reads up to len bytes; *got says how many (fewer at the end). 0, or
 * -EINVAL for a corrupt compressed stream, -EIO for a read error. */
static int read_some(gzFile z, void *buf, size_t len, size_t *got, const char *path, char *err, size_t err_size)
{
	*got = 0;
	while (*got < len) {
		size_t left = len - *got;
		int n = gzread(z, (uint8_t *)buf + *got, left < (1u << 30) ? (unsigned)left : (1u << 30));
		if (n < 0) {
			int zerr;
			const char *why = gzerror(z, &zerr);
			return scan_fail(err, err_size, zerr == Z_ERRNO ? -EIO : -EINVAL, path, "%s",
					 zerr == Z_ERRNO ? strerror(errno) : why);
		}
		if (n == 0)
			break;
		*got += (size_t)n;
	}
	return 0;
}

/* The single-file magic ("n+1" at byte 344, "n+2" at byte 4), which
 * libnifti2 takes from the file name rather than the header. */
static int check_magic(const uint8_t *buf, int version, const char *path, char *err, size_t err_size)
{
	const char *magic = (const char *)buf + (version == 2 ? 4 : 344);
	const char *want = version == 2 ? "n+2" : "n+1", *pair = version == 2 ? "ni2" : "ni1";
	if (!memcmp(magic, want, 4))
		return 0;
	if (!memcmp(magic, pair, 4))
		return scan_fail(err, err_size, -EINVAL, path,
				 "a NIfTI header of a .hdr/.img pair: only single-file NIfTI (.nii, .nii.gz) is read");
	return scan_fail(err, err_size, -EINVAL, path, "no NIfTI magic (an Analyze 7.5 header?): not read");
}

static int stored_type(int datatype, enum scan_stored *stored, const char *path, char *err, size_t err_size)
{
	static const struct {
		int datatype;
		enum scan_stored stored;
	} map[] = {
		{ DT_UINT8, SCAN_STORED_U8 },      { DT_INT8, SCAN_STORED_I8 },     { DT_UINT16, SCAN_STORED_U16 },
		{ DT_INT16, SCAN_STORED_I16 },     { DT_UINT32, SCAN_STORED_U32 },  { DT_INT32, SCAN_STORED_I32 },
		{ DT_FLOAT32, SCAN_STORED_F32 },   { DT_FLOAT64, SCAN_STORED_F64 }, { DT_RGB24, SCAN_STORED_RGB24 },
		{ DT_RGBA32, SCAN_STORED_RGBA32 },
	};
	for (size_t n = 0; n < sizeof(map) / sizeof(map[0]); n++)
		if (map[n].datatype == datatype) {
			*stored = map[n].stored;
			return 0;
		}
	return scan_fail(err, err_size, -EINVAL, path,
			 "voxels of type %s (NIfTI datatype %d) are not read: (u)int8, (u)int16, (u)int32, float32, "
			 "float64, RGB24 and RGBA32 are",
			 nifti_datatype_to_string(datatype), datatype);
}

/* The signed integer of width bytes at off, in the header's byte order. */
static int64_t field(const uint8_t *buf, size_t off, size_t width, bool swapped)
{
	uint8_t b[8];
	int16_t v16;
	int64_t v64;
	memcpy(b, buf + off, width);
	if (swapped)
		scan_swap_bytes(b, 1, width);
	if (width == 2) {
		memcpy(&v16, b, 2);
		return v16;
	}
	memcpy(&v64, b, 8);
	return v64;
}

/* What libnifti2 takes for granted when it decodes a header (with more
 * than 7 dimensions it writes past its arrays; of others it complains on
 * stderr): 1 to 7 dimensions, each at least 1, and a datatype this reader
 * takes. Checked here on the header's bytes, first. */
static int check_raw_header(const uint8_t *buf, int version, const char *path, char *err, size_t err_size)
{
	int32_t sizeof_hdr;
	memcpy(&sizeof_hdr, buf, 4);
	bool swapped = sizeof_hdr != (version == 2 ? 540 : 348);
	size_t dim = version == 2 ? 16 : 40, width = version == 2 ? 8 : 2;
	int64_t count = field(buf, dim, width, swapped);
	if (count < 1 || count > 7)
		return scan_fail(err, err_size, -EINVAL, path, "a header of %" PRId64 " dimensions", count);
	for (int d = 1; d <= count; d++) {
		int64_t v = field(buf, dim + (size_t)d * width, width, swapped);
		if (v < 1)
			return scan_fail(err, err_size, -EINVAL, path, "dimension %d is %" PRId64, d, v);
	}
	enum scan_stored stored;
	return stored_type((int)field(buf, version == 2 ? 12 : 70, 2, swapped), &stored, path, err, err_size);
}

/* The header, decoded by libnifti2 (NULL when it refuses it). */
static nifti_image *decode_header(const uint8_t *buf, int version, const char *path)
{
	if (version == 2) {
		nifti_2_header h;
		memcpy(&h, buf, sizeof(h));
		return nifti_convert_n2hdr2nim(h, path);
	}
	nifti_1_header h;
	memcpy(&h, buf, sizeof(h));
	return nifti_convert_n1hdr2nim(h, path);
}

/* Reads and decodes the header; *nim is set on success. */
static int read_header(gzFile z, const char *path, nifti_image **nim, int *version, char *err, size_t err_size)
{
	uint8_t buf[HEADER_MAX];
	size_t n;
	int ret = read_some(z, buf, sizeof(buf), &n, path, err, err_size);
	if (ret != 0)
		return ret;
	if (n < sizeof(nifti_1_header))
		return scan_fail(err, err_size, -EINVAL, path, "%zu bytes: too short for a NIfTI header", n);
	*version = nifti_header_version((const char *)buf, n);
	if (*version == 0)
		return scan_fail(err, err_size, -EINVAL, path, "an Analyze 7.5 header (no NIfTI magic): not read");
	if (*version != 1 && *version != 2)
		return scan_fail(err, err_size, -EINVAL, path, "not a NIfTI file (no NIfTI-1 or -2 header)");
	if (n < (*version == 2 ? sizeof(nifti_2_header) : sizeof(nifti_1_header)))
		return scan_fail(err, err_size, -EINVAL, path, "%zu bytes: too short for a NIfTI-%d header", n,
				 *version);
	ret = check_magic(buf, *version, path, err, err_size);
	if (ret == 0)
		ret = check_raw_header(buf, *version, path, err, err_size);
	if (ret != 0)
		return ret;
	*nim = decode_header(buf, *version, path);
	if (!*nim)
		return scan_fail(err, err_size, -EINVAL, path, "a NIfTI-%d header that libnifti2 refuses", *version);
	return 0;
}

/* 3-D only, each size within scan.h's limits; dims gets them. */
static int check_dims(const nifti_image *nim, uint32_t dims[3], const char *path, char *err, size_t err_size)
{
	for (int d = 4; d <= 7; d++)
		if (nim->dim[d] > 1)
			return scan_fail(err, err_size, -EINVAL, path,
					 "dimension %d is %" PRId64
					 ": only 3-D volumes are read (one volume of a series: "
					 "split it first)",
					 d, (int64_t)nim->dim[d]);
	for (int d = 1; d <= 3; d++) {
		int64_t v = nim->dim[d];
		if (v < 1 || v > SCAN_MAX_DIM)
			return scan_fail(err, err_size, v < 1 ? -EINVAL : -E2BIG, path,
					 "dimension %d is %" PRId64 ": 1 to %u are read", d, v, SCAN_MAX_DIM);
		dims[d - 1] = (uint32_t)v;
	}
	uint64_t voxels;
	return scan_check_dims(path, dims, &voxels, err, err_size);
}

/* For an uncompressed file (of have bytes), whether it holds the voxels
 * its header says, checked before they are allocated. */
static int check_file_size(gzFile z, uint64_t have, const char *path, uint64_t offset, uint64_t bytes, char *err,
			   size_t err_size)
{
	if (!gzdirect(z))
		return 0;
	if (offset > have || have - offset < bytes)
		return scan_fail(err, err_size, -EINVAL, path,
				 "holds %" PRIu64 " bytes; its header says %" PRIu64
				 " bytes of voxels from offset %" PRIu64,
				 have, bytes, offset);
	return 0;
}

/* Reads bytes of voxels into a buffer that grows as they come. */
static int read_voxels(gzFile z, uint64_t bytes, void **out, const char *path, char *err, size_t err_size)
{
	size_t cap = gzdirect(z) || bytes < FIRST_CHUNK ? (size_t)bytes : FIRST_CHUNK, have = 0, n = 1;
	/* Uncompressed, the file holds the bytes (check_file_size()): read whole. */
	uint8_t *buf = gzdirect(z) ? scan_samples_alloc(cap) : malloc(cap ? cap : 1);
	int ret = buf ? 0 : scan_fail(err, err_size, -ENOMEM, path, "out of memory for %zu bytes", cap);
	while (ret == 0 && have < bytes && n > 0) {
		if (have == cap) {
			cap = bytes - cap < cap ? (size_t)bytes : 2 * cap;
			uint8_t *p = realloc(buf, cap);
			if (!p) {
				ret = scan_fail(err, err_size, -ENOMEM, path, "out of memory for %zu bytes", cap);
				break;
			}
			buf = p;
		}
		ret = read_some(z, buf + have, cap - have, &n, path, err, err_size);
		have += n;
	}
	if (ret == 0 && have < bytes)
		ret = scan_fail(err, err_size, -EINVAL, path,
				"holds %zu bytes of voxels; its header says %" PRIu64
				" (truncated, or the header lies)",
				have, bytes);
	if (ret != 0)
		free(buf);
	*out = ret == 0 ? buf : NULL;
	return ret;
}

/* Millimetres per unit of the file's xyz_units (unknown: mm). */
static double unit_mm(int xyz_units)
{
	switch (XYZT_TO_SPACE(xyz_units)) {
	case NIFTI_UNITS_METER:
		return 1000;
	case NIFTI_UNITS_MICRON:
		return 1e-3;
	default:
		return 1;
	}
}

/* m's upper 3x4, scaled by mm, as a column-major 4x4; false if it is not
 * finite or singular. */
static bool take_affine(const nifti_dmat44 *m, double mm, double to_ras[16])
{
	for (int c = 0; c < 4; c++)
		for (int r = 0; r < 4; r++)
			to_ras[4 * c + r] = r < 3 ? m->m[r][c] * mm : (c == 3);
	for (int n = 0; n < 16; n++)
		if (!isfinite(to_ras[n]))
			return false;
	double det = to_ras[0] * (to_ras[5] * to_ras[10] - to_ras[9] * to_ras[6]) -
		     to_ras[4] * (to_ras[1] * to_ras[10] - to_ras[9] * to_ras[2]) +
		     to_ras[8] * (to_ras[1] * to_ras[6] - to_ras[5] * to_ras[2]);
	return det != 0;
}

/* to_ras from the sform (sform_code > 0), else the qform, else a spacing
 * diagonal; spacing from its columns. Returns which it used. */
static const char *orientation(const nifti_image *nim, struct scan *s)
{
	double mm = unit_mm(nim->xyz_units);
	const char *how = "no orientation";
	if (nim->sform_code > 0 && take_affine(&nim->sto_xyz, mm, s->to_ras))
		how = "sform";
	else if (nim->qform_code > 0 && take_affine(&nim->qto_xyz, mm, s->to_ras))
		how = "qform";
	if (!strcmp(how, "no orientation")) {
		s->spacing[0] = fabs(nim->dx) * mm;
		s->spacing[1] = fabs(nim->dy) * mm;
		s->spacing[2] = fabs(nim->dz) * mm;
		scan_set_diagonal(s);
		return how;
	}
	for (int c = 0; c < 3; c++)
		s->spacing[c] = sqrt(s->to_ras[4 * c] * s->to_ras[4 * c] + s->to_ras[4 * c + 1] * s->to_ras[4 * c + 1] +
				     s->to_ras[4 * c + 2] * s->to_ras[4 * c + 2]);
	return how;
}

/* The header's checks, and the voxels read (host order) into *buf. */
static int read_image(gzFile z, const struct scan_input *in, const nifti_image *nim, struct scan *out,
		      enum scan_stored *stored, void **buf, char *err, size_t err_size)
{
	const char *path = in->path;
	int ret = check_dims(nim, out->dims, path, err, err_size);
	if (ret == 0)
		ret = stored_type(nim->datatype, stored, path, err, err_size);
	if (ret == 0 && (size_t)nim->nbyper != scan_stored_size(*stored))
		ret = scan_fail(err, err_size, -EINVAL, path, "%d bytes per voxel of NIfTI datatype %d", nim->nbyper,
				nim->datatype);
	if (ret != 0)
		return ret;
	uint64_t bytes = (uint64_t)out->dims[0] * out->dims[1] * out->dims[2] * scan_stored_size(*stored);
	int64_t offset = nim->iname_offset;
	if (offset < (int64_t)sizeof(nifti_1_header) || offset > INT32_MAX)
		return scan_fail(err, err_size, -EINVAL, path, "a voxel offset of %" PRId64, offset);
	ret = check_file_size(z, in->size, path, (uint64_t)offset, bytes, err, err_size);
	if (ret == 0 && gzseek(z, (z_off_t)offset, SEEK_SET) != (z_off_t)offset)
		ret = scan_fail(err, err_size, -EINVAL, path, "ends before its voxels (offset %" PRId64 ")", offset);
	if (ret == 0)
		ret = read_voxels(z, bytes, buf, path, err, err_size);
	if (ret == 0 && nim->byteorder != nifti_short_order() && nim->swapsize > 1)
		scan_swap_bytes(*buf, bytes / (size_t)nim->swapsize, (size_t)nim->swapsize);
	return ret;
}

/* The volume from the decoded header and the open file. */
static int read_volume(gzFile z, const struct scan_input *in, const nifti_image *nim, int version, struct scan *out,
		       char *err, size_t err_size)
{
	const char *path = in->path;
	enum scan_stored stored = SCAN_STORED_U8;
	void *buf = NULL;
	int ret = read_image(z, in, nim, out, &stored, &buf, err, err_size);
	if (ret != 0)
		return ret;
	const char *how = orientation(nim, out);
	struct scan_rescale r = { nim->scl_slope, nim->scl_inter };
	bool scaled = r.slope != 0 && isfinite(r.slope) && isfinite(r.inter);
	ret = scan_finish(out, stored, buf, &r, scaled ? 1 : 0, path, err, err_size);
	if (ret == 0)
		scan_describe(out, version == 2 ? "NIfTI-2" : "NIfTI-1", how);
	return ret;
}

int scan_read_nifti(struct scan_input *in, struct scan *out, char *err, size_t err_size)
{
	nifti_image *nim = NULL;
	int version = 0;
	nifti_set_debug_level(0);
	errno = 0;
	gzFile z = gzdopen(in->fd, "rb");
	if (!z)
		return scan_fail(err, err_size, errno ? -errno : -ENOMEM, in->path, "%s",
				 errno ? strerror(errno) : "out of memory");
	in->fd = -1; /* zlib's now: gzclose() closes it */
	int ret = read_header(z, in->path, &nim, &version, err, err_size);
	if (ret == 0)
		ret = read_volume(z, in, nim, version, out, err, err_size);
	if (nim)
		nifti_image_free(nim);
	gzclose(z);
	return ret;
}
