/* Display lists: glNewList/glEndList record, glCallList(s) replay. */
#include "ctx.h"
#include "list.h"
#include "real.h"

void glNewList(GLuint list, GLenum mode)
{
	sgl_rec_begin(sgl_ctx_current(), list, mode);
	PASS(glNewList, list, mode);
}

void glEndList(void)
{
	PASS(glEndList);
	sgl_rec_end(sgl_ctx_current());
}

void glCallList(GLuint list)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec)
		sgl_rec_call(c->rec, list, false);
	else
		sgl_list_call(c, list, 0);
	PASS(glCallList, list);
}

/* Name i of glCallLists' array (before the base is added), or -1 for a
 * type it does not take (GL_INVALID_ENUM: nothing is called). */
static int64_t list_name(GLenum type, const void *lists, GLsizei i)
{
	const uint8_t *b = lists;
	switch (type) {
	case GL_BYTE:
		return (uint8_t)((const GLbyte *)lists)[i];
	case GL_UNSIGNED_BYTE:
		return b[i];
	case GL_SHORT:
		return (uint16_t)((const GLshort *)lists)[i];
	case GL_UNSIGNED_SHORT:
		return ((const GLushort *)lists)[i];
	case GL_INT:
		return (uint32_t)((const GLint *)lists)[i];
	case GL_UNSIGNED_INT:
		return ((const GLuint *)lists)[i];
	case GL_FLOAT:
		return (uint32_t)(int64_t)((const GLfloat *)lists)[i];
	case GL_2_BYTES:
		return b[2 * i] << 8 | b[2 * i + 1];
	case GL_3_BYTES:
		return b[3 * i] << 16 | b[3 * i + 1] << 8 | b[3 * i + 2];
	case GL_4_BYTES:
		return (int64_t)((uint32_t)b[4 * i] << 24 | (uint32_t)b[4 * i + 1] << 16 | b[4 * i + 2] << 8 |
				 b[4 * i + 3]);
	default:
		return -1;
	}
}

void glCallLists(GLsizei n, GLenum type, const void *lists)
{
	struct sgl_ctx *c = sgl_ctx_current();
	for (GLsizei i = 0; lists && i < n; i++) {
		int64_t name = list_name(type, lists, i);
		if (name < 0)
			break;
		if (c->rec)
			sgl_rec_call(c->rec, (GLuint)name, true);
		else
			sgl_list_call(c, (GLuint)(name + c->list_base), 0);
	}
	PASS(glCallLists, n, type, lists);
}

void glDeleteLists(GLuint list, GLsizei range)
{
	sgl_lists_delete(sgl_ctx_current(), list, range);
	PASS(glDeleteLists, list, range);
}

void glListBase(GLuint base)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->rec)
		sgl_rec_base(c->rec, base);
	else
		c->list_base = base;
	PASS(glListBase, base);
}
