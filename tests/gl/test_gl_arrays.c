/* Client arrays and buffer objects, from the trace, with no daemon. */
#include <stdint.h>
#include <string.h>

#include "gltest.h"

static void check_vertex(const struct tvertex *v, float x, float y, float z)
{
	CHECK_MSG(gltest_near(v->p[0], x) && gltest_near(v->p[1], y) && gltest_near(v->p[2], z),
		  "vertex (%g, %g, %g), expected (%g, %g, %g)", v->p[0], v->p[1], v->p[2], x, y, z);
}

static const GLfloat quad[4][3] = { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 }, { 1, 1, 0 } };
static const GLushort idx16[6] = { 0, 1, 2, 2, 1, 3 };
static const GLuint idx32[4] = { 0, 3, 1, 2 };

static void check_draws(void)
{
	glDrawArrays(GL_TRIANGLES, 0, 3); /* no array enabled: nothing */
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[2], 0);
	glVertexPointer(3, GL_FLOAT, 0, quad);
	glEnableClientState(GL_VERTEX_ARRAY);
	glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
	f = gltest_swap();
	CHECK_EQ(f.n[2], 6);
	check_vertex(&f.v[5], 1, 1, 0);
	glDrawArrays(GL_POINTS, 1, 2);
	glDrawElements(GL_TRIANGLES, 6, GL_UNSIGNED_SHORT, idx16);
	glDrawRangeElements(GL_LINES, 0, 3, 4, GL_UNSIGNED_INT, idx32);
	glDrawElements(GL_LINES, 2, GL_FLOAT, idx32); /* not an index type */
	f = gltest_swap();
	CHECK(f.n[0] == 2 && f.n[1] == 4 && f.n[2] == 6);
	check_vertex(&f.v[0], 1, 0, 0);
	check_vertex(&f.v[3], 1, 1, 0); /* lines come before triangles */
	check_vertex(&f.v[7], 1, 0, 0);
	CHECK_EQ(fakegl_count("glDrawElements"), 2);
	CHECK_EQ(fakegl_count("glDrawRangeElements"), 1);
	/* glArrayElement inside glBegin/glEnd. */
	glBegin(GL_LINES);
	glArrayElement(3);
	glArrayElement(0);
	glEnd();
	f = gltest_swap();
	CHECK_EQ(f.n[1], 2);
	check_vertex(&f.v[0], 1, 1, 0);
}

/* Colours per vertex, strided arrays of other types, interleaved arrays. */
static void check_layouts(void)
{
	struct {
		GLshort xy[2];
		GLubyte rgba[4];
	} mixed[3] = { { { 1, 2 }, { 255, 0, 0, 255 } },
		       { { 3, 4 }, { 0, 255, 0, 255 } },
		       { { 5, 6 }, { 0, 0, 255, 0 } } };
	glVertexPointer(2, GL_SHORT, sizeof(mixed[0]), mixed[0].xy);
	glColorPointer(4, GL_UNSIGNED_BYTE, sizeof(mixed[0]), mixed[0].rgba);
	glEnableClientState(GL_COLOR_ARRAY);
	glDrawArrays(GL_POINTS, 0, 3);
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[0], 3);
	check_vertex(&f.v[1], 3, 4, 0);
	CHECK(f.v[0].rgba == 0xff0000ffu && f.v[1].rgba == 0x00ff00ffu && f.v[2].rgba == 0x0000ff00u);
	const GLfloat c3v3[2][6] = { { 1, 0, 1, 7, 8, 9 }, { 0, 1, 1, 1, 2, 3 } };
	glInterleavedArrays(GL_C3F_V3F, 0, c3v3);
	glDrawArrays(GL_LINES, 0, 2);
	const GLdouble v4[2][4] = { { 2, 4, 6, 2 }, { 1, 1, 1, 1 } };
	glDisableClientState(GL_COLOR_ARRAY);
	glColor3f(1, 1, 0);
	glVertexPointer(4, GL_DOUBLE, 0, v4);
	glDrawArrays(GL_POINTS, 0, 1);
	f = gltest_swap();
	CHECK(f.n[0] == 1 && f.n[1] == 2);
	check_vertex(&f.v[0], 1, 2, 3);
	CHECK_EQ(f.v[0].rgba, 0xffff00ffu);
	check_vertex(&f.v[1], 7, 8, 9);
	CHECK(f.v[1].rgba == 0xff00ffffu && f.v[2].rgba == 0x00ffffffu);
	CHECK_EQ(fakegl_count("glInterleavedArrays"), 1);
}

void case_arrays(void)
{
	gltest_setup("fixed", NULL);
	gltest_capture_stderr();
	check_draws();
	check_layouts();
	/* Compiled into a list: the arrays are read at compile time. */
	GLfloat moving[3][3] = { { 0, 0, 0 }, { 1, 0, 0 }, { 0, 1, 0 } };
	glDisableClientState(GL_COLOR_ARRAY);
	glVertexPointer(3, GL_FLOAT, 0, moving);
	glNewList(1, GL_COMPILE);
	glDrawArrays(GL_TRIANGLES, 0, 3);
	glEndList();
	CHECK_EQ(gltest_trace_count("list 1 ops 1 segments 1 vertices 3"), 1);
	/* A shader program bound: its geometry is not shown, said once. */
	glUseProgram(3);
	glDrawArrays(GL_TRIANGLES, 0, 3);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	glUseProgram(4);
	struct tframe f = gltest_swap();
	CHECK(f.n[0] + f.n[1] + f.n[2] == 0);
	glUseProgram(0);
	glDrawArrays(GL_TRIANGLES, 0, 3);
	f = gltest_swap();
	CHECK_EQ(f.n[2], 3);
	CHECK_EQ(gltest_stderr_count("shader programs"), 1);
	CHECK_EQ(fakegl_count("glUseProgram"), 3);
}

/* Vertices in a buffer object, changed by glBufferSubData and mappings. */
static void check_contents(void)
{
	glBindBuffer(GL_ARRAY_BUFFER, 7);
	glBufferData(GL_ARRAY_BUFFER, sizeof(quad), quad, GL_STATIC_DRAW);
	glVertexPointer(3, GL_FLOAT, 0, (const void *)(uintptr_t)(3 * sizeof(GLfloat)));
	glBindBuffer(GL_ARRAY_BUFFER, 0); /* the pointer keeps its buffer */
	glEnableClientState(GL_VERTEX_ARRAY);
	glDrawArrays(GL_POINTS, 0, 3);
	glDrawArrays(GL_POINTS, 0, 4); /* one past the buffer: dropped */
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[0], 6);
	check_vertex(&f.v[0], 1, 0, 0);
	/* glBufferSubData, and writes through a mapping. */
	glBindBuffer(GL_ARRAY_BUFFER, 7);
	const GLfloat p[3] = { 5, 5, 5 };
	glBufferSubData(GL_ARRAY_BUFFER, 3 * sizeof(GLfloat), sizeof(p), p);
	glBufferSubData(GL_ARRAY_BUFFER, sizeof(quad), sizeof(p), p); /* out of range */
	glDrawArrays(GL_POINTS, 0, 1);
	GLfloat *m = glMapBuffer(GL_ARRAY_BUFFER, GL_WRITE_ONLY);
	CHECK(m == fakegl_map_memory());
	memcpy(m, quad, sizeof(quad));
	m[3] = 8;
	CHECK(glUnmapBuffer(GL_ARRAY_BUFFER) == GL_TRUE);
	glDrawArrays(GL_POINTS, 0, 1);
	m = glMapBufferRange(GL_ARRAY_BUFFER, 6 * sizeof(GLfloat), 3 * sizeof(GLfloat), GL_MAP_WRITE_BIT);
	m[0] = 9;
	glUnmapBuffer(GL_ARRAY_BUFFER);
	glDrawArrays(GL_POINTS, 1, 1);
	f = gltest_swap();
	CHECK_EQ(f.n[0], 3);
	check_vertex(&f.v[0], 5, 5, 5);
	check_vertex(&f.v[1], 8, 0, 0);
	check_vertex(&f.v[2], 9, 0, 0); /* the range mapped, as written */
}

/* Indices in an element buffer; the ARB names; deleted buffers. */
static void check_elements(void)
{
	glVertexPointer(3, GL_FLOAT, 0, NULL);
	glBindBufferARB(GL_ELEMENT_ARRAY_BUFFER, 8);
	glBufferDataARB(GL_ELEMENT_ARRAY_BUFFER, sizeof(idx16), idx16, GL_STATIC_DRAW);
	glDrawElements(GL_TRIANGLES, 6, GL_UNSIGNED_SHORT, (const void *)(uintptr_t)(3 * sizeof(GLushort)));
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[2], 3); /* 3 of the 6 indices from the offset on */
	check_vertex(&f.v[2], 1, 1, 0);
	/* Deleted buffers unbind; drawing from them draws nothing. */
	glDeleteBuffers(1, (const GLuint[]){ 7 });
	glDeleteBuffersARB(1, (const GLuint[]){ 8 });
	glDrawArrays(GL_POINTS, 0, 1);
	f = gltest_swap();
	CHECK_EQ(f.n[0], 0);
	CHECK_EQ(fakegl_count("glBufferSubData"), 2);
	CHECK_EQ(fakegl_count("glUnmapBuffer"), 2);
	CHECK_EQ(fakegl_count("glBindBufferARB"), 1);
}

void case_buffers(void)
{
	gltest_setup("fixed", NULL);
	check_contents();
	check_elements();
}
