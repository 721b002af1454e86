/* The mappings from the program's view to the display volume
 * (docs/opengl.md), from the trace, with no daemon (half height 1). */
#include <math.h>
#include <stdlib.h>

#include "gltest.h"

/* The 8 corners of a cube, as points. */
static void cube(float x, float y, float z, float half)
{
	glBegin(GL_POINTS);
	for (int i = 0; i < 8; i++)
		glVertex3f(x + (i & 1 ? half : -half), y + (i & 2 ? half : -half), z + (i & 4 ? half : -half));
	glEnd();
}

static void check_map(const struct tframe *f, float s, float cx, float cy, float cz)
{
	const float *m = f->map;
	CHECK_MSG(gltest_near(m[0], s) && gltest_near(m[5], s) && gltest_near(m[10], s), "scale %g %g %g, expected %g",
		  m[0], m[5], m[10], s);
	CHECK_MSG(gltest_near(m[12], -s * cx) && gltest_near(m[13], -s * cy) && gltest_near(m[14], -s * cz),
		  "offset %g %g %g, expected centre %g %g %g", m[12], m[13], m[14], cx, cy, cz);
	CHECK(m[1] == 0 && m[2] == 0 && m[4] == 0 && m[6] == 0 && m[8] == 0 && m[9] == 0);
}

/* Every vertex of the frame lies in the display cylinder once mapped. */
static void check_inside(const struct tframe *f)
{
	for (int i = 0; i < f->n_v; i++) {
		float p[3];
		for (int r = 0; r < 3; r++)
			p[r] = f->map[r] * f->v[i].p[0] + f->map[4 + r] * f->v[i].p[1] + f->map[8 + r] * f->v[i].p[2] +
			       f->map[12 + r];
		CHECK_MSG(p[0] * p[0] + p[2] * p[2] <= 1.0001f && fabsf(p[1]) <= 1.0001f, "(%g, %g, %g) outside", p[0],
			  p[1], p[2]);
	}
}

/* Fitted, steady while the geometry stays in the fit, fitted anew when it
 * leaves it or shrinks a lot. */
static void check_steady(void)
{
	const float slack = 1.15f;
	cube(2, 3, -10, 1);
	struct tframe f = gltest_swap();
	float s = 1 / (slack * sqrtf(2));
	check_map(&f, s, 2, 3, -10);
	check_inside(&f);
	/* Steady: a small move stays in the fit. */
	cube(2.1f, 3, -10.1f, 1);
	f = gltest_swap();
	check_map(&f, s, 2, 3, -10);
	check_inside(&f);
	CHECK_EQ(gltest_trace_count("fit "), 1);
	/* Nothing drawn: the fit stays. */
	f = gltest_swap();
	check_map(&f, s, 2, 3, -10);
	/* Leaving the fit, growing: fitted anew. */
	cube(2, 3, -10, 2);
	f = gltest_swap();
	check_map(&f, s / 2, 2, 3, -10);
	/* Shrinking a lot: fitted anew; a little: not. */
	cube(2, 3, -10, 1.5f);
	f = gltest_swap();
	check_map(&f, s / 2, 2, 3, -10);
	cube(0, 0, 0, 0.5f);
	f = gltest_swap();
	check_map(&f, s * 2, 0, 0, 0);
	CHECK_EQ(gltest_trace_count("fit "), 3);
}

/* Tall geometry, and display lists by their bounding spheres. */
static void check_shapes(void)
{
	const float slack = 1.15f;
	/* Tall geometry: its height decides (h = 1 offline). */
	glBegin(GL_POINTS);
	glVertex3f(0, -5, 0), glVertex3f(0, 5, 0), glVertex3f(0.1f, 0, 0);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK(gltest_near(f.map[5], 1 / (5 * slack)));
	check_inside(&f);
	/* Display lists count by their bounds, wherever they turn. */
	glNewList(1, GL_COMPILE);
	cube(0, 0, 0, 1);
	glEndList();
	glLoadIdentity();
	glTranslatef(0, 0, -20);
	glCallList(1);
	f = gltest_swap();
	float r = sqrtf(3); /* the sphere around the cube */
	check_map(&f, 1 / (slack * r * sqrtf(2)), 0, 0, -20);
	for (int a = 0; a < 360; a += 10) {
		glLoadIdentity();
		glTranslatef(0, 0, -20);
		glRotatef((float)a, 1, 1, 0);
		glCallList(1);
		f = gltest_swap();
	}
	CHECK_EQ(gltest_trace_count("fit "), 5);
}

void case_mapping(void)
{
	gltest_setup(NULL, NULL);
	check_steady();
	check_shapes();
}

void case_frustum(void)
{
	gltest_setup("frustum", NULL);
	glMatrixMode(GL_PROJECTION);
	glLoadIdentity();
	glFrustum(-1, 1, -1, 1, 1, 10);
	glMatrixMode(GL_MODELVIEW);
	glLoadIdentity();
	glBegin(GL_POINTS);
	glVertex3f(0, 0, -1), glVertex3f(0, 0, -10), glVertex3f(1, 1, -1), glVertex3f(0, 0, 1);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[0], 3); /* the one behind the eye is dropped */
	const float want[3][3] = { { 0, 0, -1 }, { 0, 0, 1 }, { 1, 1, -1 } };
	for (int i = 0; i < 3; i++)
		for (int k = 0; k < 3; k++)
			CHECK(gltest_near(f.v[i].p[k], want[i][k]));
	float k = sqrtf(0.5f);
	CHECK(gltest_near(f.map[0], k) && gltest_near(f.map[5], 1) && gltest_near(f.map[10], -k));
	CHECK(f.map[12] == 0 && f.map[13] == 0 && f.map[14] == 0);
	/* A list call carries the projection: not affine. */
	glNewList(1, GL_COMPILE);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, -2);
	glEnd();
	glEndList();
	glCallList(1);
	f = gltest_swap();
	CHECK(f.calls == 1 && f.c[0].s[11] == -1);
	/* An orthographic projection. */
	glMatrixMode(GL_PROJECTION);
	glLoadIdentity();
	glOrtho(-2, 2, -2, 2, -2, 2);
	glMatrixMode(GL_MODELVIEW);
	glBegin(GL_POINTS);
	glVertex3f(2, 2, 2);
	glEnd();
	f = gltest_swap();
	CHECK(gltest_near(f.v[0].p[0], 1) && gltest_near(f.v[0].p[1], 1) && gltest_near(f.v[0].p[2], -1));
}

void case_fixed(void)
{
	setenv("SPINDLE_GL_SCALE", "0.5", 1);
	setenv("SPINDLE_GL_OFFSET", "0,0.25,1", 1);
	gltest_setup("fixed", NULL);
	glBegin(GL_POINTS);
	glVertex3f(1, 2, 3);
	glEnd();
	struct tframe f = gltest_swap();
	const float want[16] = { 0.5f, 0, 0, 0, 0, 0.5f, 0, 0, 0, 0, 0.5f, 0, 0, 0.25f, 1, 1 };
	for (int i = 0; i < 16; i++)
		CHECK(gltest_near(f.map[i], want[i]));
	CHECK(gltest_near(f.v[0].p[0], 1) && gltest_near(f.v[0].p[2], 3)); /* eye space */
}
