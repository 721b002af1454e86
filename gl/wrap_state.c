/* The state that decides colours (glColorMaterial, glShadeModel, the
 * lighting enables, glPushAttrib/glPopAttrib), glRect, and what is passed
 * through without being shown: textures, shader programs, feedback and
 * selection. */
#include <string.h>

#include "config.h"
#include "ctx.h"
#include "list.h"
#include "real.h"
#include "wrap.h"

void sgl_uncovered(const char *what)
{
	sgl_warn_once(what, "%s: passed to OpenGL, not shown on the volumetric display", what);
}

void glColorMaterial(GLenum face, GLenum mode)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec)
		sgl_rec_state(c->rec, SGL_OP_COLOR_MATERIAL, mode, 0, NULL);
	else
		c->cs.cm_mode = mode;
	PASS(glColorMaterial, face, mode);
}

void glShadeModel(GLenum mode)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec)
		sgl_rec_state(c->rec, SGL_OP_SHADE, mode == GL_FLAT, 0, NULL);
	else
		c->cs.flat = mode == GL_FLAT;
	PASS(glShadeModel, mode);
}

static void enable(GLenum cap, bool on)
{
	if (on && (cap == GL_TEXTURE_1D || cap == GL_TEXTURE_2D || cap == GL_TEXTURE_3D))
		sgl_uncovered("textures");
	if (cap != GL_LIGHTING && cap != GL_COLOR_MATERIAL)
		return;
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec)
		sgl_rec_state(c->rec, SGL_OP_ENABLE, cap, on, NULL);
	else
		sgl_colour_enable(&c->cs, cap, on);
}

void glEnable(GLenum cap)
{
	enable(cap, true);
	PASS(glEnable, cap);
}

void glDisable(GLenum cap)
{
	enable(cap, false);
	PASS(glDisable, cap);
}

void glPushAttrib(GLbitfield mask)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (!c->rec && c->attrib_top < SGL_ATTRIB_DEPTH)
		c->attribs[c->attrib_top++] = (struct sgl_attrib){ mask, c->matrix_mode, c->cs };
	PASS(glPushAttrib, mask);
}

static void pop_attrib(struct sgl_ctx *c)
{
	const struct sgl_attrib *a = &c->attribs[--c->attrib_top];
	struct sgl_colour *cs = &c->cs;
	if (a->mask & GL_TRANSFORM_BIT)
		c->matrix_mode = a->matrix_mode;
	if (a->mask & GL_CURRENT_BIT)
		memcpy(cs->colour, a->cs.colour, sizeof(cs->colour));
	if (a->mask & GL_LIGHTING_BIT) {
		memcpy(cs->diffuse, a->cs.diffuse, sizeof(cs->diffuse));
		cs->cm_mode = a->cs.cm_mode;
		cs->flat = a->cs.flat;
	}
	if (a->mask & (GL_LIGHTING_BIT | GL_ENABLE_BIT)) {
		cs->lighting = a->cs.lighting;
		cs->color_material = a->cs.color_material;
	}
}

void glPopAttrib(void)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (!c->rec && c->attrib_top > 0)
		pop_attrib(c);
	PASS(glPopAttrib);
}

static void rect(float x1, float y1, float x2, float y2)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->in_begin)
		return;
	sgl_begin(c, GL_POLYGON);
	sgl_vertex(c, x1, y1, 0, 1);
	sgl_vertex(c, x2, y1, 0, 1);
	sgl_vertex(c, x2, y2, 0, 1);
	sgl_vertex(c, x1, y2, 0, 1);
	sgl_end(c);
}

#define RECT(sfx, T)                                                          \
	void glRect##sfx(T x1, T y1, T x2, T y2)                              \
	{                                                                     \
		rect((float)x1, (float)y1, (float)x2, (float)y2);             \
		PASS(glRect##sfx, x1, y1, x2, y2);                            \
	}                                                                     \
	void glRect##sfx##v(const T *v1, const T *v2)                         \
	{                                                                     \
		rect((float)v1[0], (float)v1[1], (float)v2[0], (float)v2[1]); \
		PASS(glRect##sfx##v, v1, v2);                                 \
	}
RECT(d, GLdouble)
RECT(f, GLfloat)
RECT(i, GLint)
RECT(s, GLshort)

void glUseProgram(GLuint program)
{
	sgl_ctx_current()->program = program;
	if (program)
		sgl_uncovered("geometry drawn with shader programs");
	PASS(glUseProgram, program);
}

void glUseProgramObjectARB(GLhandleARB program)
{
	sgl_ctx_current()->program = program;
	if (program)
		sgl_uncovered("geometry drawn with shader programs");
	PASS(glUseProgramObjectARB, program);
}

void glBindTexture(GLenum target, GLuint texture)
{
	PASS(glBindTexture, target, texture);
}

void glTexImage1D(GLenum target, GLint level, GLint internal, GLsizei w, GLint border, GLenum format, GLenum type,
		  const void *pixels)
{
	sgl_uncovered("textures");
	PASS(glTexImage1D, target, level, internal, w, border, format, type, pixels);
}

void glTexImage2D(GLenum target, GLint level, GLint internal, GLsizei w, GLsizei h, GLint border, GLenum format,
		  GLenum type, const void *pixels)
{
	sgl_uncovered("textures");
	PASS(glTexImage2D, target, level, internal, w, h, border, format, type, pixels);
}

void glTexImage3D(GLenum target, GLint level, GLint internal, GLsizei w, GLsizei h, GLsizei d, GLint border,
		  GLenum format, GLenum type, const void *pixels)
{
	sgl_uncovered("textures");
	PASS(glTexImage3D, target, level, internal, w, h, d, border, format, type, pixels);
}

/* Feedback and selection draw nothing on the screen: nor here. */
GLint glRenderMode(GLenum mode)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (mode == GL_SELECT || mode == GL_FEEDBACK)
		sgl_uncovered("feedback and selection");
	__typeof__(&glRenderMode) real = REAL(glRenderMode);
	GLint r = real ? real(mode) : 0;
	if (mode == GL_RENDER || mode == GL_SELECT || mode == GL_FEEDBACK)
		c->render_mode = mode;
	return r;
}

void glFeedbackBuffer(GLsizei size, GLenum type, GLfloat *buffer)
{
	sgl_uncovered("feedback and selection");
	PASS(glFeedbackBuffer, size, type, buffer);
}

void glSelectBuffer(GLsizei size, GLuint *buffer)
{
	sgl_uncovered("feedback and selection");
	PASS(glSelectBuffer, size, buffer);
}
