/* Buffers, display lists and layers: their requests, and commit. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "client.h"
#include "server.h"

static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };

struct vdata *vdata_ref(struct vdata *v)
{
	v->refs++;
	return v;
}

void vdata_unref(struct vdata *v)
{
	if (v && --v->refs == 0)
		free(v);
}

int object_register(struct client *c, struct object *obj, uint32_t id, enum proto_interface type)
{
	if (id < 2 || id > 0xfeffffffu)
		return client_fail(c, 1, PROTO_ERR_OBJECT, "new id %u out of range", id);
	if (idmap_get(&c->objects, id))
		return client_fail(c, 1, PROTO_ERR_OBJECT, "id %u already in use", id);
	if (c->objects.count >= c->server->cfg.max_objects)
		return client_fail(c, 1, PROTO_ERR_QUOTA, "more than %u objects", c->server->cfg.max_objects);
	if (idmap_insert(&c->objects, id, obj) < 0)
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	obj->id = id;
	obj->type = type;
	obj->client = c;
	return 0;
}

/* ---- buffers ---- */

static void buffer_free(struct buffer *b)
{
	if (b->map)
		munmap((void *)b->map, b->size ? b->size : 1);
	b->base.client->buffer_bytes -= b->size;
	free(b);
}

/* The fd must be a memfd sealed against shrinking, at least size bytes. */
static int check_memfd(struct client *c, int fd, uint64_t size)
{
	int seals = fcntl(fd, F_GET_SEALS);
	if (seals < 0)
		return client_fail(c, 1, PROTO_ERR_FD, "buffer fd is not a memfd");
	if (!(seals & F_SEAL_SHRINK))
		return client_fail(c, 1, PROTO_ERR_FD, "buffer memfd is not sealed against shrinking");
	struct stat st;
	if (fstat(fd, &st) < 0 || (uint64_t)st.st_size < size)
		return client_fail(c, 1, PROTO_ERR_FD, "buffer memfd smaller than its declared size %llu",
				   (unsigned long long)size);
	return 0;
}

int objects_create_buffer(struct client *c, uint32_t id, uint64_t size, int fd)
{
	int r = check_memfd(c, fd, size);
	if (r < 0)
		goto out_close;
	if (size > c->server->cfg.max_buffer_bytes - c->buffer_bytes || size > SIZE_MAX / 2) {
		r = client_fail(c, 1, PROTO_ERR_QUOTA, "buffers over %llu bytes",
				(unsigned long long)c->server->cfg.max_buffer_bytes);
		goto out_close;
	}
	struct buffer *b = calloc(1, sizeof(*b));
	if (!b) {
		r = client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
		goto out_close;
	}
	if (size) {
		void *map = mmap(NULL, size, PROT_READ, MAP_SHARED, fd, 0);
		if (map == MAP_FAILED) {
			free(b);
			r = client_fail(c, 1, PROTO_ERR_FD, "cannot map buffer: %s", strerror(errno));
			goto out_close;
		}
		b->map = map;
	}
	b->size = size;
	c->buffer_bytes += size;
	b->base.client = c;
	r = object_register(c, &b->base, id, PROTO_IFACE_BUFFER);
	if (r < 0)
		buffer_free(b);
out_close:
	close(fd);
	return r;
}

/* The destroy request of buffers, lists and layers. */
static int destroy_req(void *target)
{
	object_destroy(target);
	return 0;
}

const struct proto_buffer_requests buffer_requests = {
	.destroy = destroy_req,
};

/* ---- lists ---- */

static void draws_clear(struct draw_array *a)
{
	for (uint32_t i = 0; i < a->count; i++)
		vdata_unref(a->draws[i].data);
	a->count = 0;
	a->vertices = 0;
}

static void draws_finish(struct draw_array *a)
{
	draws_clear(a);
	free(a->draws);
	*a = (struct draw_array){ 0 };
}

static int draws_append(struct draw_array *a, const struct list_draw *d)
{
	if (a->count == a->cap) {
		uint32_t cap = a->cap ? a->cap * 2 : 8;
		struct list_draw *draws = realloc(a->draws, cap * sizeof(*draws));
		if (!draws)
			return -ENOMEM;
		a->draws = draws;
		a->cap = cap;
	}
	a->draws[a->count++] = *d;
	a->vertices += d->data->count;
	return 0;
}

/* dst = src, sharing vertex data. */
static int draws_copy(struct draw_array *dst, const struct draw_array *src)
{
	draws_clear(dst);
	for (uint32_t i = 0; i < src->count; i++) {
		struct list_draw d = src->draws[i];
		vdata_ref(d.data);
		if (draws_append(dst, &d) < 0) {
			vdata_unref(d.data);
			return -ENOMEM;
		}
	}
	return 0;
}

void list_unref(struct list *l)
{
	if (!l || --l->refs > 0)
		return;
	struct client *c = l->base.client;
	if (c)
		c->vertices -= l->pending.vertices;
	draws_finish(&l->pending);
	draws_finish(&l->committed);
	link_remove(&l->link);
	free(l);
}

static void list_reset_state(struct list *l)
{
	memset(l->color, 255, 4);
	memcpy(l->transform, identity, sizeof(identity));
}

int objects_create_list(struct client *c, uint32_t id)
{
	struct list *l = calloc(1, sizeof(*l));
	if (!l)
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	link_init(&l->link);
	l->refs = 1;
	list_reset_state(l);
	int r = object_register(c, &l->base, id, PROTO_IFACE_LIST);
	if (r < 0) {
		free(l);
		return r;
	}
	link_append(&c->lists, &l->link);
	return 0;
}

static int list_clear(void *target)
{
	struct list *l = target;
	l->base.client->vertices -= l->pending.vertices;
	draws_clear(&l->pending);
	list_reset_state(l);
	l->changed = true;
	return 0;
}

static int list_set_color(void *target, const struct proto_list_set_color_args *a)
{
	struct list *l = target;
	l->color[0] = (uint8_t)(a->rgba >> 24);
	l->color[1] = (uint8_t)(a->rgba >> 16);
	l->color[2] = (uint8_t)(a->rgba >> 8);
	l->color[3] = (uint8_t)a->rgba;
	return 0;
}

/* A transform must be finite, affine (bottom row 0 0 0 1) and within a sane
 * range; anything else is a fatal error of obj's client. */
static int check_transform(struct object *obj, const float m[16])
{
	for (int i = 0; i < 16; i++)
		if (!isfinite(m[i]) || fabsf(m[i]) > 1e6f)
			goto bad;
	if (m[3] == 0 && m[7] == 0 && m[11] == 0 && m[15] == 1)
		return 0;
bad:
	return client_fail(obj->client, obj->id, PROTO_ERR_VALUE, "transform is not a finite affine matrix");
}

static int list_set_transform(void *target, const struct proto_list_set_transform_args *a)
{
	struct list *l = target;
	if (check_transform(&l->base, a->matrix) < 0)
		return -EPROTO;
	memcpy(l->transform, a->matrix, sizeof(l->transform));
	return 0;
}

/* Checks a draw's vertex range against its buffer, overflow-safe. */
static bool draw_range_valid(const struct buffer *b, uint64_t offset, uint32_t count, uint32_t stride)
{
	if (count == 0)
		return offset <= b->size;
	uint64_t last = (uint64_t)(count - 1) * stride; /* < 2^64: both < 2^32 */
	return offset <= b->size && last <= b->size - offset && 12 <= b->size - offset - last;
}

static int draw_check(struct list *l, const struct proto_list_draw_args *a, struct buffer **out)
{
	struct client *c = l->base.client;
	static const uint32_t multiple[] = { 1, 2, 3 };
	if (a->mode > PROTO_LIST_MODE_TRIANGLES)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw mode %u unknown", a->mode);
	struct buffer *b = idmap_get(&c->objects, a->buffer);
	if (!b || b->base.type != PROTO_IFACE_BUFFER)
		return client_fail(c, l->base.id, PROTO_ERR_OBJECT, "draw: %u is not a buffer", a->buffer);
	uint32_t stride = a->stride ? a->stride : 12;
	if (stride < 12 || stride > 65536)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw: stride %u", a->stride);
	if (a->count % multiple[a->mode] != 0)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw: %u vertices do not make whole primitives",
				   a->count);
	if (!draw_range_valid(b, a->offset, a->count, stride))
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw: vertices past the end of buffer %u",
				   a->buffer);
	if (a->count > c->server->cfg.max_vertices - c->vertices)
		return client_fail(c, l->base.id, PROTO_ERR_QUOTA, "more than %llu vertices",
				   (unsigned long long)c->server->cfg.max_vertices);
	*out = b;
	return 0;
}

static int list_draw(void *target, const struct proto_list_draw_args *a)
{
	struct list *l = target;
	struct buffer *b = NULL;
	int r = draw_check(l, a, &b);
	if (r < 0 || a->count == 0)
		return r;
	uint32_t stride = a->stride ? a->stride : 12;
	struct vdata *v = malloc(sizeof(*v) + (size_t)a->count * 12);
	if (!v)
		return client_fail(l->base.client, l->base.id, PROTO_ERR_NO_MEMORY, "out of memory");
	v->refs = 1;
	v->count = a->count;
	const uint8_t *src = b->map + a->offset;
	if (stride == 12)
		memcpy(v->xyz, src, (size_t)a->count * 12);
	else
		for (uint32_t i = 0; i < a->count; i++)
			memcpy(v->xyz + 3 * (size_t)i, src + (size_t)i * stride, 12);
	struct list_draw d = { .prim = (enum scene_prim)a->mode, .data = v };
	memcpy(d.transform, l->transform, sizeof(d.transform));
	memcpy(d.rgba, l->color, 4);
	if (draws_append(&l->pending, &d) < 0) {
		vdata_unref(v);
		return client_fail(l->base.client, l->base.id, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	l->base.client->vertices += a->count;
	l->changed = true;
	return 0;
}

const struct proto_list_requests list_requests = {
	.destroy = destroy_req,
	.clear = list_clear,
	.set_color = list_set_color,
	.set_transform = list_set_transform,
	.draw = list_draw,
};

/* ---- layers ---- */

int objects_create_layer(struct client *c, uint32_t id)
{
	struct layer *y = calloc(1, sizeof(*y));
	if (!y)
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	link_init(&y->link);
	memcpy(y->pending.transform, identity, sizeof(identity));
	y->pending.visible = true;
	y->committed = y->pending;
	int r = object_register(c, &y->base, id, PROTO_IFACE_LAYER);
	if (r < 0) {
		free(y);
		return r;
	}
	link_append(&c->layers, &y->link);
	return 0;
}

static void layer_free(struct layer *y)
{
	list_unref(y->pending.list);
	list_unref(y->committed.list);
	link_remove(&y->link);
	free(y);
}

static int layer_set_list(void *target, const struct proto_layer_set_list_args *a)
{
	struct layer *y = target;
	struct list *l = NULL;
	if (a->list) {
		l = idmap_get(&y->base.client->objects, a->list);
		if (!l || l->base.type != PROTO_IFACE_LIST)
			return client_fail(y->base.client, y->base.id, PROTO_ERR_OBJECT, "%u is not a list", a->list);
		l->refs++;
	}
	list_unref(y->pending.list);
	y->pending.list = l;
	y->changed = true;
	return 0;
}

static int layer_set_transform(void *target, const struct proto_layer_set_transform_args *a)
{
	struct layer *y = target;
	if (check_transform(&y->base, a->matrix) < 0)
		return -EPROTO;
	memcpy(y->pending.transform, a->matrix, sizeof(y->pending.transform));
	y->changed = true;
	return 0;
}

static int layer_set_visible(void *target, const struct proto_layer_set_visible_args *a)
{
	struct layer *y = target;
	if (a->visible > 1)
		return client_fail(y->base.client, y->base.id, PROTO_ERR_VALUE, "visible must be 0 or 1");
	y->pending.visible = a->visible;
	y->changed = true;
	return 0;
}

const struct proto_layer_requests layer_requests = {
	.destroy = destroy_req,
	.set_list = layer_set_list,
	.set_transform = layer_set_transform,
	.set_visible = layer_set_visible,
};

/* ---- commit and destruction ---- */

bool objects_commit(struct client *c)
{
	bool changed = false;
	struct list *l;
	struct layer *y;
	link_for_each(l, &c->lists, link) {
		if (!l->changed)
			continue;
		if (draws_copy(&l->committed, &l->pending) < 0)
			return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory"), false;
		l->changed = false;
		changed = true;
	}
	link_for_each(y, &c->layers, link) {
		if (!y->changed)
			continue;
		if (y->pending.list)
			y->pending.list->refs++;
		list_unref(y->committed.list);
		y->committed = y->pending;
		y->changed = false;
		changed = true;
	}
	return changed;
}

void object_destroy(struct object *obj)
{
	struct client *c = obj->client;
	idmap_remove(&c->objects, obj->id);
	switch (obj->type) {
	case PROTO_IFACE_BUFFER:
		buffer_free((struct buffer *)obj);
		break;
	case PROTO_IFACE_LIST:
		list_unref((struct list *)obj);
		break;
	case PROTO_IFACE_LAYER: {
		struct layer *y = (struct layer *)obj;
		/* A departing client's layers are accounted for by the reaper. */
		if (!c->dead)
			server_scene_changed(c->server, y->committed.visible && y->committed.list);
		layer_free(y);
		break;
	}
	case PROTO_IFACE_CALLBACK:
	case PROTO_IFACE_CAPTURE: {
		struct waiter *w = (struct waiter *)obj;
		link_remove(&w->link);
		free(w);
		break;
	}
	case PROTO_IFACE_DISPLAY:
		break;
	}
}
