/* Buffer objects holding client arrays or indices (GL_ARRAY_BUFFER,
 * GL_ELEMENT_ARRAY_BUFFER): the layer keeps a copy of their contents, from
 * glBufferData, glBufferSubData and what was written through a mapping
 * (read back at glUnmapBuffer). The ARB names too. */
#include <stdlib.h>
#include <string.h>

#include "ctx.h"
#include "real.h"

static GLuint *binding(struct sgl_ctx *c, GLenum target)
{
	if (target == GL_ARRAY_BUFFER)
		return &c->array_buffer;
	if (target == GL_ELEMENT_ARRAY_BUFFER)
		return &c->element_buffer;
	return NULL;
}

/* The shadow of the buffer bound to target (made if new), under the
 * share group's lock (held on return when not NULL). */
static struct sgl_buffer *bound(struct sgl_ctx *c, GLenum target)
{
	GLuint *b = binding(c, target);
	if (!b || !*b)
		return NULL;
	pthread_mutex_lock(&c->ns->lock);
	struct sgl_buffer *buf = sgl_names_get(&c->ns->buffers, *b);
	bool ok = true;
	if (!buf && (buf = calloc(1, sizeof(*buf))))
		sgl_names_put(&c->ns->buffers, *b, buf, &ok);
	if (!buf || !ok) {
		free(buf);
		pthread_mutex_unlock(&c->ns->lock);
		return NULL;
	}
	return buf;
}

static void bind(GLenum target, GLuint buffer)
{
	GLuint *b = binding(sgl_ctx_current(), target);
	if (b)
		*b = buffer;
}

static void data(GLenum target, GLsizeiptr size, const void *src)
{
	struct sgl_ctx *c = sgl_ctx_current();
	struct sgl_buffer *b = size >= 0 ? bound(c, target) : NULL;
	if (!b)
		return;
	uint8_t *d = realloc(b->data, size ? (size_t)size : 1);
	if (d) {
		b->data = d;
		b->size = (size_t)size;
		if (src && size)
			memcpy(d, src, (size_t)size);
		else if (size)
			memset(d, 0, (size_t)size);
	}
	pthread_mutex_unlock(&c->ns->lock);
}

static void sub_data(GLenum target, GLintptr offset, GLsizeiptr size, const void *src)
{
	struct sgl_ctx *c = sgl_ctx_current();
	struct sgl_buffer *b = src && offset >= 0 && size > 0 ? bound(c, target) : NULL;
	if (!b)
		return;
	if ((size_t)offset <= b->size && b->size - (size_t)offset >= (size_t)size)
		memcpy(b->data + offset, src, (size_t)size);
	pthread_mutex_unlock(&c->ns->lock);
}

static void delete (GLsizei n, const GLuint *names)
{
	struct sgl_ctx *c = sgl_ctx_current();
	for (GLsizei i = 0; names && i < n; i++) {
		pthread_mutex_lock(&c->ns->lock);
		struct sgl_buffer *b = sgl_names_remove(&c->ns->buffers, names[i]);
		pthread_mutex_unlock(&c->ns->lock);
		if (b)
			free(b->data);
		free(b);
		if (c->array_buffer == names[i])
			c->array_buffer = 0;
		if (c->element_buffer == names[i])
			c->element_buffer = 0;
	}
}

static void mapped(GLenum target, void *p, size_t offset, size_t length, bool writes)
{
	struct sgl_ctx *c = sgl_ctx_current();
	struct sgl_buffer *b = p ? bound(c, target) : NULL;
	if (!b)
		return;
	if (offset <= b->size && b->size - offset >= length) {
		b->mapped = p;
		b->map_offset = offset;
		b->map_length = length;
		b->map_writes = writes;
	}
	pthread_mutex_unlock(&c->ns->lock);
}

/* Before the real unmap: what the program wrote through the mapping. */
static void unmapping(GLenum target)
{
	struct sgl_ctx *c = sgl_ctx_current();
	struct sgl_buffer *b = bound(c, target);
	if (!b)
		return;
	if (b->mapped && b->map_writes && b->data)
		memcpy(b->data + b->map_offset, b->mapped, b->map_length);
	b->mapped = NULL;
	pthread_mutex_unlock(&c->ns->lock);
}

static GLsizeiptr bound_size(GLenum target)
{
	struct sgl_ctx *c = sgl_ctx_current();
	struct sgl_buffer *b = bound(c, target);
	if (!b)
		return 0;
	GLsizeiptr size = (GLsizeiptr)b->size;
	pthread_mutex_unlock(&c->ns->lock);
	return size;
}

void glBindBuffer(GLenum target, GLuint buffer)
{
	bind(target, buffer);
	PASS(glBindBuffer, target, buffer);
}

void glBindBufferARB(GLenum target, GLuint buffer)
{
	bind(target, buffer);
	PASS(glBindBufferARB, target, buffer);
}

void glBufferData(GLenum target, GLsizeiptr size, const void *src, GLenum usage)
{
	data(target, size, src);
	PASS(glBufferData, target, size, src, usage);
}

void glBufferDataARB(GLenum target, GLsizeiptrARB size, const void *src, GLenum usage)
{
	data(target, size, src);
	PASS(glBufferDataARB, target, size, src, usage);
}

void glBufferSubData(GLenum target, GLintptr offset, GLsizeiptr size, const void *src)
{
	sub_data(target, offset, size, src);
	PASS(glBufferSubData, target, offset, size, src);
}

void glBufferSubDataARB(GLenum target, GLintptrARB offset, GLsizeiptrARB size, const void *src)
{
	sub_data(target, offset, size, src);
	PASS(glBufferSubDataARB, target, offset, size, src);
}

void glDeleteBuffers(GLsizei n, const GLuint *names)
{
	delete (n, names);
	PASS(glDeleteBuffers, n, names);
}

void glDeleteBuffersARB(GLsizei n, const GLuint *names)
{
	delete (n, names);
	PASS(glDeleteBuffersARB, n, names);
}

void *glMapBuffer(GLenum target, GLenum access)
{
	__typeof__(&glMapBuffer) real = REAL(glMapBuffer);
	void *p = real ? real(target, access) : NULL;
	mapped(target, p, 0, (size_t)bound_size(target), access != GL_READ_ONLY);
	return p;
}

void *glMapBufferARB(GLenum target, GLenum access)
{
	__typeof__(&glMapBufferARB) real = REAL(glMapBufferARB);
	void *p = real ? real(target, access) : NULL;
	mapped(target, p, 0, (size_t)bound_size(target), access != GL_READ_ONLY);
	return p;
}

void *glMapBufferRange(GLenum target, GLintptr offset, GLsizeiptr length, GLbitfield access)
{
	__typeof__(&glMapBufferRange) real = REAL(glMapBufferRange);
	void *p = real ? real(target, offset, length, access) : NULL;
	if (offset >= 0 && length >= 0)
		mapped(target, p, (size_t)offset, (size_t)length, access & GL_MAP_WRITE_BIT);
	return p;
}

GLboolean glUnmapBuffer(GLenum target)
{
	unmapping(target);
	__typeof__(&glUnmapBuffer) real = REAL(glUnmapBuffer);
	return real ? real(target) : GL_FALSE;
}

GLboolean glUnmapBufferARB(GLenum target)
{
	unmapping(target);
	__typeof__(&glUnmapBufferARB) real = REAL(glUnmapBufferARB);
	return real ? real(target) : GL_FALSE;
}
