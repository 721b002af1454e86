/* Display lists and matrices, from the trace, with no daemon. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "gltest.h"

static void check_vertex(const struct tvertex *v, float x, float y, float z)
{
	CHECK_MSG(gltest_near(v->p[0], x) && gltest_near(v->p[1], y) && gltest_near(v->p[2], z),
		  "vertex (%g, %g, %g), expected (%g, %g, %g)", v->p[0], v->p[1], v->p[2], x, y, z);
}

/* The translation column of a call's matrix. */
static void check_offset(const struct tcall *c, float x, float y, float z)
{
	CHECK_MSG(gltest_near(c->s[12], x) && gltest_near(c->s[13], y) && gltest_near(c->s[14], z),
		  "call of list %u at (%g, %g, %g), expected (%g, %g, %g)", c->list, c->s[12], c->s[13], c->s[14], x, y,
		  z);
}

static void triangle(void)
{
	glBegin(GL_TRIANGLES);
	glVertex3f(0, 0, 0), glVertex3f(1, 0, 0), glVertex3f(0, 1, 0);
	glEnd();
}

static void point(float x, float y, float z)
{
	glBegin(GL_POINTS);
	glVertex3f(x, y, z);
	glEnd();
}

/* A list that draws without setting a colour takes the caller's. */
static void check_compile_and_call(GLuint l)
{
	glNewList(l, GL_COMPILE);
	triangle();
	glEndList();
	CHECK_EQ(gltest_trace_count("list "), 1);
	struct tframe f = gltest_swap();
	CHECK(f.calls == 0 && f.n[2] == 0); /* compiled, not drawn */
	glColor3f(1, 0, 0);
	glTranslatef(5, 0, 0);
	glCallList(l);
	glColor3f(0, 0, 1);
	glCallList(l);
	f = gltest_swap();
	CHECK(f.calls == 2 && f.n[2] == 0); /* by reference, no vertices */
	CHECK(f.c[0].list == l && f.c[0].rgba == 0xff0000ffu && f.c[1].rgba == 0x0000ffffu);
	check_offset(&f.c[0], 5, 0, 0);
	CHECK_EQ(fakegl_count("glCallList"), 2);
	CHECK_EQ(fakegl_count("glNewList"), 1);
}

/* A list calling another, in a pushed matrix; its own colour and a point. */
static void check_nested(GLuint inner, GLuint outer)
{
	glNewList(outer, GL_COMPILE);
	glPushMatrix();
	glTranslatef(0, 2, 0);
	glCallList(inner);
	glPopMatrix();
	glColor3f(0, 0, 1);
	point(0, 0, 0);
	glEndList();
	glLoadIdentity();
	glColor3f(0, 1, 0);
	glCallList(outer);
	point(0, 0, 0); /* after the call: the colour it set */
	struct tframe f = gltest_swap();
	CHECK_EQ(f.calls, 2);
	CHECK(f.c[0].list == inner && f.c[0].rgba == 0x00ff00ffu);
	check_offset(&f.c[0], 0, 2, 0);
	CHECK(f.c[1].list == outer);
	check_offset(&f.c[1], 0, 0, 0);
	CHECK(f.n_v == 1 && f.v[0].rgba == 0x0000ffffu);
	/* A list calling itself stops at the nesting limit. */
	glNewList(outer + 1, GL_COMPILE);
	point(0, 0, 0);
	glCallList(outer + 1);
	glEndList();
	glCallList(outer + 1);
	f = gltest_swap();
	CHECK_EQ(f.calls, 64);
}

/* Matrices inside a list: relative ones bake into one segment, an
 * absolute one starts another; what the list leaves applies after. */
static void check_list_matrices(GLuint l)
{
	glNewList(l, GL_COMPILE);
	glPushMatrix();
	glTranslatef(1, 0, 0);
	point(0, 0, 0);
	glPopMatrix();
	point(0, 0, 0);
	glLoadIdentity();
	point(3, 0, 0);
	glTranslatef(0, 0, 7);
	glEndList();
	char *t = gltest_trace();
	char want[64];
	snprintf(want, sizeof(want), "list %u ops 7 segments 2 vertices 3", l);
	CHECK_MSG(strstr(t, want) != NULL, "no '%s' in the trace", want);
	free(t);
	glLoadIdentity();
	glTranslatef(0, 9, 0);
	glCallList(l);
	point(0, 0, 0);
	struct tframe f = gltest_swap();
	CHECK_EQ(f.calls, 2);
	check_offset(&f.c[0], 0, 9, 0);
	check_offset(&f.c[1], 0, 0, 0); /* after glLoadIdentity */
	check_vertex(&f.v[0], 0, 0, 7);
}

static void check_execute_delete_base(GLuint l)
{
	glLoadIdentity();
	glNewList(l + 5, GL_COMPILE_AND_EXECUTE);
	point(1, 1, 1);
	glEndList();
	struct tframe f = gltest_swap();
	CHECK(f.calls == 1 && f.c[0].list == l + 5);
	/* glListBase and glCallLists of each type. */
	glListBase(l);
	glCallLists(2, GL_UNSIGNED_BYTE, (const GLubyte[]){ 0, 5 });
	glCallLists(1, GL_UNSIGNED_INT, (const GLuint[]){ 5 });
	glCallLists(1, GL_2_BYTES, (const GLubyte[]){ 0, 5 });
	glCallLists(1, 0x1234, (const GLubyte[]){ 5 }); /* no such type */
	f = gltest_swap();
	CHECK_EQ(f.calls, 4);
	CHECK(f.c[0].list == l && f.c[1].list == l + 5 && f.c[2].list == l + 5 && f.c[3].list == l + 5);
	glListBase(0);
	/* Deleted, a list draws nothing; a list never made, nothing. */
	glDeleteLists(l + 5, 1);
	glCallList(l + 5);
	glCallList(999);
	glDeleteLists(1, 1 << 30);
	glCallList(l);
	f = gltest_swap();
	CHECK_EQ(f.calls, 0);
	CHECK_EQ(fakegl_count("glDeleteLists"), 2);
}

void case_lists(void)
{
	gltest_setup("fixed", NULL);
	GLuint l = glGenLists(10);
	check_compile_and_call(l);
	check_nested(l, l + 1);
	check_list_matrices(l + 3);
	check_execute_delete_base(l);
	/* A list replaced by glNewList of its name: the new one draws. */
	glNewList(l, GL_COMPILE);
	point(0, 0, 0);
	glEndList();
	glNewList(l, GL_COMPILE);
	triangle();
	glEndList();
	glCallList(l);
	struct tframe f = gltest_swap();
	CHECK_EQ(f.calls, 1);
	char *t = gltest_trace();
	CHECK(strstr(t, "vertices 3\n") != NULL);
	free(t);
}

/* Where (1, 0, 0) goes under the current modelview. */
static struct tvertex moved(void)
{
	point(1, 0, 0);
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n_v, 1);
	return f.v[0];
}

static void check_products(void)
{
	glLoadIdentity();
	glRotatef(90, 0, 0, 1);
	struct tvertex v = moved();
	check_vertex(&v, 0, 1, 0);
	glLoadIdentity();
	glRotated(90, 0, 1, 0);
	v = moved();
	check_vertex(&v, 0, 0, -1);
	glLoadIdentity();
	glTranslatef(1, 2, 3);
	glScalef(2, 3, 4);
	v = moved();
	check_vertex(&v, 3, 2, 3);
	glLoadIdentity();
	glTranslated(0, 0, -1);
	glScaled(-1, 1, 1);
	v = moved();
	check_vertex(&v, -1, 0, -1);
	const GLfloat t[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 1, 1, 1 };
	const GLdouble td[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 1, 1, 1 };
	glLoadMatrixf(t);
	glMultMatrixd(td);
	v = moved();
	check_vertex(&v, 3, 2, 2);
	GLfloat tt[16];
	for (int i = 0; i < 16; i++)
		tt[i] = t[(i % 4) * 4 + i / 4];
	glLoadTransposeMatrixf(tt);
	glMultTransposeMatrixf(tt);
	v = moved();
	check_vertex(&v, 3, 2, 2);
	glLoadMatrixd(td);
	glMultMatrixf(t);
	v = moved();
	check_vertex(&v, 3, 2, 2);
}

void case_matrices(void)
{
	gltest_setup("fixed", NULL);
	struct tvertex v = moved();
	check_vertex(&v, 1, 0, 0);
	check_products();
	/* The stacks. */
	glLoadIdentity();
	glPushMatrix();
	glTranslatef(5, 0, 0);
	glPushMatrix();
	glLoadIdentity();
	glPopMatrix();
	v = moved();
	check_vertex(&v, 6, 0, 0);
	glPopMatrix();
	glPopMatrix(); /* underflow: GL ignores it */
	v = moved();
	check_vertex(&v, 1, 0, 0);
	for (int i = 0; i < 40; i++) /* overflow: ignored past the depth */
		glPushMatrix();
	for (int i = 0; i < 40; i++)
		glPopMatrix();
	/* The projection and texture matrices leave eye space alone. */
	glMatrixMode(GL_PROJECTION);
	glLoadIdentity();
	glFrustum(-1, 1, -1, 1, 1, 10);
	glOrtho(-1, 1, -1, 1, 1, 10);
	glMatrixMode(GL_TEXTURE);
	glTranslatef(9, 9, 9);
	glMatrixMode(GL_MODELVIEW);
	v = moved();
	check_vertex(&v, 1, 0, 0);
	/* glPopAttrib(GL_TRANSFORM_BIT) restores the matrix mode. */
	glPushAttrib(GL_TRANSFORM_BIT);
	glMatrixMode(GL_PROJECTION);
	glPopAttrib();
	glTranslatef(1, 0, 0);
	v = moved();
	check_vertex(&v, 2, 0, 0);
	CHECK_EQ(fakegl_count("glPushMatrix"), 42);
	CHECK_EQ(fakegl_count("glFrustum"), 1);
	CHECK(fakegl_arg("glTranslatef", 0) == 1);
}
