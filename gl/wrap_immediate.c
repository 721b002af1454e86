/* glBegin/glEnd, every glVertex, glColor and glNormal, glMaterial, glRect,
 * and the enables and attributes that decide a vertex's colour. */
#include <string.h>

#include "config.h"
#include "ctx.h"
#include "list.h"
#include "mat.h"
#include "real.h"
#include "wrap.h"

void sgl_begin(struct sgl_ctx *c, GLenum mode)
{
	if (c->in_begin)
		return;
	struct sgl_geom *own = NULL, *inherit = NULL;
	bool flat;
	if (c->rec) {
		struct sgl_seg *s = sgl_rec_segment(c->rec);
		own = &s->own;
		inherit = &s->inherit;
		memcpy(c->begin_s, c->rec->l[c->rec->top], sizeof(c->begin_s));
		flat = c->rec->cs.flat;
	} else {
		if (sgl_ctx_drawing(c))
			own = &c->frame.imm;
		sgl_ctx_stage_matrix(c, c->begin_s);
		flat = c->cs.flat;
	}
	c->in_begin = sgl_asm_begin(&c->as, mode, flat, own, inherit);
}

void sgl_vertex(struct sgl_ctx *c, float x, float y, float z, float w)
{
	if (!c->in_begin)
		return;
	struct sgl_avertex v;
	const float p[4] = { x, y, z, w };
	sgl_mat_apply(c->begin_s, p, v.pos);
	sgl_colour_rgba(c->rec ? &c->rec->cs : &c->cs, v.rgba);
	v.inherit = c->rec && !sgl_rec_colour_known(c->rec);
	sgl_asm_vertex(&c->as, &v);
}

void sgl_end(struct sgl_ctx *c)
{
	if (!c->in_begin)
		return;
	sgl_asm_end(&c->as);
	c->in_begin = false;
}

void sgl_color(struct sgl_ctx *c, const float rgba[4])
{
	if (c->rec)
		sgl_rec_state(c->rec, SGL_OP_COLOR, 0, 0, rgba);
	else
		sgl_colour_set(&c->cs, rgba);
}

static void material(struct sgl_ctx *c, GLenum face, GLenum pname, const float rgba[4])
{
	if ((face != GL_FRONT && face != GL_FRONT_AND_BACK) || (pname != GL_DIFFUSE && pname != GL_AMBIENT_AND_DIFFUSE))
		return;
	if (c->rec)
		sgl_rec_state(c->rec, SGL_OP_MATERIAL, 0, 0, rgba);
	else
		memcpy(c->cs.diffuse, rgba, sizeof(c->cs.diffuse));
}

void glBegin(GLenum mode)
{
	sgl_begin(sgl_ctx_current(), mode);
	PASS(glBegin, mode);
}

void glEnd(void)
{
	sgl_end(sgl_ctx_current());
	PASS(glEnd);
}

static void vertex(float x, float y, float z, float w)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->in_begin)
		sgl_vertex(c, x, y, z, w);
}

#define VERTEX2(sfx, T)                                 \
	void glVertex2##sfx(T x, T y)                   \
	{                                               \
		vertex((float)x, (float)y, 0, 1);       \
		PASS(glVertex2##sfx, x, y);             \
	}                                               \
	void glVertex2##sfx##v(const T *v)              \
	{                                               \
		vertex((float)v[0], (float)v[1], 0, 1); \
		PASS(glVertex2##sfx##v, v);             \
	}
#define VERTEX3(sfx, T)                                           \
	void glVertex3##sfx(T x, T y, T z)                        \
	{                                                         \
		vertex((float)x, (float)y, (float)z, 1);          \
		PASS(glVertex3##sfx, x, y, z);                    \
	}                                                         \
	void glVertex3##sfx##v(const T *v)                        \
	{                                                         \
		vertex((float)v[0], (float)v[1], (float)v[2], 1); \
		PASS(glVertex3##sfx##v, v);                       \
	}
#define VERTEX4(sfx, T)                                                     \
	void glVertex4##sfx(T x, T y, T z, T w)                             \
	{                                                                   \
		vertex((float)x, (float)y, (float)z, (float)w);             \
		PASS(glVertex4##sfx, x, y, z, w);                           \
	}                                                                   \
	void glVertex4##sfx##v(const T *v)                                  \
	{                                                                   \
		vertex((float)v[0], (float)v[1], (float)v[2], (float)v[3]); \
		PASS(glVertex4##sfx##v, v);                                 \
	}
#define VERTEX(sfx, T) VERTEX2(sfx, T) VERTEX3(sfx, T) VERTEX4(sfx, T)
VERTEX(d, GLdouble)
VERTEX(f, GLfloat)
VERTEX(i, GLint)
VERTEX(s, GLshort)

static void color(float r, float g, float b, float a)
{
	const float rgba[4] = { r, g, b, a };
	sgl_color(sgl_ctx_current(), rgba);
}

/* Integer components map to 0..1 (signed ones to -1..1), as GL does. */
#define COLOR(sfx, T, K)                                                                           \
	void glColor3##sfx(T r, T g, T b)                                                          \
	{                                                                                          \
		color((float)(r * K), (float)(g * K), (float)(b * K), 1);                          \
		PASS(glColor3##sfx, r, g, b);                                                      \
	}                                                                                          \
	void glColor3##sfx##v(const T *v)                                                          \
	{                                                                                          \
		color((float)(v[0] * K), (float)(v[1] * K), (float)(v[2] * K), 1);                 \
		PASS(glColor3##sfx##v, v);                                                         \
	}                                                                                          \
	void glColor4##sfx(T r, T g, T b, T a)                                                     \
	{                                                                                          \
		color((float)(r * K), (float)(g * K), (float)(b * K), (float)(a * K));             \
		PASS(glColor4##sfx, r, g, b, a);                                                   \
	}                                                                                          \
	void glColor4##sfx##v(const T *v)                                                          \
	{                                                                                          \
		color((float)(v[0] * K), (float)(v[1] * K), (float)(v[2] * K), (float)(v[3] * K)); \
		PASS(glColor4##sfx##v, v);                                                         \
	}
COLOR(b, GLbyte, (1.0 / 127))
COLOR(s, GLshort, (1.0 / 32767))
COLOR(i, GLint, (1.0 / 2147483647))
COLOR(ub, GLubyte, (1.0 / 255))
COLOR(us, GLushort, (1.0 / 65535))
COLOR(ui, GLuint, (1.0 / 4294967295.0))
COLOR(f, GLfloat, 1.0)
COLOR(d, GLdouble, 1.0)

/* Normals are passed through: the display emits light, nothing is lit. */
#define NORMAL(sfx, T)                         \
	void glNormal3##sfx(T x, T y, T z)     \
	{                                      \
		PASS(glNormal3##sfx, x, y, z); \
	}                                      \
	void glNormal3##sfx##v(const T *v)     \
	{                                      \
		PASS(glNormal3##sfx##v, v);    \
	}
NORMAL(b, GLbyte)
NORMAL(d, GLdouble)
NORMAL(f, GLfloat)
NORMAL(i, GLint)
NORMAL(s, GLshort)

void glMaterialf(GLenum face, GLenum pname, GLfloat param)
{
	PASS(glMaterialf, face, pname, param);
}

void glMateriali(GLenum face, GLenum pname, GLint param)
{
	PASS(glMateriali, face, pname, param);
}

void glMaterialfv(GLenum face, GLenum pname, const GLfloat *params)
{
	if (params)
		material(sgl_ctx_current(), face, pname, params);
	PASS(glMaterialfv, face, pname, params);
}

void glMaterialiv(GLenum face, GLenum pname, const GLint *params)
{
	if (params && (pname == GL_DIFFUSE || pname == GL_AMBIENT_AND_DIFFUSE)) {
		float v[4];
		for (int i = 0; i < 4; i++)
			v[i] = (float)(params[i] / 2147483647.0);
		material(sgl_ctx_current(), face, pname, v);
	}
	PASS(glMaterialiv, face, pname, params);
}
