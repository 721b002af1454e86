/* A scan placed on the display (tools/scan_display.h): the voxel axes put
 * on the display's (left +x, superior +y, anterior +z) for axial, coronal,
 * sagittal and flipped acquisitions and for tilted ones (the nearest axes,
 * the tilt reported); the samples written in that order, each display step
 * moving the right way in patient space; the fit inside the cylinder and
 * the height, centred, touching one of them; the window statistics. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "scan_display.h"

/* to_ras from three columns (RAS mm per voxel step along i, j, k) and the origin. */
static void make_ras(double m[16], const double ci[3], const double cj[3], const double ck[3])
{
	memset(m, 0, 16 * sizeof(double));
	for (int r = 0; r < 3; r++) {
		m[r] = ci[r];
		m[4 + r] = cj[r];
		m[8 + r] = ck[r];
	}
	m[12] = 7;
	m[13] = -3;
	m[14] = 11;
	m[15] = 1;
}

static void spacing_of(const double m[16], double s[3])
{
	for (int c = 0; c < 3; c++)
		s[c] = sqrt(m[4 * c] * m[4 * c] + m[4 * c + 1] * m[4 * c + 1] + m[4 * c + 2] * m[4 * c + 2]);
}

/* Display coordinates (x left, y superior, z anterior) of voxel (i, j, k). */
static void voxel_display(const double m[16], const double v[3], double d[3])
{
	double ras[3];
	for (int r = 0; r < 3; r++)
		ras[r] = m[r] * v[0] + m[4 + r] * v[1] + m[8 + r] * v[2] + m[12 + r];
	d[0] = -ras[0];
	d[1] = ras[2];
	d[2] = ras[1];
}

static void expect_layout(const char *name, const double m[16], const unsigned axis[3], const bool flip[3],
			  double oblique)
{
	const uint32_t dims[3] = { 5, 6, 7 };
	double spacing[3];
	struct scan_layout l;
	spacing_of(m, spacing);
	scan_layout_of(dims, spacing, m, &l);
	for (int a = 0; a < 3; a++) {
		CHECK_MSG(l.axis[a] == axis[a] && l.flip[a] == flip[a], "%s: display axis %d: voxel axis %u%s", name, a,
			  l.axis[a], l.flip[a] ? " flipped" : "");
		CHECK(l.dims[a] == dims[axis[a]] && l.spacing[a] == spacing[axis[a]]);
	}
	CHECK_MSG(fabs(l.oblique_deg - oblique) < 1e-6, "%s: oblique %g, not %g", name, l.oblique_deg, oblique);
	printf("%s: x <- %c%c, y <- %c%c, z <- %c%c, %.1f degrees oblique\n", name, l.flip[0] ? '-' : '+',
	       "ijk"[l.axis[0]], l.flip[1] ? '-' : '+', "ijk"[l.axis[1]], l.flip[2] ? '-' : '+', "ijk"[l.axis[2]],
	       l.oblique_deg);
}

static void check_orientations(void)
{
	double m[16];
	/* A raw file's diagonal: i right, j anterior, k superior. */
	make_ras(m, (double[]){ 0.5, 0, 0 }, (double[]){ 0, 0.7, 0 }, (double[]){ 0, 0, 2 });
	expect_layout("RAS diagonal", m, (unsigned[]){ 0, 2, 1 }, (bool[]){ true, false, false }, 0);
	/* Axial DICOM (LPS): i to the left, j posterior, k superior. */
	make_ras(m, (double[]){ -0.8, 0, 0 }, (double[]){ 0, -0.8, 0 }, (double[]){ 0, 0, 1.25 });
	expect_layout("axial", m, (unsigned[]){ 0, 2, 1 }, (bool[]){ false, false, true }, 0);
	/* Coronal: i to the left, j inferior, k anterior. */
	make_ras(m, (double[]){ -1, 0, 0 }, (double[]){ 0, 0, -1 }, (double[]){ 0, 3, 0 });
	expect_layout("coronal", m, (unsigned[]){ 0, 1, 2 }, (bool[]){ false, true, false }, 0);
	/* Sagittal: i posterior, j inferior, k to the right. */
	make_ras(m, (double[]){ 0, -1, 0 }, (double[]){ 0, 0, -1 }, (double[]){ 2, 0, 0 });
	expect_layout("sagittal", m, (unsigned[]){ 2, 1, 0 }, (bool[]){ true, true, true }, 0);
	/* Axial tilted 20 degrees about the left-right axis: the same axes. */
	double t = 20 * M_PI / 180;
	make_ras(m, (double[]){ -1, 0, 0 }, (double[]){ 0, -cos(t), sin(t) }, (double[]){ 0, sin(t), cos(t) });
	expect_layout("axial tilted 20", m, (unsigned[]){ 0, 2, 1 }, (bool[]){ false, false, true }, 20);
	/* Tilted 60 degrees: nearer coronal (j now mostly superior). */
	t = 60 * M_PI / 180;
	make_ras(m, (double[]){ -1, 0, 0 }, (double[]){ 0, -cos(t), sin(t) }, (double[]){ 0, sin(t), cos(t) });
	expect_layout("axial tilted 60", m, (unsigned[]){ 0, 1, 2 }, (bool[]){ false, false, false }, 30);
	/* A gantry tilt's shear: k leans anterior by 15 degrees, i and j straight. */
	t = 15 * M_PI / 180;
	make_ras(m, (double[]){ -1, 0, 0 }, (double[]){ 0, -1, 0 }, (double[]){ 0, sin(t), cos(t) });
	expect_layout("sheared", m, (unsigned[]){ 0, 2, 1 }, (bool[]){ false, false, true }, 15);
}

/* Samples written in the layout's order: each equals the voxel that
 * scan_layout_source() names, and a step along a display axis moves along
 * it in patient space. */
static void check_write(const char *name, const double m[16])
{
	struct scan s = { .type = SCAN_U16, .dims = { 5, 6, 7 } };
	struct scan_layout l;
	size_t count = 5 * 6 * 7;
	uint16_t *v = malloc(count * 2), *got = malloc(count * 2);
	CHECK(v && got);
	for (size_t n = 0; n < count; n++)
		v[n] = (uint16_t)(1000 + n);
	s.data = v;
	s.size = count * 2;
	memcpy(s.to_ras, m, sizeof(s.to_ras));
	spacing_of(m, s.spacing);
	scan_layout_of(s.dims, s.spacing, s.to_ras, &l);
	FILE *f = tmpfile();
	CHECK(f);
	CHECK(scan_layout_write(&s, &l, fileno(f)) == 0);
	CHECK(pread(fileno(f), got, count * 2, 0) == (ssize_t)(count * 2));
	fclose(f);
	for (uint32_t z = 0; z < l.dims[2]; z++)
		for (uint32_t y = 0; y < l.dims[1]; y++)
			for (uint32_t x = 0; x < l.dims[0]; x++) {
				size_t d = ((size_t)z * l.dims[1] + y) * l.dims[0] + x;
				CHECK(got[d] == v[scan_layout_source(&l, s.dims, x, y, z)]);
			}
	for (int a = 0; a < 3; a++) {
		uint32_t p[3] = { 1, 1, 1 }, q[3] = { 1, 1, 1 };
		q[a] = 2;
		size_t vp = scan_layout_source(&l, s.dims, p[0], p[1], p[2]);
		size_t vq = scan_layout_source(&l, s.dims, q[0], q[1], q[2]);
		double ip[3] = { vp % 5, vp / 5 % 6, vp / 30 }, iq[3] = { vq % 5, vq / 5 % 6, vq / 30 }, dp[3], dq[3];
		voxel_display(m, ip, dp);
		voxel_display(m, iq, dq);
		CHECK_MSG(dq[a] - dp[a] > 0.5 * l.spacing[a], "%s: a step along display axis %d moves %g mm along it",
			  name, a, dq[a] - dp[a]);
	}
	free(v);
	free(got);
}

static void check_writes(void)
{
	double m[16], t = 20 * M_PI / 180;
	make_ras(m, (double[]){ 0.5, 0, 0 }, (double[]){ 0, 0.7, 0 }, (double[]){ 0, 0, 2 });
	check_write("RAS diagonal", m);
	make_ras(m, (double[]){ 0, -1, 0 }, (double[]){ 0, 0, -1 }, (double[]){ 2, 0, 0 });
	check_write("sagittal", m);
	make_ras(m, (double[]){ -1, 0, 0 }, (double[]){ 0, -cos(t), sin(t) }, (double[]){ 0, sin(t), cos(t) });
	check_write("tilted", m);
	printf("samples in the display's order: each step along a display axis moves along it\n");
}

/* The box's corners within the cylinder and the height; one limit met. */
static void check_fit(const uint32_t dims[3], const double spacing[3], float h)
{
	struct scan_layout l = { .dims = { dims[0], dims[1], dims[2] },
				 .spacing = { spacing[0], spacing[1], spacing[2] } };
	float m[16];
	const float margin = 0.95f;
	scan_layout_fit(&l, h, margin, m);
	double worst_r = 0, worst_y = 0;
	for (int c = 0; c < 8; c++) {
		double p[3], q[3];
		for (int a = 0; a < 3; a++)
			p[a] = c & (1 << a) ? dims[a] * spacing[a] : 0;
		for (int r = 0; r < 3; r++)
			q[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
		worst_r = fmax(worst_r, hypot(q[0], q[2]));
		worst_y = fmax(worst_y, fabs(q[1]));
		/* centred: the opposite corner lands opposite */
		double o[3];
		for (int a = 0; a < 3; a++)
			o[a] = dims[a] * spacing[a] - p[a];
		for (int r = 0; r < 3; r++)
			CHECK(fabs(q[r] + (m[r] * o[0] + m[4 + r] * o[1] + m[8 + r] * o[2] + m[12 + r])) < 1e-5);
	}
	CHECK(m[0] == m[5] && m[5] == m[10] && m[1] == 0 && m[4] == 0 && m[15] == 1);
	CHECK_MSG(worst_r <= margin + 1e-5 && worst_y <= margin * h + 1e-5, "fit: radius %g, height %g", worst_r,
		  worst_y);
	CHECK_MSG(fabs(worst_r - margin) < 1e-5 || fabs(worst_y - margin * h) < 1e-5, "fit: neither limit met");
	printf("fit %ux%ux%u of %gx%gx%g mm, h %g: corners to radius %.4f, height %.4f\n", dims[0], dims[1], dims[2],
	       spacing[0], spacing[1], spacing[2], h, worst_r, worst_y);
}

static void check_fits(void)
{
	check_fit((uint32_t[]){ 512, 100, 512 }, (double[]){ 0.7, 0.7, 0.7 }, 1.0f); /* flat: the cylinder */
	check_fit((uint32_t[]){ 64, 300, 64 }, (double[]){ 1, 2.5, 1 }, 1.0f);       /* tall: the height */
	check_fit((uint32_t[]){ 10, 10, 10 }, (double[]){ 1, 1, 1 }, 0.5f);
	check_fit((uint32_t[]){ 1, 1, 1 }, (double[]){ 3, 0.1, 7 }, 1.0f);
}

static void check_stats(void)
{
	struct scan_stats st;
	uint8_t u8[200];
	for (int n = 0; n < 200; n++)
		u8[n] = n < 100 ? 0 : (uint8_t)(n - 99); /* 100 zeros, 1..100 */
	CHECK(scan_stats_of(SCAN_U8, u8, 200, &st) == 0);
	CHECK_MSG(st.nonzero == 100 && st.p1 == 1 && st.p99 == 99 && st.min == 0 && !st.looks_like_ct,
		  "u8: %llu nonzero, p1 %g, p99 %g", (unsigned long long)st.nonzero, st.p1, st.p99);
	int16_t ct[1000];
	for (int n = 0; n < 1000; n++)
		ct[n] = (int16_t)(n < 500 ? -1000 : n - 500); /* air, and 0..499 */
	CHECK(scan_stats_of(SCAN_I16, ct, 1000, &st) == 0);
	CHECK(st.looks_like_ct && st.min == -1000 && st.nonzero == 999 && st.p1 == -1000 && st.p99 == 490);
	ct[0] = -400;
	for (int n = 1; n < 1000; n++)
		ct[n] = 100;
	CHECK(scan_stats_of(SCAN_I16, ct, 1000, &st) == 0 && !st.looks_like_ct);
	float f[6] = { NAN, 0, INFINITY, 2.0f, 4.0f, -1.0f };
	CHECK(scan_stats_of(SCAN_F32, f, 6, &st) == 0);
	CHECK(st.nonzero == 3 && st.min == -1 && fabs(st.p1 + 1) < 1e-3 && fabs(st.p99 - 4) < 1e-3);
	const float zeros[2] = { 0, 0 };
	CHECK(scan_stats_of(SCAN_F32, zeros, 2, &st) == 0 && st.nonzero == 0 && st.p1 == 0 && st.p99 == 0);
	CHECK(scan_stats_of(SCAN_RGBA8, u8, 50, &st) == -EINVAL);
	printf("statistics: percentiles of the non-zero samples, CT by its air\n");
}

int main(void)
{
	check_orientations();
	check_writes();
	check_fits();
	check_stats();
	return check_done();
}
