/* What the layer records, from the trace, with no daemon: immediate mode
 * in every mode and every glVertex and glColor, display lists, matrices,
 * client arrays and buffer objects, and the mappings. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "gltest.h"

static void check_vertex(const struct tvertex *v, float x, float y, float z)
{
	CHECK_MSG(gltest_near(v->p[0], x) && gltest_near(v->p[1], y) && gltest_near(v->p[2], z),
		  "vertex (%g, %g, %g), expected (%g, %g, %g)", v->p[0], v->p[1], v->p[2], x, y, z);
}

/* Each glBegin mode: how many point, line and triangle vertices n
 * vertices make. */
static const struct {
	GLenum mode;
	int n, points, lines, tris;
} modes[] = {
	{ GL_POINTS, 5, 5, 0, 0 },       { GL_LINES, 5, 0, 4, 0 },     { GL_LINE_STRIP, 4, 0, 6, 0 },
	{ GL_LINE_LOOP, 4, 0, 8, 0 },    { GL_TRIANGLES, 7, 0, 0, 6 }, { GL_TRIANGLE_STRIP, 5, 0, 0, 9 },
	{ GL_TRIANGLE_FAN, 5, 0, 0, 9 }, { GL_QUADS, 9, 0, 0, 12 },    { GL_QUAD_STRIP, 7, 0, 0, 12 },
	{ GL_POLYGON, 5, 0, 0, 9 },
};

static void check_modes(void)
{
	for (size_t m = 0; m < sizeof(modes) / sizeof(modes[0]); m++) {
		glBegin(modes[m].mode);
		for (int i = 0; i < modes[m].n; i++)
			glVertex3f((float)i, (float)(i * i % 7), 0);
		glEnd();
		struct tframe f = gltest_swap();
		CHECK_MSG(f.n[0] == (unsigned)modes[m].points && f.n[1] == (unsigned)modes[m].lines &&
				  f.n[2] == (unsigned)modes[m].tris,
			  "mode %#x: %u %u %u", modes[m].mode, f.n[0], f.n[1], f.n[2]);
		CHECK(!strcmp(f.by, "swap") && !strcmp(f.status, "offline"));
	}
	CHECK_EQ(fakegl_count("glVertex3f"), 56);
	CHECK_EQ(fakegl_count("glBegin"), 10);
	CHECK_EQ(fakegl_count("glXSwapBuffers"), 10);
}

/* The split of a line loop, a quad and a quad strip, vertex by vertex. */
static void check_splits(void)
{
	static const float sq[4][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 1 } };
	glBegin(GL_LINE_LOOP);
	for (int i = 0; i < 3; i++)
		glVertex2fv(sq[i]);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n_v, 6);
	check_vertex(&f.v[4], 1, 1, 0); /* the closing segment */
	check_vertex(&f.v[5], 0, 0, 0);
	glBegin(GL_QUADS);
	for (int i = 0; i < 4; i++)
		glVertex2fv(sq[i]);
	glEnd();
	f = gltest_swap();
	CHECK_EQ(f.n_v, 6);
	const int quad[6] = { 0, 1, 2, 0, 2, 3 };
	for (int i = 0; i < 6; i++)
		check_vertex(&f.v[i], sq[quad[i]][0], sq[quad[i]][1], 0);
	glBegin(GL_QUAD_STRIP); /* v0 v1 v3 v2 is the quad */
	for (int i = 0; i < 4; i++)
		glVertex2fv(sq[i]);
	glEnd();
	f = gltest_swap();
	CHECK_EQ(f.n_v, 6);
	const int strip[6] = { 0, 1, 3, 0, 3, 2 };
	for (int i = 0; i < 6; i++)
		check_vertex(&f.v[i], sq[strip[i]][0], sq[strip[i]][1], 0);
}

/* Every glVertex variant, each once, as points. */
static void check_variants(void)
{
	const GLdouble d[4] = { 1, 2, 3, 2 };
	const GLfloat fl[4] = { 1, 2, 3, 2 };
	const GLint in[4] = { 1, 2, 3, 2 };
	const GLshort sh[4] = { 1, 2, 3, 2 };
	glBegin(GL_POINTS);
	glVertex2d(1, 2), glVertex2dv(d), glVertex2f(1, 2), glVertex2fv(fl);
	glVertex2i(1, 2), glVertex2iv(in), glVertex2s(1, 2), glVertex2sv(sh);
	glVertex3d(1, 2, 3), glVertex3dv(d), glVertex3f(1, 2, 3), glVertex3fv(fl);
	glVertex3i(1, 2, 3), glVertex3iv(in), glVertex3s(1, 2, 3), glVertex3sv(sh);
	glVertex4d(1, 2, 3, 2), glVertex4dv(d), glVertex4f(1, 2, 3, 2), glVertex4fv(fl);
	glVertex4i(1, 2, 3, 2), glVertex4iv(in), glVertex4s(1, 2, 3, 2), glVertex4sv(sh);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[0], 24);
	for (int i = 0; i < 8; i++)
		check_vertex(&f.v[i], 1, 2, 0);
	for (int i = 8; i < 16; i++)
		check_vertex(&f.v[i], 1, 2, 3);
	for (int i = 16; i < 24; i++)
		check_vertex(&f.v[i], 0.5f, 1, 1.5f); /* divided by w */
	const char *names[] = { "glVertex2d", "glVertex2sv", "glVertex3i", "glVertex4fv", "glVertex4s" };
	for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++)
		CHECK_EQ(fakegl_count(names[i]), 1);
	CHECK(fakegl_arg("glVertex3d", 2) == 3 && fakegl_arg("glVertex4s", 3) == 2);
	/* glRect: a polygon of two triangles. */
	glRectf(0, 0, 2, 1);
	glRectiv((const GLint[]){ 0, 0 }, (const GLint[]){ 1, 1 });
	f = gltest_swap();
	CHECK_EQ(f.n[2], 12);
	check_vertex(&f.v[1], 2, 0, 0);
	CHECK_EQ(fakegl_count("glRectf"), 1);
}

void case_immediate(void)
{
	gltest_setup("fixed", NULL);
	check_modes();
	check_splits();
	check_variants();
	/* Outside glBegin/glEnd a vertex is nothing; an unknown mode too. */
	glVertex3f(1, 1, 1);
	glBegin(0x1234);
	glVertex3f(1, 1, 1);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK(f.n[0] + f.n[1] + f.n[2] == 0);
}

static unsigned point_colour(void)
{
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n_v, 1);
	return f.v[0].rgba;
}

#define COLOUR3(sfx, T, one)                                         \
	do {                                                         \
		glColor3##sfx((T)(one), 0, (T)(one));                \
		CHECK_EQ(point_colour(), 0xff00ffffu);               \
		const T v3[3] = { 0, (T)(one), 0 };                  \
		glColor3##sfx##v(v3);                                \
		CHECK_EQ(point_colour(), 0x00ff00ffu);               \
		glColor4##sfx(0, 0, (T)(one), 0);                    \
		CHECK_EQ(point_colour(), 0x0000ff00u);               \
		const T v4[4] = { (T)(one), (T)(one), 0, (T)(one) }; \
		glColor4##sfx##v(v4);                                \
		CHECK_EQ(point_colour(), 0xffff00ffu);               \
		CHECK_EQ(fakegl_count("glColor4" #sfx "v"), 1);      \
	} while (0)

/* Every glColor variant, integer components normalised. */
static void check_colour_calls(void)
{
	CHECK_EQ(point_colour(), 0xffffffffu); /* GL's initial colour */
	COLOUR3(b, GLbyte, 127);
	COLOUR3(s, GLshort, 32767);
	COLOUR3(i, GLint, 2147483647);
	COLOUR3(ub, GLubyte, 255);
	COLOUR3(us, GLushort, 65535);
	COLOUR3(ui, GLuint, 4294967295u);
	COLOUR3(f, GLfloat, 1);
	COLOUR3(d, GLdouble, 1);
	glColor3f(0.5f, 0.25f, 2);
	CHECK_EQ(point_colour(), 0x8040ffffu); /* clamped */
}

static void check_lighting(void)
{
	/* Lit: the front material's diffuse colour; with GL_COLOR_MATERIAL
	 * the current colour drives it. */
	glEnable(GL_LIGHTING);
	glColor3f(1, 0, 0);
	glMaterialfv(GL_FRONT, GL_DIFFUSE, (const GLfloat[]){ 0, 0, 1, 1 });
	CHECK_EQ(point_colour(), 0x0000ffffu);
	glMaterialfv(GL_BACK, GL_DIFFUSE, (const GLfloat[]){ 0, 1, 0, 1 });
	glMaterialf(GL_FRONT, GL_SHININESS, 5);
	CHECK_EQ(point_colour(), 0x0000ffffu);
	glColorMaterial(GL_FRONT, GL_AMBIENT_AND_DIFFUSE);
	glEnable(GL_COLOR_MATERIAL);
	CHECK_EQ(point_colour(), 0xff0000ffu);
	glColor3f(0, 1, 0);
	CHECK_EQ(point_colour(), 0x00ff00ffu);
	glDisable(GL_COLOR_MATERIAL);
	glColor3f(1, 1, 1);
	CHECK_EQ(point_colour(), 0x00ff00ffu);
	glDisable(GL_LIGHTING);
	CHECK_EQ(point_colour(), 0xffffffffu);
	CHECK_EQ(fakegl_count("glEnable"), 2);
	CHECK_EQ(fakegl_count("glMaterialfv"), 2);
}

void case_colours(void)
{
	gltest_setup("fixed", NULL);
	check_colour_calls();
	check_lighting();
	/* Normals are passed through; flat shading takes the last vertex's colour. */
	glNormal3f(0, 0, 1);
	CHECK_EQ(fakegl_count("glNormal3f"), 1);
	glShadeModel(GL_FLAT);
	glBegin(GL_TRIANGLES);
	glColor3f(1, 0, 0), glVertex3f(0, 0, 0), glColor3f(0, 1, 0), glVertex3f(1, 0, 0);
	glColor3f(0, 0, 1), glVertex3f(0, 1, 0);
	glEnd();
	struct tframe f = gltest_swap();
	CHECK(f.v[0].rgba == 0x0000ffffu && f.v[1].rgba == 0x0000ffffu);
	/* glPushAttrib / glPopAttrib restore the colour. */
	glPushAttrib(GL_CURRENT_BIT);
	glColor3f(1, 0, 0);
	glPopAttrib();
	CHECK_EQ(point_colour(), 0x0000ffffu);
}
