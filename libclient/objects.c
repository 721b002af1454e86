/* libspindle: buffers, lists, layers, commit, status and capture. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "private.h"

struct spindle_buffer {
	struct lib_object base;
};

struct spindle_list {
	struct lib_object base;
};

struct spindle_layer {
	struct lib_object base;
};

struct spindle_volume {
	struct lib_object base;
};

static void *object_new(struct spindle *sp, size_t size)
{
	uint32_t id;
	struct lib_object *obj = lib_alloc(sp, size, &id);
	if (!obj)
		return NULL;
	obj->sp = sp;
	obj->id = id;
	link_append(&sp->objects, &obj->link);
	return obj;
}

void lib_object_free(struct lib_object *obj)
{
	link_remove(&obj->link);
	free(obj);
}

/* Queues a creation request's result; frees the object if it failed. */
static void *object_created(struct lib_object *obj, int r)
{
	r = lib_sent(obj->sp, r);
	if (r < 0) {
		lib_object_free(obj);
		errno = -r;
		return NULL;
	}
	return obj;
}

/* Sends a destructor request and frees the handle. */
static void object_destroyed(struct lib_object *obj, int (*req)(struct proto_conn *, uint32_t))
{
	if (!obj)
		return;
	if (!obj->sp->dead)
		lib_sent(obj->sp, req(obj->sp->conn, obj->id));
	lib_object_free(obj);
}

/* A sealed memfd holding a copy of data. -errno on failure. */
static int sealed_memfd(const void *data, size_t size)
{
	int fd = memfd_create("spindle-buffer", MFD_CLOEXEC | MFD_ALLOW_SEALING);
	if (fd < 0)
		return -errno;
	const char *p = data;
	size_t left = size;
	while (left > 0) {
		ssize_t n = write(fd, p, left);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0) {
			int e = n < 0 ? errno : EIO;
			close(fd);
			return -e;
		}
		p += n;
		left -= (size_t)n;
	}
	if (fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL) < 0) {
		int e = errno;
		close(fd);
		return -e;
	}
	return fd;
}

/* Fails a constructor with errno e. */
static void *fail_null(int e)
{
	errno = e;
	return NULL;
}

struct spindle_buffer *spindle_buffer_create(struct spindle *sp, const void *data, size_t size)
{
	if (size && !data)
		return fail_null(EINVAL);
	if (sp->version >= 2 && size <= SPINDLE_INLINE_MAX)
		return spindle_buffer_create_inline(sp, data, size);
	int fd = sealed_memfd(data, size);
	if (fd < 0)
		return fail_null(-fd);
	struct spindle_buffer *b = spindle_buffer_create_from_fd(sp, fd, size);
	int e = errno;
	close(fd);
	errno = e;
	return b;
}

struct spindle_buffer *spindle_buffer_create_inline(struct spindle *sp, const void *data, size_t size)
{
	if ((size && !data) || size > SPINDLE_INLINE_MAX)
		return fail_null(EINVAL);
	if (sp->version < 2)
		return fail_null(ENOTSUP);
	struct spindle_buffer *b = object_new(sp, sizeof(*b));
	if (!b)
		return NULL;
	return object_created(&b->base,
			      proto_req_display_create_buffer_inline(sp->conn, 1, b->base.id, data, (uint32_t)size));
}

struct spindle_buffer *spindle_buffer_create_from_fd(struct spindle *sp, int fd, uint64_t size)
{
	if (fd < 0)
		return fail_null(EBADF);
	struct spindle_buffer *b = object_new(sp, sizeof(*b));
	if (!b)
		return NULL;
	/* The writer duplicates fd into the queue: the caller keeps its own. */
	return object_created(&b->base, proto_req_display_create_buffer(sp->conn, 1, b->base.id, size, fd));
}

void spindle_buffer_destroy(struct spindle_buffer *buf)
{
	object_destroyed(buf ? &buf->base : NULL, proto_req_buffer_destroy);
}

struct spindle_list *spindle_list_create(struct spindle *sp)
{
	struct spindle_list *l = object_new(sp, sizeof(*l));
	if (!l)
		return NULL;
	return object_created(&l->base, proto_req_display_create_list(sp->conn, 1, l->base.id));
}

void spindle_list_destroy(struct spindle_list *list)
{
	object_destroyed(list ? &list->base : NULL, proto_req_list_destroy);
}

#define SEND(obj, call) ((obj)->sp->dead ? -EPIPE : lib_sent((obj)->sp, call))

int spindle_list_clear(struct spindle_list *list)
{
	return SEND(&list->base, proto_req_list_clear(list->base.sp->conn, list->base.id));
}

int spindle_list_set_color(struct spindle_list *list, uint8_t r, uint8_t g, uint8_t b, uint8_t a)
{
	uint32_t rgba = (uint32_t)r << 24 | (uint32_t)g << 16 | (uint32_t)b << 8 | a;
	return SEND(&list->base, proto_req_list_set_color(list->base.sp->conn, list->base.id, rgba));
}

int spindle_list_set_transform(struct spindle_list *list, const float m[16])
{
	return SEND(&list->base, proto_req_list_set_transform(list->base.sp->conn, list->base.id, m));
}

/* Version 2 requests fail locally on a version 1 connection. */
#define SEND_V2(obj, call) ((obj)->sp->version < 2 && !(obj)->sp->dead ? -ENOTSUP : SEND(obj, call))

int spindle_list_draw(struct spindle_list *list, enum spindle_mode mode, struct spindle_buffer *buf, size_t offset,
		      uint32_t count, uint32_t stride)
{
	if (!buf || buf->base.sp != list->base.sp)
		return -EINVAL;
	if (mode == SPINDLE_LINE_STRIP && list->base.sp->version < 2)
		return -ENOTSUP;
	return SEND(&list->base,
		    proto_req_list_draw(list->base.sp->conn, list->base.id, mode, buf->base.id, offset, count, stride));
}

int spindle_list_draw_indexed(struct spindle_list *list, enum spindle_mode mode, struct spindle_buffer *vertices,
			      size_t offset, uint32_t vertex_count, uint32_t stride, struct spindle_buffer *indices,
			      size_t index_offset, uint32_t index_count, enum spindle_index_type index_type)
{
	if (!vertices || !indices || vertices->base.sp != list->base.sp || indices->base.sp != list->base.sp)
		return -EINVAL;
	struct proto_list_draw_indexed_args a = {
		.mode = mode,
		.vertices = vertices->base.id,
		.offset = offset,
		.vertex_count = vertex_count,
		.stride = stride,
		.indices = indices->base.id,
		.index_offset = index_offset,
		.index_count = index_count,
		.index_type = index_type,
	};
	return SEND_V2(&list->base, proto_req_list_draw_indexed(list->base.sp->conn, list->base.id, &a));
}

int spindle_list_set_vertex_format(struct spindle_list *list, enum spindle_vertex_format format)
{
	return SEND_V2(&list->base, proto_req_list_set_vertex_format(list->base.sp->conn, list->base.id, format));
}

int spindle_list_set_point_size(struct spindle_list *list, uint32_t size)
{
	return SEND_V2(&list->base, proto_req_list_set_point_size(list->base.sp->conn, list->base.id, size));
}

int spindle_list_push(struct spindle_list *list)
{
	return SEND_V2(&list->base, proto_req_list_push(list->base.sp->conn, list->base.id));
}

int spindle_list_pop(struct spindle_list *list)
{
	return SEND_V2(&list->base, proto_req_list_pop(list->base.sp->conn, list->base.id));
}

int spindle_list_multiply_transform(struct spindle_list *list, const float m[16])
{
	return SEND_V2(&list->base, proto_req_list_multiply_transform(list->base.sp->conn, list->base.id, m));
}

int spindle_list_points(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
			uint32_t stride)
{
	return spindle_list_draw(list, SPINDLE_POINTS, buf, offset, count, stride);
}

int spindle_list_lines(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
		       uint32_t stride)
{
	return spindle_list_draw(list, SPINDLE_LINES, buf, offset, count, stride);
}

int spindle_list_triangles(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
			   uint32_t stride)
{
	return spindle_list_draw(list, SPINDLE_TRIANGLES, buf, offset, count, stride);
}

struct spindle_volume *spindle_volume_create(struct spindle *sp, struct spindle_buffer *buf, uint64_t offset,
					     enum spindle_volume_type type, const uint32_t size[3],
					     const float spacing[3])
{
	if (!buf || !size || !spacing)
		return fail_null(EINVAL);
	if (sp->version < 6)
		return fail_null(EPROTONOSUPPORT);
	struct spindle_volume *v = object_new(sp, sizeof(*v));
	if (!v)
		return NULL;
	struct proto_display_create_volume_args a = {
		.id = v->base.id,
		.buffer = buf->base.id,
		.offset = offset,
		.type = (uint32_t)type,
		.nx = size[0],
		.ny = size[1],
		.nz = size[2],
		.sx = spacing[0],
		.sy = spacing[1],
		.sz = spacing[2],
	};
	return object_created(&v->base, proto_req_display_create_volume(sp->conn, 1, &a));
}

void spindle_volume_destroy(struct spindle_volume *vol)
{
	object_destroyed(vol ? &vol->base : NULL, proto_req_volume_destroy);
}

#define SEND_V6(obj, call) ((obj)->sp->version < 6 && !(obj)->sp->dead ? -EPROTONOSUPPORT : SEND(obj, call))

int spindle_list_draw_volume(struct spindle_list *list, struct spindle_volume *vol, enum spindle_sampling sampling,
			     float threshold, float window_center, float window_width)
{
	if (!vol)
		return -EINVAL;
	return SEND_V6(&list->base,
		       proto_req_list_draw_volume(list->base.sp->conn, list->base.id, vol->base.id, (uint32_t)sampling,
						  threshold, window_center, window_width));
}

int spindle_list_set_volume_lut(struct spindle_list *list, struct spindle_buffer *buf, uint64_t offset, uint32_t count)
{
	if (!buf)
		return -EINVAL;
	return SEND_V6(&list->base,
		       proto_req_list_set_volume_lut(list->base.sp->conn, list->base.id, buf->base.id, offset, count));
}

struct spindle_layer *spindle_layer_create(struct spindle *sp)
{
	struct spindle_layer *y = object_new(sp, sizeof(*y));
	if (!y)
		return NULL;
	return object_created(&y->base, proto_req_display_create_layer(sp->conn, 1, y->base.id));
}

void spindle_layer_destroy(struct spindle_layer *layer)
{
	object_destroyed(layer ? &layer->base : NULL, proto_req_layer_destroy);
}

int spindle_layer_set_list(struct spindle_layer *layer, struct spindle_list *list)
{
	if (list && list->base.sp != layer->base.sp)
		return -EINVAL;
	return SEND(&layer->base,
		    proto_req_layer_set_list(layer->base.sp->conn, layer->base.id, list ? list->base.id : 0));
}

int spindle_layer_set_transform(struct spindle_layer *layer, const float m[16])
{
	return SEND(&layer->base, proto_req_layer_set_transform(layer->base.sp->conn, layer->base.id, m));
}

int spindle_layer_set_visible(struct spindle_layer *layer, bool visible)
{
	return SEND(&layer->base, proto_req_layer_set_visible(layer->base.sp->conn, layer->base.id, visible));
}

int spindle_layer_set_priority(struct spindle_layer *layer, int32_t priority)
{
	return SEND_V2(&layer->base, proto_req_layer_set_priority(layer->base.sp->conn, layer->base.id, priority));
}

int spindle_layer_set_exclusive(struct spindle_layer *layer, bool exclusive)
{
	return SEND_V2(&layer->base, proto_req_layer_set_exclusive(layer->base.sp->conn, layer->base.id, exclusive));
}

struct lib_callback *lib_request_frame(struct spindle *sp, spindle_frame_func func, void *data)
{
	struct lib_callback *cb = lib_callback_add(sp, LIB_CALLBACK_FRAME);
	if (!cb)
		return NULL;
	cb->func = func;
	cb->data = data;
	int r = lib_sent(sp, proto_req_display_frame(sp->conn, 1, cb->id));
	if (r < 0) {
		lib_callback_remove(sp, cb);
		return fail_null(-r);
	}
	return cb;
}

int spindle_request_frame(struct spindle *sp, spindle_frame_func func, void *data)
{
	return lib_request_frame(sp, func, data) ? 0 : -errno;
}

int spindle_commit(struct spindle *sp)
{
	if (sp->dead)
		return -EPIPE;
	int r = lib_sent(sp, proto_req_display_commit(sp->conn, 1));
	if (r == 0)
		r = spindle_flush(sp);
	return r == -EAGAIN ? 0 : r;
}

static void store_frame(void *data, const struct spindle_frame *frame)
{
	struct spindle_frame *out = data;
	*out = *frame;
}

static bool frame_arrived(struct spindle *sp, void *data)
{
	return ((struct spindle_frame *)data)->time_ns != 0 || ((struct spindle_frame *)data)->volume_seq != 0;
}

static int refusal_errno(uint32_t code)
{
	switch (code) {
	case SPINDLE_REFUSED_QUOTA:
		return -EDQUOT;
	case SPINDLE_REFUSED_DENIED:
		return -EACCES;
	case SPINDLE_REFUSED_BUSY:
		return -EBUSY;
	}
	return -EPERM;
}

/* Only refused commits get an answer, so whether this one was refused is
 * known once a sync sent after it is answered; refusals of earlier
 * commits are collected by a roundtrip first. */
int spindle_commit_and_wait(struct spindle *sp, struct spindle_frame *frame)
{
	struct spindle_frame got = { 0 };
	int r = sp->version >= 2 ? spindle_roundtrip(sp) : 0;
	uint64_t refusals = sp->refusals;
	struct lib_callback *cb = r == 0 ? lib_request_frame(sp, store_frame, &got) : NULL;
	if (r == 0 && !cb)
		r = -errno;
	if (r == 0)
		r = spindle_commit(sp);
	if (r == 0 && sp->version >= 2)
		r = spindle_roundtrip(sp);
	if (r == 0 && sp->refusals != refusals) {
		cb->data = NULL; /* still pending; it fires with a later commit */
		cb->func = NULL;
		return refusal_errno(sp->last_refusal);
	}
	if (r == 0)
		r = lib_wait(sp, frame_arrived, &got);
	if (r == 0 && frame)
		*frame = got;
	return r;
}

static bool status_arrived(struct spindle *sp, void *data)
{
	return sp->status_serial != *(uint64_t *)data;
}

int spindle_get_status(struct spindle *sp, struct spindle_status *out)
{
	if (sp->dead)
		return -EPIPE;
	uint64_t serial = sp->status_serial;
	int r = lib_sent(sp, proto_req_display_get_status(sp->conn, 1));
	if (r == 0)
		r = lib_wait(sp, status_arrived, &serial);
	if (r == 0)
		*out = sp->status;
	return r;
}

/* A private, read-only description of the memfd, positioned at 0: the one
 * received shares its offset with the daemon and other clients. */
static int reopen_readonly(int fd)
{
	char path[64];
	snprintf(path, sizeof(path), "/proc/self/fd/%d", fd);
	return open(path, O_RDONLY | O_CLOEXEC);
}

int spindle_capture(struct spindle *sp, int *fd, size_t *size)
{
	struct lib_callback *cb = lib_callback_add(sp, LIB_CALLBACK_CAPTURE);
	if (!cb)
		return -errno;
	int r = lib_sent(sp, proto_req_display_capture(sp->conn, 1, cb->id));
	if (r == 0)
		r = lib_wait_callback(sp, cb);
	if (r == 0 && cb->error)
		r = cb->error;
	if (r == 0) {
		*fd = reopen_readonly(cb->fd);
		*size = (size_t)cb->size;
		if (*fd < 0)
			r = -errno;
	}
	lib_callback_remove(sp, cb);
	return r;
}
