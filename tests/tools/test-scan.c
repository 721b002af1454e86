/* Reading scans (tools/scan.h) on the 3-D Shepp-Logan phantom that
 * scripts/make-phantom writes at test time: NIfTI-1 (.nii, int16 with an
 * sform), .nii.gz (uint16 rescaled by scl_inter, qform only) and a DICOM
 * series made by dcmtk's dump2dcm (shuffled file names, mixed transfer
 * syntaxes, tilted slices, uint16 with Rescale Intercept) give the same
 * dims, spacing, voxels and voxel-to-RAS mapping, the one the phantom's
 * geometry says; every voxel holds the phantom's analytic value. Then the
 * refusals: truncated and lying files, mixed series, a missing slice, an
 * empty directory, short raw files, and NIfTI files written here for the
 * type conversions and rescales.
 *
 * argv: python3, scripts/make-phantom, a scratch directory. Skipped (77)
 * when dcmtk's dump2dcm is missing (scripts/install-deps installs it). */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include "check.h"
#include "scan.h"
#include "scan_dicom.h"

/* nifti1.h's DT_UNKNOWN (a datatype) would clash with dirent.h's. */
#undef DT_UNKNOWN
#include <nifti1.h>
#include <nifti2.h>

extern char **environ;

/* The phantom's size and geometry (make-phantom's options). */
static const uint32_t DIMS[3] = { 48, 40, 32 };
static const double SPACING[3] = { 0.8, 0.9, 2.0 };
#define TILT_DEG 12.0

static char work[4096];

static const char *at(const char *name)
{
	static char paths[8][4352];
	static int next;
	char *p = paths[next++ % 8];
	snprintf(p, sizeof(paths[0]), "%s/%s", work, name);
	return p;
}

/* Runs argv, stdout into out_path (when not NULL); its exit status. */
static int run(char *const argv[], const char *out_path)
{
	posix_spawn_file_actions_t fa;
	pid_t pid;
	int status;
	posix_spawn_file_actions_init(&fa);
	if (out_path)
		posix_spawn_file_actions_addopen(&fa, 1, out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
	int ret = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
	posix_spawn_file_actions_destroy(&fa);
	CHECK_MSG(ret == 0, "spawn %s: %s", argv[0], strerror(ret));
	CHECK(waitpid(pid, &status, 0) == pid);
	return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

static bool in_path(const char *tool)
{
	char *path = strdup(getenv("PATH") ? getenv("PATH") : "/usr/bin:/bin"), *save = NULL;
	bool found = false;
	for (char *dir = strtok_r(path, ":", &save); dir && !found; dir = strtok_r(NULL, ":", &save)) {
		char p[4096];
		snprintf(p, sizeof(p), "%s/%s", dir, tool);
		found = access(p, X_OK) == 0;
	}
	free(path);
	return found;
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
	return remove(path);
}

static void remove_tree(const char *path)
{
	nftw(path, remove_one, 16, FTW_DEPTH | FTW_PHYS);
}

static void write_file(const char *path, const void *data, size_t len)
{
	FILE *f = fopen(path, "wb");
	CHECK(f);
	CHECK(len == 0 || fwrite(data, 1, len, f) == len);
	CHECK(fclose(f) == 0);
}

/* The first limit bytes of src (all of it when limit is SIZE_MAX). */
static void copy_file(const char *src, const char *dst, size_t limit)
{
	FILE *f = fopen(src, "rb");
	CHECK(f);
	static char buf[1 << 20];
	size_t n = fread(buf, 1, sizeof(buf), f);
	CHECK(n < sizeof(buf) && !ferror(f));
	fclose(f);
	write_file(dst, buf, n < limit ? n : limit);
}

/* Copies the files of src into a new dst, but the one named skip. */
static void copy_dir(const char *src, const char *dst, const char *skip)
{
	CHECK(mkdir(dst, 0755) == 0);
	DIR *d = opendir(src);
	CHECK(d);
	for (struct dirent *e; (e = readdir(d));) {
		if (e->d_name[0] == '.' || (skip && !strcmp(e->d_name, skip)))
			continue;
		char a[8192], b[8192];
		snprintf(a, sizeof(a), "%s/%s", src, e->d_name);
		snprintf(b, sizeof(b), "%s/%s", dst, e->d_name);
		copy_file(a, b, SIZE_MAX);
	}
	closedir(d);
}

/* scan_read() fails with code and a message naming path. */
static void expect_error(const char *path, const struct scan_raw *raw, int code)
{
	struct scan s;
	char err[1024];
	memset(&s, 0x5a, sizeof(s));
	int ret = scan_read(path, raw, &s, err, sizeof(err));
	CHECK_MSG(ret == code, "%s: %d (%s), not %d", path, ret, err, code);
	CHECK_MSG(strstr(err, path) != NULL, "the message does not name %s: %s", path, err);
	CHECK(s.data == NULL && s.size == 0 && s.dims[0] == 0);
	printf("refused as it should: %s\n", err);
}

static void read_ok(const char *path, const struct scan_raw *raw, struct scan *s)
{
	char err[1024];
	int ret = scan_read(path, raw, s, err, sizeof(err));
	CHECK_MSG(ret == 0, "%s: %d: %s", path, ret, err);
	printf("read %s: %s\n", path, s->what);
}

/* ---- the phantom ---- */

struct ellipsoid {
	double x0, y0, z0, a, b, c, phi, value;
};

struct table {
	double radius, axes[3], base;
	struct ellipsoid e[16];
	int count;
};

static void read_table(const char *path, struct table *t)
{
	FILE *f = fopen(path, "r");
	char line[512];
	CHECK(f);
	memset(t, 0, sizeof(*t));
	while (fgets(line, sizeof(line), f)) {
		struct ellipsoid *e = &t->e[t->count];
		if (sscanf(line, "radius %lf", &t->radius) == 1 || sscanf(line, "base %lf", &t->base) == 1)
			continue;
		if (sscanf(line, "axes %lf %lf %lf", &t->axes[0], &t->axes[1], &t->axes[2]) == 3)
			continue;
		if (sscanf(line, "ellipsoid %lf %lf %lf %lf %lf %lf %lf %lf", &e->x0, &e->y0, &e->z0, &e->a, &e->b,
			   &e->c, &e->phi, &e->value) == 8) {
			CHECK(++t->count < 16);
		}
	}
	fclose(f);
	CHECK(t->count == 10 && t->radius > 0 && t->base == -1000);
}

/* The ellipsoid's quadric at p: <= 1 inside. */
static double quadric(const struct ellipsoid *e, const double p[3])
{
	double cs = cos(e->phi * M_PI / 180), sn = sin(e->phi * M_PI / 180);
	double dx = p[0] - e->x0, dy = p[1] - e->y0, dz = p[2] - e->z0;
	double x = dx * cs + dy * sn, y = -dx * sn + dy * cs;
	return x * x / (e->a * e->a) + y * y / (e->b * e->b) + dz * dz / (e->c * e->c);
}

/* The phantom's value at voxel v; false when the voxel's centre lies on
 * an ellipsoid's surface, where rounding may go either way. */
static bool analytic(const struct table *t, const uint32_t v[3], double *value, uint32_t *inside)
{
	double p[3];
	for (int a = 0; a < 3; a++)
		p[a] = t->axes[a] * (v[a] - (DIMS[a] - 1) / 2.0) * SPACING[a] / t->radius;
	*value = t->base;
	for (int n = 0; n < t->count; n++) {
		double q = quadric(&t->e[n], p);
		if (fabs(q - 1) < 1e-9)
			return false;
		if (q <= 1) {
			*value += t->e[n].value;
			inside[n]++;
		}
	}
	return true;
}

static void check_analytic(const struct scan *s, const struct table *t)
{
	uint32_t v[3], inside[16] = { 0 }, checked = 0;
	const int16_t *d = s->data;
	for (v[2] = 0; v[2] < DIMS[2]; v[2]++)
		for (v[1] = 0; v[1] < DIMS[1]; v[1]++)
			for (v[0] = 0; v[0] < DIMS[0]; v[0]++) {
				double want;
				if (!analytic(t, v, &want, inside))
					continue;
				int16_t got = d[((size_t)v[2] * DIMS[1] + v[1]) * DIMS[0] + v[0]];
				CHECK_MSG(got == want, "voxel (%u, %u, %u): %d, the phantom says %g", v[0], v[1], v[2],
					  got, want);
				checked++;
			}
	CHECK(checked > 0.99 * DIMS[0] * DIMS[1] * DIMS[2]);
	/* The big ellipsoids have voxels inside; so does one small one. */
	for (int n = 0; n < 5; n++)
		CHECK_MSG(inside[n] > 0, "no voxel inside ellipsoid %d", n);
	CHECK(inside[8] > 0);
	printf("%u voxels equal the analytic phantom (inside each ellipsoid:", checked);
	for (int n = 0; n < t->count; n++)
		printf(" %u", inside[n]);
	printf(")\n");
}

/* dims, spacing and the geometry make-phantom gives the series: i towards
 * the patient's left, j posterior and k superior tilted by TILT_DEG about
 * the left-right axis, the grid's centre at the origin. */
static void check_geometry(const struct scan *s)
{
	double t = TILT_DEG * M_PI / 180;
	const double want[3][3] = {
		{ -SPACING[0], 0, 0 },
		{ 0, -cos(t) * SPACING[1], sin(t) * SPACING[1] },
		{ 0, sin(t) * SPACING[2], cos(t) * SPACING[2] },
	};
	for (int a = 0; a < 3; a++) {
		CHECK_EQ(s->dims[a], DIMS[a]);
		CHECK_MSG(fabs(s->spacing[a] - SPACING[a]) < 1e-4, "%s: spacing %d: %g", s->what, a, s->spacing[a]);
		for (int r = 0; r < 3; r++)
			CHECK_MSG(fabs(s->to_ras[4 * a + r] - want[a][r]) < 1e-4,
				  "%s: to_ras column %d row %d: %g, not %g", s->what, a, r, s->to_ras[4 * a + r],
				  want[a][r]);
	}
	double centre[3];
	scan_voxel_to_ras(s, (DIMS[0] - 1) / 2.0, (DIMS[1] - 1) / 2.0, (DIMS[2] - 1) / 2.0, centre);
	for (int r = 0; r < 3; r++)
		CHECK_MSG(fabs(centre[r]) < 1e-3, "%s: the centre at %g", s->what, centre[r]);
}

/* The same voxels and the same mapping of the grid's corners. */
static void check_same(const struct scan *a, const struct scan *b)
{
	CHECK(a->type == b->type && a->size == b->size);
	CHECK_MSG(memcmp(a->data, b->data, a->size) == 0, "%s and %s differ in voxels", a->what, b->what);
	for (int c = 0; c < 8; c++) {
		double v[3] = { c & 1 ? DIMS[0] - 1 : 0, c & 2 ? DIMS[1] - 1 : 0, c & 4 ? DIMS[2] - 1 : 0 }, pa[3],
		       pb[3];
		scan_voxel_to_ras(a, v[0], v[1], v[2], pa);
		scan_voxel_to_ras(b, v[0], v[1], v[2], pb);
		for (int r = 0; r < 3; r++)
			CHECK_MSG(fabs(pa[r] - pb[r]) < 1e-3, "corner %d: %g against %g", c, pa[r], pb[r]);
	}
}

static void make_phantom(char **argv)
{
	char size[64], spacing[64], tilt[32];
	snprintf(size, sizeof(size), "%u,%u,%u", DIMS[0], DIMS[1], DIMS[2]);
	snprintf(spacing, sizeof(spacing), "%g,%g,%g", SPACING[0], SPACING[1], SPACING[2]);
	snprintf(tilt, sizeof(tilt), "%g", TILT_DEG);
	static const char *const outputs[][2] = { { "--nii", "p.nii" },
						  { "--nii-gz", "p.nii.gz" },
						  { "--nii2", "p2.nii" },
						  { "--dicom", "dicom" } };
	char *a[32] = {
		argv[1], argv[2], "--size", size, "--spacing", spacing, "--tilt", tilt, "--uid", "a", "--table"
	};
	int n = 11;
	for (size_t i = 0; i < sizeof(outputs) / sizeof(outputs[0]); i++) {
		a[n++] = (char *)outputs[i][0];
		a[n++] = (char *)at(outputs[i][1]);
	}
	CHECK(run(a, at("table.txt")) == 0);
	/* A second series, for the mixed directory. */
	char *b[] = { argv[1], argv[2], "--size", "48,40,2", "--uid", "b", "--dicom", (char *)at("dicom-b"), NULL };
	CHECK(run(b, NULL) == 0);
}

static void check_phantom(void)
{
	struct scan nii, gz, two, dcm;
	struct table t;
	read_table(at("table.txt"), &t);
	read_ok(at("p.nii"), NULL, &nii);
	read_ok(at("p.nii.gz"), NULL, &gz);
	read_ok(at("p2.nii"), NULL, &two);
	read_ok(at("dicom"), NULL, &dcm);
	CHECK(nii.type == SCAN_I16 && gz.type == SCAN_I16 && two.type == SCAN_I16 && dcm.type == SCAN_I16);
	check_geometry(&nii);
	check_geometry(&gz);
	check_geometry(&two);
	check_geometry(&dcm);
	check_same(&nii, &gz);
	check_same(&nii, &two);
	check_same(&nii, &dcm);
	check_analytic(&nii, &t);
	CHECK(strstr(nii.what, "sform") && strstr(gz.what, "qform") && strstr(two.what, "NIfTI-2"));
	scan_free(&nii);
	scan_free(&gz);
	scan_free(&two);
	scan_free(&dcm);
	CHECK(nii.data == NULL);
}

/* ---- refusals ---- */

static void check_bad_nifti(void)
{
	size_t full = 352 + 2u * DIMS[0] * DIMS[1] * DIMS[2];
	copy_file(at("p.nii"), at("truncated.nii"), full / 2);
	expect_error(at("truncated.nii"), NULL, -EINVAL);
	copy_file(at("p.nii"), at("header-only.nii"), 200);
	expect_error(at("header-only.nii"), NULL, -EINVAL);
	/* A header that claims more slices than the file holds. */
	copy_file(at("p.nii"), at("lying.nii"), SIZE_MAX);
	FILE *f = fopen(at("lying.nii"), "r+b");
	int16_t dim3 = 64;
	CHECK(f && fseek(f, 40 + 3 * 2, SEEK_SET) == 0 && fwrite(&dim3, 2, 1, f) == 1 && fclose(f) == 0);
	expect_error(at("lying.nii"), NULL, -EINVAL);
	/* The same, compressed: found only while reading. */
	gzFile z = gzopen(at("lying.nii.gz"), "wb");
	FILE *src = fopen(at("lying.nii"), "rb");
	static char buf[1 << 20];
	size_t n = fread(buf, 1, sizeof(buf), src);
	fclose(src);
	CHECK(z && gzwrite(z, buf, (unsigned)n) == (int)n && gzclose(z) == Z_OK);
	expect_error(at("lying.nii.gz"), NULL, -EINVAL);
	/* A truncated compressed stream. */
	copy_file(at("p.nii.gz"), at("cut.nii.gz"), 700);
	expect_error(at("cut.nii.gz"), NULL, -EINVAL);
	write_file(at("garbage.nii"), "not a NIfTI file at all, just some text", 40);
	expect_error(at("garbage.nii"), NULL, -EINVAL);
	expect_error(at("missing.nii"), NULL, -ENOENT);
	write_file(at("unknown.img"), "x", 1);
	expect_error(at("unknown.img"), NULL, -EINVAL);
}

/* The file of dir whose slice lies in the middle of the series. */
static void middle_slice(const char *dir, char *name, size_t size)
{
	DIR *d = opendir(dir);
	double want = 0;
	CHECK(d);
	for (struct dirent *e; (e = readdir(d));) {
		char p[8192], err[512];
		struct scan_dicom_slice s;
		if (e->d_name[0] == '.')
			continue;
		snprintf(p, sizeof(p), "%s/%s", dir, e->d_name);
		CHECK_MSG(scan_dicom_read_slice(p, &s, err, sizeof(err)) == 0, "%s", err);
		CHECK(s.rows == DIMS[1] && s.columns == DIMS[0] && s.pixel_spacing[0] == SPACING[1]);
		CHECK(s.pixel_spacing[1] == SPACING[0] && s.bits_stored == 12 && !s.is_signed);
		CHECK(s.rescale.slope == 1 && s.rescale.inter == -1024);
		/* Along the normal, the centre slice is nearest 0. */
		double along = -sin(TILT_DEG * M_PI / 180) * s.position[1] + cos(TILT_DEG * M_PI / 180) * s.position[2];
		if (!name[0] || fabs(along - SPACING[2] / 2) < fabs(want - SPACING[2] / 2)) {
			snprintf(name, size, "%s", e->d_name);
			want = along;
		}
	}
	closedir(d);
}

static void check_bad_dicom(void)
{
	char middle[256] = "", a[8192], b[8192];
	middle_slice(at("dicom"), middle, sizeof(middle));
	copy_dir(at("dicom"), at("missing-slice"), middle);
	expect_error(at("missing-slice"), NULL, -EINVAL);
	copy_dir(at("dicom"), at("mixed"), NULL);
	snprintf(a, sizeof(a), "%s/IM0000", at("dicom-b"));
	snprintf(b, sizeof(b), "%s/ZZ-other-series", at("mixed"));
	copy_file(a, b, SIZE_MAX);
	expect_error(at("mixed"), NULL, -EINVAL);
	CHECK(mkdir(at("empty"), 0755) == 0);
	expect_error(at("empty"), NULL, -ENODATA);
	copy_dir(at("dicom"), at("truncated-slice"), NULL);
	snprintf(a, sizeof(a), "%s/%s", at("dicom"), middle);
	snprintf(b, sizeof(b), "%s/%s", at("truncated-slice"), middle);
	copy_file(a, b, 2000);
	expect_error(at("truncated-slice"), NULL, -EINVAL);
	copy_dir(at("dicom"), at("duplicate"), NULL);
	snprintf(b, sizeof(b), "%s/%s-copy", at("duplicate"), middle);
	copy_file(a, b, SIZE_MAX);
	expect_error(at("duplicate"), NULL, -EINVAL);
	copy_dir(at("dicom"), at("not-dicom"), NULL);
	snprintf(b, sizeof(b), "%s/README", at("not-dicom"));
	write_file(b, "notes\n", 6);
	expect_error(at("not-dicom"), NULL, -EINVAL);
	/* One slice: its Slice Thickness is the spacing. */
	CHECK(mkdir(at("one"), 0755) == 0);
	snprintf(b, sizeof(b), "%s/only", at("one"));
	copy_file(a, b, SIZE_MAX);
	struct scan s;
	read_ok(at("one"), NULL, &s);
	CHECK(s.dims[2] == 1 && fabs(s.spacing[2] - SPACING[2]) < 1e-9);
	scan_free(&s);
}

/* ---- raw files ---- */

static void check_raw(void)
{
	const uint8_t be[8] = { 0x01, 0x02, 0x80, 0x00, 0xff, 0xfe, 0x00, 0x07 };
	write_file(at("raw.bin"), be, sizeof(be));
	struct scan_raw r = { .dims = { 2, 2, 1 }, .type = SCAN_U16, .spacing = { 1, 2, 3 }, .big_endian = true };
	struct scan s;
	read_ok(at("raw.bin"), &r, &s);
	const uint16_t *u = s.data;
	CHECK(s.type == SCAN_U16 && u[0] == 0x0102 && u[1] == 0x8000 && u[2] == 0xfffe && u[3] == 7);
	CHECK(s.to_ras[0] == 1 && s.to_ras[5] == 2 && s.to_ras[10] == 3 && s.to_ras[15] == 1 && s.to_ras[12] == 0);
	scan_free(&s);
	r.type = SCAN_I16;
	r.big_endian = false;
	read_ok(at("raw.bin"), &r, &s);
	CHECK(s.type == SCAN_I16 && ((int16_t *)s.data)[1] == 0x0080 && ((int16_t *)s.data)[2] == -257);
	scan_free(&s);
	r = (struct scan_raw){ .dims = { 1, 1, 2 }, .type = SCAN_F32, .spacing = { 1, 1, 1 }, .big_endian = true };
	const uint8_t f[8] = { 0x3f, 0xc0, 0, 0, 0xc1, 0x20, 0, 0 }; /* 1.5, -10 */
	write_file(at("raw-f32.bin"), f, sizeof(f));
	read_ok(at("raw-f32.bin"), &r, &s);
	CHECK(((float *)s.data)[0] == 1.5f && ((float *)s.data)[1] == -10.0f);
	scan_free(&s);
	r = (struct scan_raw){ .dims = { 1, 1, 1 }, .type = SCAN_RGBA8, .spacing = { 1, 1, 1 }, .offset = 4 };
	read_ok(at("raw.bin"), &r, &s);
	CHECK(s.type == SCAN_RGBA8 && !memcmp(s.data, be + 4, 4));
	scan_free(&s);

	r = (struct scan_raw){ .dims = { 2, 2, 2 }, .type = SCAN_U16, .spacing = { 1, 1, 1 } };
	expect_error(at("raw.bin"), &r, -EINVAL); /* 8 bytes, 16 needed */
	r.dims[2] = 1;
	r.offset = 1;
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.offset = UINT64_MAX;
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.offset = 0;
	r.spacing[1] = 0;
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.spacing[1] = NAN;
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.spacing[1] = 1;
	r.dims[0] = 0;
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.dims[0] = 4097;
	expect_error(at("raw.bin"), &r, -E2BIG);
	r.dims[0] = r.dims[1] = r.dims[2] = 2048;
	expect_error(at("raw.bin"), &r, -E2BIG);
	r = (struct scan_raw){ .dims = { 1, 1, 1 }, .type = (enum scan_type)9, .spacing = { 1, 1, 1 } };
	expect_error(at("raw.bin"), &r, -EINVAL);
	r.type = SCAN_U8;
	expect_error(at("dicom"), &r, -EINVAL);
	expect_error(at("no-such-raw"), &r, -ENOENT);
}

/* ---- NIfTI files written here ---- */

/* A NIfTI-1 file (gzipped when path ends in .gz), no orientation. */
static void write_nifti1(const char *path, const int16_t dims[4], int datatype, int bitpix, double slope, double inter,
			 const void *data, size_t len)
{
	nifti_1_header h;
	memset(&h, 0, sizeof(h));
	h.sizeof_hdr = 348;
	h.dim[0] = dims[3] > 1 ? 4 : 3;
	for (int a = 0; a < 4; a++)
		h.dim[a + 1] = dims[a];
	h.datatype = (short)datatype;
	h.bitpix = (short)bitpix;
	h.pixdim[1] = h.pixdim[2] = h.pixdim[3] = 1.5f;
	h.vox_offset = 352;
	h.scl_slope = (float)slope;
	h.scl_inter = (float)inter;
	h.xyzt_units = NIFTI_UNITS_MM;
	memcpy(h.magic, "n+1", 4);
	char ext[4] = { 0 };
	gzFile z = gzopen(path, strstr(path, ".gz") ? "wb" : "wbT");
	CHECK(z && gzwrite(z, &h, sizeof(h)) == sizeof(h) && gzwrite(z, ext, 4) == 4);
	CHECK(gzwrite(z, data, (unsigned)len) == (int)len && gzclose(z) == Z_OK);
}

static void read_nifti(const char *name, const int16_t dims[4], int datatype, int bitpix, double slope, double inter,
		       const void *data, size_t len, struct scan *s)
{
	write_nifti1(at(name), dims, datatype, bitpix, slope, inter, data, len);
	read_ok(at(name), NULL, s);
	CHECK(s->dims[0] == (uint32_t)dims[0] && s->dims[1] == (uint32_t)dims[1] && s->dims[2] == (uint32_t)dims[2]);
	CHECK(s->spacing[0] == 1.5 && s->to_ras[0] == 1.5 && s->to_ras[5] == 1.5 && s->to_ras[10] == 1.5);
}

static void check_nifti_types(void)
{
	const int16_t dims[4] = { 2, 2, 1, 1 };
	struct scan s;
	const int8_t i8[4] = { -128, -1, 0, 127 };
	read_nifti("i8.nii", dims, DT_INT8, 8, 0, 0, i8, sizeof(i8), &s);
	CHECK(s.type == SCAN_I16 && ((int16_t *)s.data)[0] == -128 && ((int16_t *)s.data)[3] == 127);
	scan_free(&s);
	const uint8_t u8[4] = { 0, 1, 2, 255 };
	read_nifti("u8-scaled.nii.gz", dims, DT_UINT8, 8, 2.5, -1, u8, sizeof(u8), &s);
	CHECK(s.type == SCAN_F32 && ((float *)s.data)[1] == 1.5f && ((float *)s.data)[3] == 636.5f);
	scan_free(&s);
	read_nifti("u8.nii", dims, DT_UINT8, 8, 1, 0, u8, sizeof(u8), &s);
	CHECK(s.type == SCAN_U8 && !memcmp(s.data, u8, 4));
	scan_free(&s);
	const uint16_t u16[4] = { 0, 1000, 40000, 65535 };
	read_nifti("u16-shift.nii", dims, DT_UINT16, 16, 1, -32768, u16, sizeof(u16), &s);
	CHECK(s.type == SCAN_I16 && ((int16_t *)s.data)[0] == -32768 && ((int16_t *)s.data)[3] == 32767);
	scan_free(&s);
	read_nifti("u16-big-shift.nii", dims, DT_UINT16, 16, 1, 1, u16, sizeof(u16), &s);
	CHECK(s.type == SCAN_F32 && ((float *)s.data)[3] == 65536.0f);
	scan_free(&s);
	const int32_t i32[4] = { -1000, 0, 3000, 32767 };
	read_nifti("i32.nii", dims, DT_INT32, 32, 0, 0, i32, sizeof(i32), &s);
	CHECK(s.type == SCAN_I16 && ((int16_t *)s.data)[0] == -1000 && ((int16_t *)s.data)[3] == 32767);
	scan_free(&s);
	const uint32_t u32[4] = { 0, 1, 65535, 65536 };
	read_nifti("u32.nii", dims, DT_UINT32, 32, 0, 0, u32, sizeof(u32), &s);
	CHECK(s.type == SCAN_F32 && ((float *)s.data)[3] == 65536.0f);
	scan_free(&s);
	const double f64[4] = { -1.5, 0, 1e6, 0.25 };
	read_nifti("f64.nii", dims, DT_FLOAT64, 64, 0, 0, f64, sizeof(f64), &s);
	CHECK(s.type == SCAN_F32 && ((float *)s.data)[0] == -1.5f && ((float *)s.data)[2] == 1e6f);
	scan_free(&s);
	const uint8_t rgb[12] = { 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12 };
	read_nifti("rgb.nii", dims, DT_RGB24, 24, 0, 0, rgb, sizeof(rgb), &s);
	const uint8_t rgba[16] = { 1, 2, 3, 255, 4, 5, 6, 255, 7, 8, 9, 255, 10, 11, 12, 255 };
	CHECK(s.type == SCAN_RGBA8 && !memcmp(s.data, rgba, 16));
	scan_free(&s);

	const float c64[8] = { 0 };
	write_nifti1(at("complex.nii"), dims, DT_COMPLEX64, 64, 0, 0, c64, sizeof(c64));
	expect_error(at("complex.nii"), NULL, -EINVAL);
	const int16_t dims4[4] = { 2, 2, 1, 2 };
	write_nifti1(at("4d.nii"), dims4, DT_UINT8, 8, 0, 0, rgb, 8);
	expect_error(at("4d.nii"), NULL, -EINVAL);
	const int16_t huge[4] = { 4096, 4096, 4096, 1 };
	write_nifti1(at("huge.nii"), huge, DT_UINT8, 8, 0, 0, rgb, 8);
	expect_error(at("huge.nii"), NULL, -E2BIG);
}

/* A NIfTI-2 file, in micrometres, with an sform. */
static void check_nifti2(void)
{
	nifti_2_header h;
	memset(&h, 0, sizeof(h));
	h.sizeof_hdr = 540;
	memcpy(h.magic, "n+2\0\r\n\032\n", 8);
	h.dim[0] = 3;
	h.dim[1] = 3;
	h.dim[2] = h.dim[3] = 1;
	h.datatype = DT_INT16;
	h.bitpix = 16;
	h.pixdim[1] = h.pixdim[2] = h.pixdim[3] = 500;
	h.vox_offset = 544;
	h.xyzt_units = NIFTI_UNITS_MICRON;
	h.sform_code = NIFTI_XFORM_SCANNER_ANAT;
	h.srow_x[0] = 500;
	h.srow_y[2] = 250;
	h.srow_z[1] = -2000;
	h.srow_x[3] = 10000;
	char body[540 + 4 + 6] = { 0 };
	const int16_t v[3] = { -5, 0, 5 };
	memcpy(body, &h, sizeof(h));
	memcpy(body + 544, v, sizeof(v));
	write_file(at("two.nii"), body, sizeof(body));
	struct scan s;
	read_ok(at("two.nii"), NULL, &s);
	CHECK(strstr(s.what, "NIfTI-2") && s.type == SCAN_I16 && ((int16_t *)s.data)[0] == -5);
	CHECK(s.spacing[0] == 0.5 && s.spacing[1] == 2 && s.spacing[2] == 0.25);
	CHECK(s.to_ras[0] == 0.5 && s.to_ras[6] == -2 && s.to_ras[9] == 0.25 && s.to_ras[12] == 10);
	scan_free(&s);
	/* The same header for a .hdr/.img pair: refused, nothing else opened. */
	memcpy(body + 4, "ni2\0\r\n\032\n", 8);
	write_file(at("pair.nii"), body, sizeof(body));
	expect_error(at("pair.nii"), NULL, -EINVAL);
}

int main(int argc, char **argv)
{
	CHECK(argc == 4);
	if (!in_path("dump2dcm")) {
		printf("SKIP: dcmtk's dump2dcm is not installed (scripts/install-deps)\n");
		return 77;
	}
	snprintf(work, sizeof(work), "%s/scan-test-XXXXXX", argv[3]);
	CHECK(mkdtemp(work));
	make_phantom(argv);
	check_phantom();
	check_bad_nifti();
	check_bad_dicom();
	check_raw();
	check_nifti_types();
	check_nifti2();
	remove_tree(work);
	return check_done();
}
