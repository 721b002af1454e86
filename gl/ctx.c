#include "ctx.h"

#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "frame.h"
#include "list.h"
#include "mat.h"
#include "output.h"

static pthread_mutex_t registry = PTHREAD_MUTEX_INITIALIZER;
static struct sgl_ctx *contexts; /* every live context but the default */
static struct sgl_ctx *default_ctx;
static uint32_t next_id = 1;
static __thread struct sgl_ctx *current;

static struct sgl_ns *ns_create(void)
{
	struct sgl_ns *ns = calloc(1, sizeof(*ns));
	if (!ns)
		abort();
	pthread_mutex_init(&ns->lock, NULL);
	ns->refs = 1;
	return ns;
}

static void unref_list_value(void *v)
{
	sgl_list_unref(v);
}

static void free_buffer_value(void *v)
{
	struct sgl_buffer *b = v;
	free(b->data);
	free(b);
}

/* Under the registry lock for the count; frees outside any lock. */
static bool ns_unref_locked(struct sgl_ns *ns)
{
	return --ns->refs == 0;
}

static void ns_free(struct sgl_ns *ns)
{
	sgl_names_clear(&ns->lists, unref_list_value);
	sgl_names_clear(&ns->buffers, free_buffer_value);
	pthread_mutex_destroy(&ns->lock);
	free(ns);
}

/* Under the registry lock. */
static struct sgl_ctx *ctx_new(void *handle, struct sgl_ns *ns)
{
	struct sgl_ctx *c = calloc(1, sizeof(*c));
	if (!c)
		abort();
	c->id = next_id++;
	c->handle = handle;
	c->ns = ns ? ns : ns_create();
	if (ns)
		ns->refs++;
	c->matrix_mode = GL_MODELVIEW;
	sgl_mat_identity(c->mv[0]);
	sgl_mat_identity(c->proj[0]);
	sgl_colour_init(&c->cs);
	c->vertex.size = 4;
	c->vertex.type = GL_FLOAT;
	c->color.size = 4;
	c->color.type = GL_FLOAT;
	c->render_mode = GL_RENDER;
	sgl_geom_init(&c->frame.imm);
	c->out = sgl_out_create(c->id);
	return c;
}

/* Outside the registry lock: the context is unreachable. */
static void ctx_free(struct sgl_ctx *c, bool free_ns)
{
	sgl_rec_abandon(c);
	sgl_frame_clear(&c->frame);
	free(c->frame.calls);
	sgl_geom_free(&c->frame.imm);
	sgl_out_destroy(c->out);
	if (free_ns)
		ns_free(c->ns);
	free(c);
}

static struct sgl_ctx *find(void *handle)
{
	for (struct sgl_ctx *c = contexts; c; c = c->next)
		if (c->handle == handle)
			return c;
	return NULL;
}

static void unlink_ctx(struct sgl_ctx *c)
{
	for (struct sgl_ctx **p = &contexts; *p; p = &(*p)->next) {
		if (*p == c) {
			*p = c->next;
			return;
		}
	}
}

struct sgl_ctx *sgl_ctx_current(void)
{
	struct sgl_ctx *c = current;
	if (c)
		return c;
	sgl_config();
	pthread_mutex_lock(&registry);
	if (!default_ctx)
		default_ctx = ctx_new(NULL, NULL);
	c = default_ctx;
	pthread_mutex_unlock(&registry);
	return c;
}

void sgl_ctx_created(void *handle, void *share)
{
	if (!handle)
		return;
	sgl_config();
	pthread_mutex_lock(&registry);
	struct sgl_ctx *old = find(handle), *with = share ? find(share) : NULL;
	if (old) /* a handle reused after a destroy the layer missed */
		old->handle = NULL;
	struct sgl_ctx *c = ctx_new(handle, with ? with->ns : NULL);
	c->next = contexts;
	contexts = c;
	pthread_mutex_unlock(&registry);
}

/* Under the registry lock: whether c is now to be freed, and its share
 * group with it. */
static bool release_locked(struct sgl_ctx *c, bool *free_ns)
{
	if (!c || !c->destroyed || c->current > 0)
		return false;
	*free_ns = ns_unref_locked(c->ns);
	return true;
}

void sgl_ctx_destroyed(void *handle)
{
	bool free_ns = false, go = false;
	pthread_mutex_lock(&registry);
	struct sgl_ctx *c = handle ? find(handle) : NULL;
	if (c) {
		unlink_ctx(c);
		c->destroyed = true;
		go = release_locked(c, &free_ns);
	}
	pthread_mutex_unlock(&registry);
	if (go)
		ctx_free(c, free_ns);
}

void sgl_ctx_make_current(void *handle)
{
	bool free_ns = false, go = false;
	sgl_config();
	pthread_mutex_lock(&registry);
	struct sgl_ctx *old = current, *c = handle ? find(handle) : NULL;
	if (handle && !c) { /* created in a way the layer did not see */
		c = ctx_new(handle, NULL);
		c->next = contexts;
		contexts = c;
	}
	if (old != c) {
		if (old)
			old->current--;
		if (c)
			c->current++;
		go = release_locked(old, &free_ns);
	}
	current = c;
	pthread_mutex_unlock(&registry);
	if (go)
		ctx_free(old, free_ns);
}

/* ---- matrices ---- */

float *sgl_ctx_matrix(struct sgl_ctx *c)
{
	if (c->matrix_mode == GL_MODELVIEW)
		return c->mv[c->mv_top];
	if (c->matrix_mode == GL_PROJECTION)
		return c->proj[c->proj_top];
	return NULL;
}

void sgl_ctx_stage_matrix(struct sgl_ctx *c, float out[16])
{
	if (sgl_config()->map == SGL_MAP_FRUSTUM)
		sgl_mat_mul(out, c->proj[c->proj_top], c->mv[c->mv_top]);
	else
		memcpy(out, c->mv[c->mv_top], 16 * sizeof(float));
}

void sgl_ctx_mult(struct sgl_ctx *c, const float m[16])
{
	float *t = sgl_ctx_matrix(c);
	if (t)
		sgl_mat_mul(t, t, m);
}

void sgl_ctx_load(struct sgl_ctx *c, const float m[16])
{
	float *t = sgl_ctx_matrix(c);
	if (t)
		memcpy(t, m, 16 * sizeof(float));
}

static void stack_op(float (*stack)[16], int *top, bool push)
{
	if (push && *top + 1 < SGL_STACK_DEPTH) {
		memcpy(stack[*top + 1], stack[*top], 16 * sizeof(float));
		++*top;
	} else if (!push && *top > 0) {
		--*top;
	}
}

void sgl_ctx_push(struct sgl_ctx *c)
{
	if (c->matrix_mode == GL_MODELVIEW)
		stack_op(c->mv, &c->mv_top, true);
	else if (c->matrix_mode == GL_PROJECTION)
		stack_op(c->proj, &c->proj_top, true);
}

void sgl_ctx_pop(struct sgl_ctx *c)
{
	if (c->matrix_mode == GL_MODELVIEW)
		stack_op(c->mv, &c->mv_top, false);
	else if (c->matrix_mode == GL_PROJECTION)
		stack_op(c->proj, &c->proj_top, false);
}

bool sgl_ctx_matrix_op(struct sgl_ctx *c, enum sgl_op_kind kind, const float *m, unsigned mode)
{
	switch (kind) {
	case SGL_OP_MULT:
		sgl_ctx_mult(c, m);
		return true;
	case SGL_OP_LOAD:
		sgl_ctx_load(c, m);
		return true;
	case SGL_OP_PUSH:
		sgl_ctx_push(c);
		return true;
	case SGL_OP_POP:
		sgl_ctx_pop(c);
		return true;
	case SGL_OP_MODE:
		c->matrix_mode = mode;
		return true;
	default:
		return false;
	}
}

bool sgl_ctx_drawing(struct sgl_ctx *c)
{
	return c->render_mode == GL_RENDER && c->program == 0;
}

/* ---- colour ---- */

void sgl_colour_init(struct sgl_colour *cs)
{
	*cs = (struct sgl_colour){
		.colour = { 1, 1, 1, 1 },
		.diffuse = { 0.8f, 0.8f, 0.8f, 1 },
		.cm_mode = GL_AMBIENT_AND_DIFFUSE,
	};
}

static uint8_t to_byte(float v)
{
	if (!(v > 0))
		return 0;
	return v >= 1 ? 255 : (uint8_t)(v * 255 + 0.5f);
}

void sgl_colour_rgba(const struct sgl_colour *cs, uint8_t out[4])
{
	const float *src = cs->lighting ? cs->diffuse : cs->colour;
	for (int i = 0; i < 4; i++)
		out[i] = to_byte(src[i]);
}

static bool follows_colour(const struct sgl_colour *cs)
{
	return cs->color_material && (cs->cm_mode == GL_DIFFUSE || cs->cm_mode == GL_AMBIENT_AND_DIFFUSE);
}

void sgl_colour_set(struct sgl_colour *cs, const float rgba[4])
{
	memcpy(cs->colour, rgba, sizeof(cs->colour));
	if (follows_colour(cs))
		memcpy(cs->diffuse, rgba, sizeof(cs->diffuse));
}

void sgl_colour_enable(struct sgl_colour *cs, GLenum cap, bool on)
{
	if (cap == GL_LIGHTING) {
		cs->lighting = on;
	} else if (cap == GL_COLOR_MATERIAL) {
		cs->color_material = on;
		if (follows_colour(cs))
			memcpy(cs->diffuse, cs->colour, sizeof(cs->diffuse));
	}
}
