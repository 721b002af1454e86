#include "list.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "ctx.h"
#include "frame.h"
#include "mat.h"
#include "output.h"

static void *grow(void *p, uint32_t *cap, uint32_t need, size_t size)
{
	if (need <= *cap)
		return p;
	uint32_t c = *cap ? *cap * 2 : 16;
	while (c < need)
		c *= 2;
	p = realloc(p, (size_t)c * size);
	if (!p)
		abort();
	*cap = c;
	return p;
}

static void add_op(struct sgl_list *l, const struct sgl_op *op)
{
	l->ops = grow(l->ops, &l->cap_ops, l->n_ops + 1, sizeof(*op));
	l->ops[l->n_ops++] = *op;
}

void sgl_rec_begin(struct sgl_ctx *c, GLuint name, GLenum mode)
{
	if (c->rec || name == 0 || (mode != GL_COMPILE && mode != GL_COMPILE_AND_EXECUTE))
		return; /* GL's errors: nothing is compiled */
	struct sgl_rec *r = calloc(1, sizeof(*r));
	struct sgl_list *l = calloc(1, sizeof(*l));
	if (!r || !l)
		abort();
	l->refs = 1;
	l->name = name;
	r->list = l;
	sgl_mat_identity(r->l[0]);
	r->mode = mode;
	r->matrix_mode = c->matrix_mode;
	r->cs = c->cs;
	c->rec = r;
}

static uint32_t seg_vertices(const struct sgl_seg *s)
{
	return sgl_geom_count(&s->own) + sgl_geom_count(&s->inherit);
}

/* The sphere around a segment (its box's centre): its bounds wherever a
 * rotation turns it, which keeps the fit steady. */
static void seg_sphere(struct sgl_seg *s)
{
	const struct sgl_geom *g[2] = { &s->own, &s->inherit };
	float lo[3], hi[3], r2 = 0;
	for (int i = 0; i < 3; i++) {
		lo[i] = fminf(g[0]->lo[i], g[1]->lo[i]);
		hi[i] = fmaxf(g[0]->hi[i], g[1]->hi[i]);
		s->centre[i] = lo[i] <= hi[i] ? (lo[i] + hi[i]) / 2 : 0;
	}
	for (int k = 0; k < 2; k++) {
		for (int kind = 0; kind < SGL_KINDS; kind++) {
			for (uint32_t i = 0; i < g[k]->n[kind]; i++) {
				const float *p = g[k]->v[kind][i].xyz;
				float dx = p[0] - s->centre[0], dy = p[1] - s->centre[1], dz = p[2] - s->centre[2];
				r2 = fmaxf(r2, dx * dx + dy * dy + dz * dz);
			}
		}
	}
	s->radius = sqrtf(r2);
}

void sgl_rec_end(struct sgl_ctx *c)
{
	struct sgl_rec *r = c->rec;
	if (!r)
		return;
	c->rec = NULL;
	struct sgl_list *l = r->list;
	GLenum mode = r->mode;
	free(r);
	uint32_t verts = 0;
	for (uint32_t i = 0; i < l->n_segs; i++) {
		verts += seg_vertices(l->segs[i]);
		seg_sphere(l->segs[i]);
	}
	sgl_trace("list %u ops %u segments %u vertices %u", l->name, l->n_ops, l->n_segs, verts);
	bool ok;
	pthread_mutex_lock(&c->ns->lock);
	struct sgl_list *old = sgl_names_put(&c->ns->lists, l->name, l, &ok);
	pthread_mutex_unlock(&c->ns->lock);
	if (old)
		sgl_list_unref(old);
	if (ok && mode == GL_COMPILE_AND_EXECUTE)
		sgl_list_call(c, l->name, 0);
	if (!ok)
		sgl_list_unref(l);
}

void sgl_rec_abandon(struct sgl_ctx *c)
{
	if (!c->rec)
		return;
	sgl_list_unref(c->rec->list);
	free(c->rec);
	c->rec = NULL;
}

/* The geometry after this point is drawn under a matrix known only when
 * the list runs: the next segment starts here, relative to the modelview
 * of this point. */
static void end_segment(struct sgl_rec *r)
{
	r->seg = NULL;
	r->anchor = r->list->n_ops;
	sgl_mat_identity(r->l[0]);
	r->top = 0;
}

struct sgl_seg *sgl_rec_segment(struct sgl_rec *r)
{
	if (r->seg)
		return r->seg;
	struct sgl_list *l = r->list;
	struct sgl_seg *s = calloc(1, sizeof(*s));
	if (!s)
		abort();
	sgl_geom_init(&s->own);
	sgl_geom_init(&s->inherit);
	s->index = l->n_segs;
	l->segs = grow(l->segs, &l->cap_segs, l->n_segs + 1, sizeof(*l->segs));
	l->segs[l->n_segs++] = s;
	/* Its op goes back to the anchor: the matrix calls since are in
	 * r->l, baked into its vertices, and still replayed after it. */
	add_op(l, &(struct sgl_op){ .kind = SGL_OP_SEG });
	memmove(l->ops + r->anchor + 1, l->ops + r->anchor, (l->n_ops - 1 - r->anchor) * sizeof(*l->ops));
	l->ops[r->anchor] = (struct sgl_op){ .kind = SGL_OP_SEG, .a = s->index };
	r->seg = s;
	return s;
}

bool sgl_rec_colour_known(const struct sgl_rec *r)
{
	if (!r->cs.lighting)
		return r->color_set;
	return r->material_set || (r->cs.color_material && r->color_set);
}

void sgl_rec_matrix(struct sgl_rec *r, enum sgl_op_kind kind, const float *m, GLenum mode)
{
	struct sgl_op op = { .kind = kind, .a = mode };
	if (m)
		memcpy(op.m, m, sizeof(op.m));
	add_op(r->list, &op);
	if (kind == SGL_OP_MODE) {
		r->matrix_mode = mode;
		return;
	}
	if (r->matrix_mode == GL_PROJECTION)
		end_segment(r); /* the stage matrix changes in frustum mode */
	if (r->matrix_mode != GL_MODELVIEW)
		return;
	if (kind == SGL_OP_MULT) {
		sgl_mat_mul(r->l[r->top], r->l[r->top], m);
	} else if (kind == SGL_OP_PUSH && r->top + 1 < SGL_STACK_DEPTH) {
		memcpy(r->l[r->top + 1], r->l[r->top], sizeof(r->l[0]));
		r->top++;
	} else if (kind == SGL_OP_POP && r->top > 0) {
		r->top--;
	} else {
		end_segment(r); /* a load, or a pop past the anchor */
	}
}

void sgl_rec_state(struct sgl_rec *r, enum sgl_op_kind kind, uint32_t a, uint32_t b, const float *v)
{
	struct sgl_op op = { .kind = kind, .a = a, .b = b };
	if (v)
		memcpy(op.m, v, 4 * sizeof(float));
	add_op(r->list, &op);
	switch (kind) {
	case SGL_OP_COLOR:
		sgl_colour_set(&r->cs, v);
		r->color_set = true;
		break;
	case SGL_OP_MATERIAL:
		memcpy(r->cs.diffuse, v, sizeof(r->cs.diffuse));
		r->material_set = true;
		break;
	case SGL_OP_ENABLE:
		sgl_colour_enable(&r->cs, a, b);
		end_segment(r); /* inherited colours are taken at a segment's start */
		break;
	case SGL_OP_SHADE:
		r->cs.flat = a;
		break;
	case SGL_OP_COLOR_MATERIAL:
		r->cs.cm_mode = a;
		break;
	default:
		break;
	}
}

void sgl_rec_call(struct sgl_rec *r, GLuint name, bool add_base)
{
	add_op(r->list, &(struct sgl_op){ .kind = SGL_OP_CALL, .a = name, .b = add_base });
	/* The called list may change the matrix and the colour. */
	end_segment(r);
	r->color_set = r->material_set = false;
}

void sgl_rec_base(struct sgl_rec *r, GLuint base)
{
	add_op(r->list, &(struct sgl_op){ .kind = SGL_OP_BASE, .a = base });
}

/* ---- replay ---- */

static void exec_op(struct sgl_ctx *c, struct sgl_list *l, const struct sgl_op *op, int depth)
{
	switch (op->kind) {
	case SGL_OP_SEG:
		sgl_frame_add_call(c, l, l->segs[op->a]);
		break;
	case SGL_OP_MULT:
	case SGL_OP_LOAD:
	case SGL_OP_PUSH:
	case SGL_OP_POP:
	case SGL_OP_MODE:
		sgl_ctx_matrix_op(c, op->kind, op->m, op->a);
		break;
	case SGL_OP_CALL:
		sgl_list_call(c, op->a + (op->b ? c->list_base : 0), depth + 1);
		break;
	case SGL_OP_BASE:
		c->list_base = op->a;
		break;
	case SGL_OP_COLOR:
		sgl_colour_set(&c->cs, op->m);
		break;
	case SGL_OP_MATERIAL:
		memcpy(c->cs.diffuse, op->m, sizeof(c->cs.diffuse));
		break;
	case SGL_OP_ENABLE:
		sgl_colour_enable(&c->cs, op->a, op->b);
		break;
	case SGL_OP_SHADE:
		c->cs.flat = op->a;
		break;
	case SGL_OP_COLOR_MATERIAL:
		c->cs.cm_mode = op->a;
		break;
	}
}

void sgl_list_call(struct sgl_ctx *c, GLuint name, int depth)
{
	if (depth >= SGL_CALL_DEPTH)
		return;
	struct sgl_list *l = sgl_ns_list(c->ns, name);
	if (!l)
		return;
	for (uint32_t i = 0; i < l->n_ops; i++)
		exec_op(c, l, &l->ops[i], depth);
	sgl_list_unref(l);
}

struct sgl_list *sgl_ns_list(struct sgl_ns *ns, GLuint name)
{
	pthread_mutex_lock(&ns->lock);
	struct sgl_list *l = sgl_names_get(&ns->lists, name);
	if (l)
		__atomic_add_fetch(&l->refs, 1, __ATOMIC_RELAXED);
	pthread_mutex_unlock(&ns->lock);
	return l;
}

void sgl_list_unref(struct sgl_list *l)
{
	if (!l || __atomic_sub_fetch(&l->refs, 1, __ATOMIC_ACQ_REL) > 0)
		return;
	for (uint32_t i = 0; i < l->n_segs; i++) {
		struct sgl_seg *s = l->segs[i];
		sgl_out_seg_release(s);
		sgl_geom_free(&s->own);
		sgl_geom_free(&s->inherit);
		free(s);
	}
	free(l->segs);
	free(l->ops);
	free(l);
}

/* The names of [first, first + range) that are lists: by name for a small
 * range, else by a look at every list (glDeleteLists(1, 1 << 30) exists). */
static uint32_t *names_in_range(struct sgl_names *m, GLuint first, GLsizei range, uint32_t *n)
{
	uint64_t end = (uint64_t)first + (uint64_t)range;
	uint32_t cap = 0, *keys = NULL;
	*n = 0;
	if ((uint64_t)range <= m->count * 4 + 64) {
		for (uint64_t k = first; k < end; k++) {
			if (!sgl_names_get(m, (uint32_t)k))
				continue;
			keys = grow(keys, &cap, *n + 1, sizeof(*keys));
			keys[(*n)++] = (uint32_t)k;
		}
		return keys;
	}
	for (size_t i = 0; i < m->cap; i++) {
		uint32_t k = m->slots[i].key;
		if (k && k >= first && k < end) {
			keys = grow(keys, &cap, *n + 1, sizeof(*keys));
			keys[(*n)++] = k;
		}
	}
	return keys;
}

void sgl_lists_delete(struct sgl_ctx *c, GLuint first, GLsizei range)
{
	if (range <= 0)
		return;
	uint32_t n;
	pthread_mutex_lock(&c->ns->lock);
	uint32_t *keys = names_in_range(&c->ns->lists, first, range, &n);
	struct sgl_list **gone = n ? calloc(n, sizeof(*gone)) : NULL;
	if (n && !gone)
		abort();
	for (uint32_t i = 0; i < n; i++)
		gone[i] = sgl_names_remove(&c->ns->lists, keys[i]);
	pthread_mutex_unlock(&c->ns->lock);
	for (uint32_t i = 0; i < n; i++)
		sgl_list_unref(gone[i]);
	free(gone);
	free(keys);
}
