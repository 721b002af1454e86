/* Client vertex arrays (glVertexPointer, glColorPointer,
 * glInterleavedArrays) drawn by glDrawArrays, glDrawElements,
 * glDrawRangeElements and glArrayElement while no shader program is bound,
 * in client memory or in buffer objects (wrap_buffers.c shadows their
 * contents). Each draw goes through the glBegin/glEnd path. */
#include <stdint.h>
#include <string.h>

#include "ctx.h"
#include "list.h"
#include "real.h"
#include "wrap.h"

/* An array resolved for one draw: where element 0 is and how many bytes
 * may be read from there. */
struct view {
	const uint8_t *base;
	size_t limit;
};

static size_t type_size(GLenum type)
{
	switch (type) {
	case GL_BYTE:
	case GL_UNSIGNED_BYTE:
		return 1;
	case GL_SHORT:
	case GL_UNSIGNED_SHORT:
		return 2;
	case GL_INT:
	case GL_UNSIGNED_INT:
	case GL_FLOAT:
		return 4;
	case GL_DOUBLE:
		return 8;
	default:
		return 0;
	}
}

/* Component k at p; integer colours are normalised. */
static float component(GLenum type, const uint8_t *p, int k, bool normalise)
{
	double v = 0, scale = 1;
	switch (type) {
#define READ(gltype, T, max)                              \
	case gltype: {                                    \
		T x;                                      \
		memcpy(&x, p + k * sizeof(T), sizeof(T)); \
		v = x;                                    \
		scale = max;                              \
		break;                                    \
	}
		READ(GL_BYTE, int8_t, 127.0)
		READ(GL_UNSIGNED_BYTE, uint8_t, 255.0)
		READ(GL_SHORT, int16_t, 32767.0)
		READ(GL_UNSIGNED_SHORT, uint16_t, 65535.0)
		READ(GL_INT, int32_t, 2147483647.0)
		READ(GL_UNSIGNED_INT, uint32_t, 4294967295.0)
		READ(GL_FLOAT, float, 1.0)
		READ(GL_DOUBLE, double, 1.0)
#undef READ
	default:
		break;
	}
	return (float)(normalise ? v / scale : v);
}

static struct view resolve(struct sgl_ctx *c, GLuint buffer, const void *pointer)
{
	if (!buffer)
		return (struct view){ pointer, SIZE_MAX };
	struct sgl_buffer *b = sgl_names_get(&c->ns->buffers, buffer);
	size_t offset = (size_t)(uintptr_t)pointer;
	if (!b || !b->data || offset > b->size)
		return (struct view){ NULL, 0 };
	return (struct view){ b->data + offset, b->size - offset };
}

/* Element i of array a into out (defaults from out kept). */
static bool fetch(const struct sgl_array *a, const struct view *v, uint32_t i, float out[4], bool normalise)
{
	size_t esize = type_size(a->type) * (size_t)a->size;
	size_t stride = a->stride ? (size_t)a->stride : esize;
	if (!v->base || !esize || a->size < 2 || a->size > 4)
		return false;
	if (v->limit != SIZE_MAX && ((size_t)i * stride > v->limit || v->limit - (size_t)i * stride < esize))
		return false;
	const uint8_t *p = v->base + (size_t)i * stride;
	for (int k = 0; k < a->size; k++)
		out[k] = component(a->type, p, k, normalise);
	return true;
}

struct draw {
	struct view vertex, color, index;
	GLenum index_type;
};

static void element(struct sgl_ctx *c, const struct draw *d, uint32_t i)
{
	float rgba[4] = { 0, 0, 0, 1 }, p[4] = { 0, 0, 0, 1 };
	if (c->color.enabled && fetch(&c->color, &d->color, i, rgba, true)) {
		/* No op in a list: GL leaves the colour after an array draw undefined. */
		struct sgl_colour *cs = c->rec ? &c->rec->cs : &c->cs;
		sgl_colour_set(cs, rgba);
		if (c->rec)
			c->rec->color_set = true;
	}
	if (fetch(&c->vertex, &d->vertex, i, p, false))
		sgl_vertex(c, p[0], p[1], p[2], p[3]);
}

static bool index_at(const struct draw *d, GLsizei i, uint32_t *out)
{
	size_t size = type_size(d->index_type), at = (size_t)i * size;
	if (!d->index.base || !size || at > d->index.limit || d->index.limit - at < size)
		return false;
	*out = (uint32_t)component(d->index_type, d->index.base + at, 0, false);
	return true;
}

/* indices NULL with index_type 0: glDrawArrays from first. */
static void draw(GLenum mode, GLint first, GLsizei count, GLenum index_type, const void *indices)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (!c->vertex.enabled || c->in_begin || count <= 0 || first < 0 || (!c->rec && !sgl_ctx_drawing(c)))
		return;
	if (index_type && index_type != GL_UNSIGNED_BYTE && index_type != GL_UNSIGNED_SHORT &&
	    index_type != GL_UNSIGNED_INT)
		return;
	pthread_mutex_lock(&c->ns->lock);
	struct draw d = {
		.vertex = resolve(c, c->vertex.buffer, c->vertex.pointer),
		.color = resolve(c, c->color.buffer, c->color.pointer),
		.index = index_type ? resolve(c, c->element_buffer, indices) : (struct view){ NULL, 0 },
		.index_type = index_type,
	};
	sgl_begin(c, mode);
	for (GLsizei i = 0; i < count && c->in_begin; i++) {
		uint32_t e = (uint32_t)first + (uint32_t)i;
		if (!index_type || index_at(&d, i, &e))
			element(c, &d, e);
	}
	sgl_end(c);
	pthread_mutex_unlock(&c->ns->lock);
}

void glDrawArrays(GLenum mode, GLint first, GLsizei count)
{
	draw(mode, first, count, 0, NULL);
	PASS(glDrawArrays, mode, first, count);
}

void glDrawElements(GLenum mode, GLsizei count, GLenum type, const void *indices)
{
	draw(mode, 0, count, type, indices);
	PASS(glDrawElements, mode, count, type, indices);
}

void glDrawRangeElements(GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type, const void *indices)
{
	draw(mode, 0, count, type, indices);
	PASS(glDrawRangeElements, mode, start, end, count, type, indices);
}

void glArrayElement(GLint i)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (c->in_begin && i >= 0) {
		pthread_mutex_lock(&c->ns->lock);
		struct draw d = {
			.vertex = resolve(c, c->vertex.buffer, c->vertex.pointer),
			.color = resolve(c, c->color.buffer, c->color.pointer),
		};
		if (c->vertex.enabled)
			element(c, &d, (uint32_t)i);
		pthread_mutex_unlock(&c->ns->lock);
	}
	PASS(glArrayElement, i);
}

static void set_array(struct sgl_array *a, struct sgl_ctx *c, GLint size, GLenum type, GLsizei stride,
		      const void *pointer)
{
	a->size = size;
	a->type = type;
	a->stride = stride;
	a->pointer = pointer;
	a->buffer = c->array_buffer;
}

void glVertexPointer(GLint size, GLenum type, GLsizei stride, const void *pointer)
{
	struct sgl_ctx *c = sgl_ctx_current();
	set_array(&c->vertex, c, size, type, stride, pointer);
	PASS(glVertexPointer, size, type, stride, pointer);
}

void glColorPointer(GLint size, GLenum type, GLsizei stride, const void *pointer)
{
	struct sgl_ctx *c = sgl_ctx_current();
	set_array(&c->color, c, size, type, stride, pointer);
	PASS(glColorPointer, size, type, stride, pointer);
}

static void client_state(GLenum array, bool on)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (array == GL_VERTEX_ARRAY)
		c->vertex.enabled = on;
	else if (array == GL_COLOR_ARRAY)
		c->color.enabled = on;
}

void glEnableClientState(GLenum array)
{
	client_state(array, true);
	PASS(glEnableClientState, array);
}

void glDisableClientState(GLenum array)
{
	client_state(array, false);
	PASS(glDisableClientState, array);
}

/* glInterleavedArrays' formats: the colour (size, type, offset; size 0:
 * none), the vertex (size, offset) and the element size. */
static const struct interleaved {
	GLenum format;
	GLint csize;
	GLenum ctype;
	GLint coff, vsize, voff, esize;
} formats[] = {
	{ GL_V2F, 0, 0, 0, 2, 0, 8 },
	{ GL_V3F, 0, 0, 0, 3, 0, 12 },
	{ GL_C4UB_V2F, 4, GL_UNSIGNED_BYTE, 0, 2, 4, 12 },
	{ GL_C4UB_V3F, 4, GL_UNSIGNED_BYTE, 0, 3, 4, 16 },
	{ GL_C3F_V3F, 3, GL_FLOAT, 0, 3, 12, 24 },
	{ GL_N3F_V3F, 0, 0, 0, 3, 12, 24 },
	{ GL_C4F_N3F_V3F, 4, GL_FLOAT, 0, 3, 28, 40 },
	{ GL_T2F_V3F, 0, 0, 0, 3, 8, 20 },
	{ GL_T4F_V4F, 0, 0, 0, 4, 16, 32 },
	{ GL_T2F_C4UB_V3F, 4, GL_UNSIGNED_BYTE, 8, 3, 12, 24 },
	{ GL_T2F_C3F_V3F, 3, GL_FLOAT, 8, 3, 20, 32 },
	{ GL_T2F_N3F_V3F, 0, 0, 0, 3, 20, 32 },
	{ GL_T2F_C4F_N3F_V3F, 4, GL_FLOAT, 8, 3, 36, 48 },
	{ GL_T4F_C4F_N3F_V4F, 4, GL_FLOAT, 16, 4, 44, 60 },
};

void glInterleavedArrays(GLenum format, GLsizei stride, const void *pointer)
{
	struct sgl_ctx *c = sgl_ctx_current();
	for (size_t i = 0; i < sizeof(formats) / sizeof(formats[0]); i++) {
		const struct interleaved *f = &formats[i];
		if (f->format != format || stride < 0)
			continue;
		GLsizei s = stride ? stride : f->esize;
		uintptr_t p = (uintptr_t)pointer; /* an offset when a buffer is bound */
		set_array(&c->vertex, c, f->vsize, GL_FLOAT, s, (const void *)(p + (uintptr_t)f->voff));
		c->vertex.enabled = true;
		c->color.enabled = f->csize > 0;
		if (f->csize)
			set_array(&c->color, c, f->csize, f->ctype, s, (const void *)(p + (uintptr_t)f->coff));
	}
	PASS(glInterleavedArrays, format, stride, pointer);
}
