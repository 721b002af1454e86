/* Buffers, display lists and layers: their requests, and commit. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "client.h"
#include "config.h"
#include "geometry.h"
#include "mat4.h"
#include "stage.h"
#include "turn.h"

static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };

int object_register(struct client *c, struct object *obj, uint32_t id, enum proto_interface type)
{
	if (id < 2 || id > 0xfeffffffu)
		return client_fail(c, 1, PROTO_ERR_OBJECT, "new id %u out of range", id);
	if (idmap_get(&c->objects, id))
		return client_fail(c, 1, PROTO_ERR_OBJECT, "id %u already in use", id);
	if (c->objects.count >= c->env->cfg->max_objects)
		return client_fail(c, 1, PROTO_ERR_QUOTA, "more than %u objects", c->env->cfg->max_objects);
	if (idmap_insert(&c->objects, id, obj) < 0)
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	obj->id = id;
	obj->type = type;
	obj->client = c;
	return 0;
}

/* ---- the client's and the daemon-wide accounting ---- */

/* Bytes counted against memory-budget. */
static uint64_t budget_used(const struct client_totals *t)
{
	return t->buffer_bytes + t->vertices * CLIENT_VERTEX_BYTES;
}

/* Room for bytes more under memory-budget; else c is failed (quota). */
int objects_budget_room(struct client *c, uint64_t bytes)
{
	struct client_totals *t = c->env->totals;
	uint64_t budget = c->env->cfg->memory_budget, used = budget_used(t);
	if (used <= budget && bytes <= budget - used)
		return 0;
	t->refused_memory++;
	return client_fail(c, 1, PROTO_ERR_QUOTA, "the daemon's memory budget is used up (%llu of %llu bytes)",
			   (unsigned long long)used, (unsigned long long)budget);
}

/* Vertices more the budget has room for. */
static uint64_t budget_vertices(const struct client *c)
{
	uint64_t budget = c->env->cfg->memory_budget, used = budget_used(c->env->totals);
	return used < budget ? (budget - used) / CLIENT_VERTEX_BYTES : 0;
}

void objects_account_buffer(struct client *c, int64_t bytes, int mappings)
{
	c->buffer_bytes += (uint64_t)bytes;
	c->env->totals->buffer_bytes += (uint64_t)bytes;
	c->env->totals->mappings += (uint32_t)mappings;
}

static void account_vertices(struct client *c, int64_t n)
{
	c->vertices += (uint64_t)n;
	c->env->totals->vertices += (uint64_t)n;
}

int objects_charge(struct client *c, uint64_t bytes)
{
	if (bytes > c->env->cfg->max_buffer_bytes - c->buffer_bytes)
		return client_fail(c, 1, PROTO_ERR_QUOTA, "buffers and volumes over %llu bytes",
				   (unsigned long long)c->env->cfg->max_buffer_bytes);
	if (objects_budget_room(c, bytes) < 0)
		return -EPROTO;
	objects_account_buffer(c, (int64_t)bytes, 0);
	return 0;
}

void objects_uncharge(struct client *c, uint64_t bytes)
{
	objects_account_buffer(c, -(int64_t)bytes, 0);
}

int objects_destroy_req(void *target)
{
	object_destroy(target);
	return 0;
}

/* ---- lists ---- */

static void draws_clear(struct draw_array *a)
{
	for (uint32_t i = 0; i < a->count; i++)
		vdata_unref(a->items[i].data);
	a->count = 0;
	a->vertices = 0;
	a->prims = 0;
}

static void draws_finish(struct draw_array *a)
{
	draws_clear(a);
	free(a->items);
	*a = (struct draw_array){ 0 };
}

static int draws_append(struct draw_array *a, const struct list_item *d)
{
	if (a->count == a->cap) {
		uint32_t cap = a->cap ? a->cap * 2 : 8;
		struct list_item *items = realloc(a->items, cap * sizeof(*items));
		if (!items)
			return -ENOMEM;
		a->items = items;
		a->cap = cap;
	}
	a->items[a->count++] = *d;
	a->vertices += d->data->count;
	a->prims += d->data->prims;
	return 0;
}

/* dst = src, sharing vertex data. */
static int draws_copy(struct draw_array *dst, const struct draw_array *src)
{
	draws_clear(dst);
	for (uint32_t i = 0; i < src->count; i++) {
		struct list_item d = src->items[i];
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
		account_vertices(c, -(int64_t)l->pending.vertices);
	draws_finish(&l->pending);
	draws_finish(&l->committed);
	link_remove(&l->link);
	free(l->lut);
	free(l);
}

static void list_reset_state(struct list *l)
{
	memset(l->state.color, 255, 4);
	memcpy(l->state.transform, identity, sizeof(identity));
	l->state.point_size = 1;
	l->state.format = DRAW_XYZ;
	l->depth = 0;
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

/* A fatal error of list l's client, on l. */
#define list_fail(l, code, ...) client_fail((l)->base.client, (l)->base.id, code, __VA_ARGS__)

static int list_clear(void *target)
{
	struct list *l = target;
	account_vertices(l->base.client, -(int64_t)l->pending.vertices);
	draws_clear(&l->pending);
	list_reset_state(l);
	free(l->lut);
	l->lut = NULL;
	l->lut_count = 0;
	l->changed = true;
	return 0;
}

static int list_set_color(void *target, const struct proto_list_set_color_args *a)
{
	struct list *l = target;
	l->state.color[0] = (uint8_t)(a->rgba >> 24);
	l->state.color[1] = (uint8_t)(a->rgba >> 16);
	l->state.color[2] = (uint8_t)(a->rgba >> 8);
	l->state.color[3] = (uint8_t)a->rgba;
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
	memcpy(l->state.transform, a->matrix, sizeof(l->state.transform));
	return 0;
}

static int list_multiply_transform(void *target, const struct proto_list_multiply_transform_args *a)
{
	struct list *l = target;
	if (check_transform(&l->base, a->matrix) < 0)
		return -EPROTO;
	float m[16];
	mat4_mul(m, l->state.transform, a->matrix);
	for (int i = 0; i < 16; i++)
		if (!isfinite(m[i]) || fabsf(m[i]) > 1e6f)
			return list_fail(l, PROTO_ERR_VALUE, "multiply_transform: the product is out of range");
	memcpy(l->state.transform, m, sizeof(m));
	return 0;
}

static int list_push(void *target)
{
	struct list *l = target;
	if (l->depth == LIST_STACK_DEPTH)
		return list_fail(l, PROTO_ERR_VALUE, "push: more than %d states pushed", LIST_STACK_DEPTH);
	l->stack[l->depth++] = l->state;
	return 0;
}

static int list_pop(void *target)
{
	struct list *l = target;
	if (l->depth == 0)
		return list_fail(l, PROTO_ERR_VALUE, "pop: nothing pushed");
	l->state = l->stack[--l->depth];
	return 0;
}

static int list_set_point_size(void *target, const struct proto_list_set_point_size_args *a)
{
	struct list *l = target;
	if (a->size < 1 || a->size > 16)
		return list_fail(l, PROTO_ERR_VALUE, "point size %u is not 1 to 16", a->size);
	l->state.point_size = (uint8_t)a->size;
	return 0;
}

static int list_set_vertex_format(void *target, const struct proto_list_set_vertex_format_args *a)
{
	struct list *l = target;
	if (!draw_format_size(a->format))
		return list_fail(l, PROTO_ERR_VALUE, "vertex format %u unknown", a->format);
	l->state.format = (uint8_t)a->format;
	return 0;
}

/* Whether [offset, offset + (count - 1) * stride + size) lies in a buffer
 * of buffer_size bytes, overflow-safe (count < 2^32, stride <= 65536). */
static bool range_valid(uint64_t buffer_size, uint64_t offset, uint32_t count, uint32_t stride, uint32_t size)
{
	if (offset > buffer_size)
		return false;
	if (count == 0)
		return true;
	uint64_t last = (uint64_t)(count - 1) * stride; /* < 2^48 */
	return last <= buffer_size - offset && size <= buffer_size - offset - last;
}

/* The bytes of b from offset on (offset <= size, checked): an empty
 * buffer has no mapping, and NULL + 0 is undefined. */
static const uint8_t *buffer_at(const struct buffer *b, uint64_t offset)
{
	static const uint8_t none[4];
	return b->map ? b->map + offset : none;
}

const struct buffer *objects_buffer(struct client *c, uint32_t blame, uint32_t id, const char *what)
{
	struct buffer *b = idmap_get(&c->objects, id);
	if (!b || b->base.type != PROTO_IFACE_BUFFER) {
		client_fail(c, blame, PROTO_ERR_OBJECT, "%s: %u is not a buffer", what, id);
		return NULL;
	}
	return b;
}

static const struct buffer *draw_buffer(struct list *l, uint32_t id, const char *what)
{
	return objects_buffer(l->base.client, l->base.id, id, what);
}

/* Checks mode, vertex buffer, stride and the vertex range; fills the
 * vertex half of src. */
static int vertex_source(struct list *l, uint32_t mode, uint32_t buffer, uint64_t offset, uint32_t count,
			 uint32_t stride, struct draw_source *src)
{
	struct client *c = l->base.client;
	uint32_t last_mode = c->version >= 2 ? PROTO_LIST_MODE_LINE_STRIP : PROTO_LIST_MODE_TRIANGLES;
	if (mode > last_mode)
		return list_fail(l, PROTO_ERR_VALUE, "draw mode %u unknown at version %u", mode, c->version);
	const struct buffer *b = draw_buffer(l, buffer, "draw");
	if (!b)
		return -EPROTO;
	uint32_t size = draw_format_size(l->state.format);
	stride = stride ? stride : size;
	if (stride < size || stride > 65536)
		return list_fail(l, PROTO_ERR_VALUE, "draw: stride %u (vertices of %u bytes)", stride, size);
	if (!range_valid(b->size, offset, count, stride, size))
		return list_fail(l, PROTO_ERR_VALUE, "draw: vertices past the end of buffer %u", buffer);
	*src = (struct draw_source){
		.mode = (enum draw_mode)mode,
		.format = (enum draw_format)l->state.format,
		.base = buffer_at(b, offset),
		.stride = stride,
		.vertex_count = count,
	};
	return 0;
}

/* Builds the draw's data and appends it with the current state. */
static int list_append_draw(struct list *l, const struct draw_source *src)
{
	struct client *c = l->base.client;
	struct vdata *v;
	uint32_t bad = 0;
	uint64_t room = c->env->cfg->max_vertices - c->vertices, budget = budget_vertices(c);
	switch (draw_build(src, room < budget ? room : budget, &v, &bad)) {
	case DRAW_OK:
		break;
	case DRAW_BAD_COUNT:
		return list_fail(l, PROTO_ERR_VALUE, "draw: %u vertices do not make whole primitives",
				 src->index ? src->index_count : src->vertex_count);
	case DRAW_BAD_INDEX:
		return list_fail(l, PROTO_ERR_VALUE, "draw_indexed: index %u is not below vertex_count %u", bad,
				 src->vertex_count);
	case DRAW_TOO_MANY:
		if (budget < room) {
			c->env->totals->refused_memory++;
			return list_fail(l, PROTO_ERR_QUOTA,
					 "the daemon's memory budget is used up (room for %llu "
					 "vertices more)",
					 (unsigned long long)budget);
		}
		return list_fail(l, PROTO_ERR_QUOTA, "more than %llu vertices",
				 (unsigned long long)c->env->cfg->max_vertices);
	case DRAW_NO_MEMORY:
		return list_fail(l, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	return v ? objects_list_append(l, v) : 0;
}

int objects_list_append(struct list *l, struct vdata *v)
{
	struct client *c = l->base.client;
	uint64_t room = c->env->cfg->max_vertices - c->vertices, budget = budget_vertices(c);
	if (v->count > room || v->count > budget) {
		vdata_unref(v);
		if (budget < room) {
			c->env->totals->refused_memory++;
			return list_fail(l, PROTO_ERR_QUOTA, "the daemon's memory budget is used up");
		}
		return list_fail(l, PROTO_ERR_QUOTA, "more than %llu vertices",
				 (unsigned long long)c->env->cfg->max_vertices);
	}
	struct list_item d = { .data = v, .point_size = l->state.point_size };
	memcpy(d.transform, l->state.transform, sizeof(d.transform));
	memcpy(d.rgba, l->state.color, 4);
	if (draws_append(&l->pending, &d) < 0) {
		vdata_unref(v);
		return list_fail(l, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	account_vertices(c, v->count);
	l->changed = true;
	return 0;
}

static int list_draw(void *target, const struct proto_list_draw_args *a)
{
	struct list *l = target;
	struct draw_source src;
	if (vertex_source(l, a->mode, a->buffer, a->offset, a->count, a->stride, &src) < 0)
		return -EPROTO;
	return list_append_draw(l, &src);
}

static int list_draw_indexed(void *target, const struct proto_list_draw_indexed_args *a)
{
	struct list *l = target;
	struct draw_source src;
	if (vertex_source(l, a->mode, a->vertices, a->offset, a->vertex_count, a->stride, &src) < 0)
		return -EPROTO;
	if (a->index_type != PROTO_LIST_INDEX_TYPE_U16 && a->index_type != PROTO_LIST_INDEX_TYPE_U32)
		return list_fail(l, PROTO_ERR_VALUE, "index type %u unknown", a->index_type);
	const struct buffer *ib = draw_buffer(l, a->indices, "draw_indexed");
	if (!ib)
		return -EPROTO;
	if (a->index_offset % a->index_type)
		return list_fail(l, PROTO_ERR_VALUE, "draw_indexed: index offset %llu not a multiple of %u",
				 (unsigned long long)a->index_offset, a->index_type);
	if (!range_valid(ib->size, a->index_offset, a->index_count, a->index_type, a->index_type))
		return list_fail(l, PROTO_ERR_VALUE, "draw_indexed: indices past the end of buffer %u", a->indices);
	src.index = buffer_at(ib, a->index_offset);
	src.index_count = a->index_count;
	src.index_size = a->index_type;
	return list_append_draw(l, &src);
}

const struct proto_list_requests list_requests = {
	.destroy = objects_destroy_req,
	.clear = list_clear,
	.set_color = list_set_color,
	.set_transform = list_set_transform,
	.draw = list_draw,
	.draw_indexed = list_draw_indexed,
	.set_vertex_format = list_set_vertex_format,
	.set_point_size = list_set_point_size,
	.push = list_push,
	.pop = list_pop,
	.multiply_transform = list_multiply_transform,
	.draw_volume = volumes_list_draw,
	.set_volume_lut = volumes_list_set_lut,
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
	memcpy(y->committed.transform, identity, sizeof(identity));
	memcpy(y->committed.base, identity, sizeof(identity));
	y->committed.visible = true;
	y->committed.owner = c;
	int r = object_register(c, &y->base, id, PROTO_IFACE_LAYER);
	if (r < 0) {
		free(y);
		return r;
	}
	stage_add(c->env->stage, &y->committed);
	link_append(&c->layers, &y->link);
	return 0;
}

/* Off the stage already. */
static void layer_free(struct layer *y)
{
	list_unref(y->pending.list);
	list_unref(y->committed_list);
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

static int layer_set_priority(void *target, const struct proto_layer_set_priority_args *a)
{
	struct layer *y = target;
	if (a->priority < -1000 || a->priority > 1000)
		return client_fail(y->base.client, y->base.id, PROTO_ERR_VALUE, "priority %d is not -1000 to 1000",
				   a->priority);
	y->pending.priority = a->priority;
	y->changed = true;
	return 0;
}

static int layer_set_exclusive(void *target, const struct proto_layer_set_exclusive_args *a)
{
	struct layer *y = target;
	if (a->exclusive > 1)
		return client_fail(y->base.client, y->base.id, PROTO_ERR_VALUE, "exclusive must be 0 or 1");
	y->pending.exclusive = a->exclusive;
	y->changed = true;
	return 0;
}

const struct proto_layer_requests layer_requests = {
	.destroy = objects_destroy_req,
	.set_list = layer_set_list,
	.set_transform = layer_set_transform,
	.set_visible = layer_set_visible,
	.set_priority = layer_set_priority,
	.set_exclusive = layer_set_exclusive,
};

/* ---- commit and destruction ---- */

/* The layer's list, and whether it is visible and exclusive, after a commit now. */
static const struct list *layer_after_commit(const struct layer *y, bool *visible, bool *exclusive)
{
	*visible = y->changed ? y->pending.visible : y->committed.visible;
	*exclusive = y->changed ? y->pending.exclusive : y->committed.exclusive;
	return y->changed ? y->pending.list : y->committed_list;
}

static uint64_t list_prims_after_commit(const struct list *l)
{
	return l->changed ? l->pending.prims : l->committed.prims;
}

uint32_t objects_commit_check(struct client *c, uint32_t *object, char *text, size_t size)
{
	const struct config *cfg = c->env->cfg;
	uint64_t prims = 0;
	const struct layer *exclusive = NULL;
	struct layer *y;
	link_for_each(y, &c->layers, link) {
		bool visible, excl;
		const struct list *l = layer_after_commit(y, &visible, &excl);
		if (!visible)
			continue;
		if (l)
			prims += list_prims_after_commit(l);
		if (excl && !exclusive)
			exclusive = y;
	}
	*object = 1;
	if (prims > cfg->max_primitives) {
		snprintf(text, size, "the commit would show %llu primitives, over the quota of %llu",
			 (unsigned long long)prims, (unsigned long long)cfg->max_primitives);
		return PROTO_DISPLAY_REFUSAL_QUOTA;
	}
	if (!exclusive)
		return 0;
	*object = exclusive->base.id;
	if (!client_may_be_exclusive(c)) {
		snprintf(text, size, "exclusive layers are not granted to this client (policy: %s)",
			 config_policy_name(cfg->exclusive));
		return PROTO_DISPLAY_REFUSAL_DENIED;
	}
	const void *holder = stage_exclusive_owner(c->env->stage);
	if (holder && holder != c) {
		snprintf(text, size, "another client's exclusive layer is showing");
		return PROTO_DISPLAY_REFUSAL_BUSY;
	}
	return 0;
}

bool objects_leave_stage(struct client *c)
{
	bool changed = false;
	struct layer *y;
	link_for_each(y, &c->layers, link)
		changed |= stage_remove(&y->committed);
	return changed;
}

/* A departing client's watchers stop now: nothing more is sent to it, and
 * they no longer count against max-watchers (the objects are freed with the
 * client, at the reap). */
void objects_leave_watch(struct client *c)
{
	for (uint32_t i = 0; i < c->objects.cap; i++) {
		struct object *obj = c->objects.slots[i].value;
		if (c->objects.slots[i].id && obj->type == PROTO_IFACE_WATCHER)
			watch_remove(c->env->watch, &((struct watcher *)obj)->entry);
	}
}

/* The pending state becomes what the stage shows of y. */
static void layer_commit(struct layer *y)
{
	struct list *l = y->pending.list;
	if (l)
		l->refs++;
	list_unref(y->committed_list);
	y->committed_list = l;
	struct stage_layer *s = &y->committed;
	s->draws = l ? &l->committed : NULL;
	memcpy(s->transform, y->pending.transform, sizeof(s->transform));
	/* A turn of the base by whole images, or a move along the axis by
	 * whole rows, keeps the base: the cache can reuse the layer's render
	 * shifted (turn.h). */
	const struct geometry *g = y->base.client->env->geom;
	if (!turn_find_lift(s->base, s->transform, g->images_per_rev, 2.0 * g->half_height / g->height, &s->turn,
			    &s->lift)) {
		memcpy(s->base, s->transform, sizeof(s->base));
		s->turn = 0;
		s->lift = 0;
	}
	s->priority = y->pending.priority;
	s->visible = y->pending.visible;
	s->exclusive = y->pending.exclusive;
	y->changed = false;
}

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
		layer_commit(y);
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
		buffers_destroy((struct buffer *)obj);
		break;
	case PROTO_IFACE_LIST:
		list_unref((struct list *)obj);
		break;
	case PROTO_IFACE_LAYER: {
		struct layer *y = (struct layer *)obj;
		/* A departing client's layers are accounted for when it dies. */
		if (stage_remove(&y->committed) && !c->dead)
			stage_changed(c->env->stage);
		layer_free(y);
		break;
	}
	case PROTO_IFACE_CALLBACK:
	case PROTO_IFACE_CAPTURE: {
		struct callback *cb = (struct callback *)obj;
		frames_remove(&cb->wait);
		free(cb);
		break;
	}
	case PROTO_IFACE_WATCHER: {
		struct watcher *wa = (struct watcher *)obj;
		watch_remove(c->env->watch, &wa->entry);
		free(wa);
		break;
	}
	case PROTO_IFACE_VOLUME:
		volume_object_destroy((struct volume_obj *)obj);
		break;
	case PROTO_IFACE_DISPLAY:
		break;
	}
}
