/* The matrix stacks: every call is compiled into a list being compiled,
 * else done on the layer's copy of the modelview and projection stacks. */
#include "ctx.h"
#include "list.h"
#include "mat.h"
#include "real.h"

static void matrix_op(enum sgl_op_kind kind, const float *m, GLenum mode)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec) {
		sgl_rec_matrix(c->rec, kind, m, mode);
		return;
	}
	sgl_ctx_matrix_op(c, kind, m, mode);
}

static void mult(const float m[16])
{
	matrix_op(SGL_OP_MULT, m, 0);
}

void glMatrixMode(GLenum mode)
{
	matrix_op(SGL_OP_MODE, NULL, mode);
	PASS(glMatrixMode, mode);
}

void glLoadIdentity(void)
{
	float m[16];
	sgl_mat_identity(m);
	matrix_op(SGL_OP_LOAD, m, 0);
	PASS(glLoadIdentity);
}

void glLoadMatrixf(const GLfloat *m)
{
	if (m)
		matrix_op(SGL_OP_LOAD, m, 0);
	PASS(glLoadMatrixf, m);
}

void glLoadMatrixd(const GLdouble *m)
{
	float f[16];
	if (m) {
		sgl_mat_from_double(f, m);
		matrix_op(SGL_OP_LOAD, f, 0);
	}
	PASS(glLoadMatrixd, m);
}

void glMultMatrixf(const GLfloat *m)
{
	if (m)
		mult(m);
	PASS(glMultMatrixf, m);
}

void glMultMatrixd(const GLdouble *m)
{
	float f[16];
	if (m) {
		sgl_mat_from_double(f, m);
		mult(f);
	}
	PASS(glMultMatrixd, m);
}

void glLoadTransposeMatrixf(const GLfloat m[16])
{
	float f[16];
	if (m) {
		sgl_mat_transpose(f, m);
		matrix_op(SGL_OP_LOAD, f, 0);
	}
	PASS(glLoadTransposeMatrixf, m);
}

void glLoadTransposeMatrixd(const GLdouble m[16])
{
	float f[16];
	if (m) {
		sgl_mat_from_double(f, m);
		sgl_mat_transpose(f, f);
		matrix_op(SGL_OP_LOAD, f, 0);
	}
	PASS(glLoadTransposeMatrixd, m);
}

void glMultTransposeMatrixf(const GLfloat m[16])
{
	float f[16];
	if (m) {
		sgl_mat_transpose(f, m);
		mult(f);
	}
	PASS(glMultTransposeMatrixf, m);
}

void glMultTransposeMatrixd(const GLdouble m[16])
{
	float f[16];
	if (m) {
		sgl_mat_from_double(f, m);
		sgl_mat_transpose(f, f);
		mult(f);
	}
	PASS(glMultTransposeMatrixd, m);
}

void glPushMatrix(void)
{
	matrix_op(SGL_OP_PUSH, NULL, 0);
	PASS(glPushMatrix);
}

void glPopMatrix(void)
{
	matrix_op(SGL_OP_POP, NULL, 0);
	PASS(glPopMatrix);
}

void glRotatef(GLfloat angle, GLfloat x, GLfloat y, GLfloat z)
{
	float m[16];
	sgl_mat_rotate(m, angle, x, y, z);
	mult(m);
	PASS(glRotatef, angle, x, y, z);
}

void glRotated(GLdouble angle, GLdouble x, GLdouble y, GLdouble z)
{
	float m[16];
	sgl_mat_rotate(m, (float)angle, (float)x, (float)y, (float)z);
	mult(m);
	PASS(glRotated, angle, x, y, z);
}

void glTranslatef(GLfloat x, GLfloat y, GLfloat z)
{
	float m[16];
	sgl_mat_translate(m, x, y, z);
	mult(m);
	PASS(glTranslatef, x, y, z);
}

void glTranslated(GLdouble x, GLdouble y, GLdouble z)
{
	float m[16];
	sgl_mat_translate(m, (float)x, (float)y, (float)z);
	mult(m);
	PASS(glTranslated, x, y, z);
}

void glScalef(GLfloat x, GLfloat y, GLfloat z)
{
	float m[16];
	sgl_mat_scale(m, x, y, z);
	mult(m);
	PASS(glScalef, x, y, z);
}

void glScaled(GLdouble x, GLdouble y, GLdouble z)
{
	float m[16];
	sgl_mat_scale(m, (float)x, (float)y, (float)z);
	mult(m);
	PASS(glScaled, x, y, z);
}

void glFrustum(GLdouble l, GLdouble r, GLdouble b, GLdouble t, GLdouble n, GLdouble f)
{
	float m[16];
	if (sgl_mat_frustum(m, l, r, b, t, n, f))
		mult(m);
	PASS(glFrustum, l, r, b, t, n, f);
}

void glOrtho(GLdouble l, GLdouble r, GLdouble b, GLdouble t, GLdouble n, GLdouble f)
{
	float m[16];
	if (sgl_mat_ortho(m, l, r, b, t, n, f))
		mult(m);
	PASS(glOrtho, l, r, b, t, n, f);
}

void glFrustumf(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f)
{
	float m[16];
	if (sgl_mat_frustum(m, l, r, b, t, n, f))
		mult(m);
	PASS(glFrustumf, l, r, b, t, n, f);
}

void glOrthof(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f)
{
	float m[16];
	if (sgl_mat_ortho(m, l, r, b, t, n, f))
		mult(m);
	PASS(glOrthof, l, r, b, t, n, f);
}
