#include "geom.h"

#include <GL/gl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mat.h"

void sgl_geom_init(struct sgl_geom *g)
{
	memset(g, 0, sizeof(*g));
	sgl_geom_reset(g);
}

void sgl_geom_reset(struct sgl_geom *g)
{
	for (int k = 0; k < SGL_KINDS; k++)
		g->n[k] = 0;
	for (int i = 0; i < 3; i++) {
		g->lo[i] = INFINITY;
		g->hi[i] = -INFINITY;
	}
	g->overflow = false;
}

void sgl_geom_free(struct sgl_geom *g)
{
	for (int k = 0; k < SGL_KINDS; k++)
		free(g->v[k]);
	sgl_geom_init(g);
}

uint32_t sgl_geom_count(const struct sgl_geom *g)
{
	return g->n[SGL_POINTS] + g->n[SGL_LINES] + g->n[SGL_TRIS];
}

bool sgl_geom_empty(const struct sgl_geom *g)
{
	return sgl_geom_count(g) == 0;
}

static bool reserve(struct sgl_geom *g, enum sgl_kind k, uint32_t more)
{
	if (sgl_geom_count(g) + more > SGL_GEOM_MAX) {
		g->overflow = true;
		return false;
	}
	if (g->n[k] + more <= g->cap[k])
		return true;
	uint32_t cap = g->cap[k] ? g->cap[k] : 64;
	while (cap < g->n[k] + more)
		cap *= 2;
	struct sgl_vertex *v = realloc(g->v[k], (size_t)cap * sizeof(*v));
	if (!v) {
		g->overflow = true;
		return false;
	}
	g->v[k] = v;
	g->cap[k] = cap;
	return true;
}

void sgl_geom_add(struct sgl_geom *g, enum sgl_kind k, const struct sgl_vertex *v)
{
	uint32_t n = (uint32_t)k + 1;
	for (uint32_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++)
			if (!isfinite(v[i].xyz[c]))
				return;
	if (!reserve(g, k, n))
		return;
	memcpy(g->v[k] + g->n[k], v, n * sizeof(*v));
	g->n[k] += n;
	for (uint32_t i = 0; i < n; i++) {
		for (int c = 0; c < 3; c++) {
			g->lo[c] = fminf(g->lo[c], v[i].xyz[c]);
			g->hi[c] = fmaxf(g->hi[c], v[i].xyz[c]);
		}
	}
}

/* One vertex through m; false when it lies behind the eye (w <= 0). */
static bool transform(const float m[16], const struct sgl_vertex *in, struct sgl_vertex *out, const uint8_t *rgba)
{
	float p[4] = { in->xyz[0], in->xyz[1], in->xyz[2], 1 };
	sgl_mat_apply(m, p, p);
	if (!(p[3] > 1e-6f))
		return false;
	for (int c = 0; c < 3; c++)
		out->xyz[c] = p[c] / p[3];
	memcpy(out->rgba, rgba ? rgba : in->rgba, 4);
	return true;
}

void sgl_geom_append(struct sgl_geom *dst, const struct sgl_geom *src, const float m[16], const uint8_t *rgba)
{
	for (int k = 0; k < SGL_KINDS; k++) {
		uint32_t per = (uint32_t)k + 1;
		for (uint32_t i = 0; i + per <= src->n[k]; i += per) {
			struct sgl_vertex v[3];
			bool ok = true;
			for (uint32_t j = 0; j < per && ok; j++)
				ok = transform(m, &src->v[k][i + j], &v[j], rgba);
			if (ok)
				sgl_geom_add(dst, (enum sgl_kind)k, v);
		}
	}
}

bool sgl_geom_equal(const struct sgl_geom *a, const struct sgl_geom *b)
{
	for (int k = 0; k < SGL_KINDS; k++) {
		if (a->n[k] != b->n[k])
			return false;
		if (a->n[k] && memcmp(a->v[k], b->v[k], a->n[k] * sizeof(struct sgl_vertex)) != 0)
			return false;
	}
	return true;
}

void sgl_geom_copy(struct sgl_geom *dst, const struct sgl_geom *src)
{
	sgl_geom_reset(dst);
	for (int k = 0; k < SGL_KINDS; k++) {
		if (!src->n[k] || !reserve(dst, (enum sgl_kind)k, src->n[k]))
			continue;
		memcpy(dst->v[k], src->v[k], src->n[k] * sizeof(struct sgl_vertex));
		dst->n[k] = src->n[k];
	}
	memcpy(dst->lo, src->lo, sizeof(dst->lo));
	memcpy(dst->hi, src->hi, sizeof(dst->hi));
	dst->overflow = src->overflow;
}

/* ---- the primitive assembler ---- */

bool sgl_asm_begin(struct sgl_asm *a, unsigned mode, bool flat, struct sgl_geom *own, struct sgl_geom *inherit)
{
	if (mode > GL_POLYGON)
		return false;
	a->mode = mode;
	a->count = 0;
	a->flat = flat;
	a->own = own;
	a->inherit = inherit;
	return true;
}

/* Emits one primitive: the divide by w, flat shading (the colour of pv,
 * GL's provoking vertex), and the choice between own and inherited colour
 * (by the last vertex: a list that sets a colour mid-primitive owns it). */
static void emit(struct sgl_asm *a, enum sgl_kind k, const struct sgl_avertex *const *in, const struct sgl_avertex *pv)
{
	int n = (int)k + 1;
	struct sgl_vertex v[3];
	const struct sgl_avertex *last = in[n - 1];
	for (int i = 0; i < n; i++) {
		float w = in[i]->pos[3];
		if (!(w > 1e-6f) || !isfinite(w))
			return;
		for (int c = 0; c < 3; c++)
			v[i].xyz[c] = in[i]->pos[c] / w;
		const struct sgl_avertex *col = a->flat ? pv : in[i];
		if (col->inherit && !last->inherit)
			col = last;
		memcpy(v[i].rgba, col->rgba, 4);
	}
	struct sgl_geom *g = last->inherit && a->inherit ? a->inherit : a->own;
	if (g)
		sgl_geom_add(g, k, v);
}

static void emit2(struct sgl_asm *a, const struct sgl_avertex *p, const struct sgl_avertex *q)
{
	const struct sgl_avertex *v[2] = { p, q };
	emit(a, SGL_LINES, v, q);
}

static void emit3(struct sgl_asm *a, const struct sgl_avertex *p, const struct sgl_avertex *q,
		  const struct sgl_avertex *r, const struct sgl_avertex *pv)
{
	const struct sgl_avertex *v[3] = { p, q, r };
	emit(a, SGL_TRIS, v, pv);
}

/* The modes whose primitives share vertices: prev[0..2] are the three
 * vertices before v (the oldest first), first the sequence's first. */
static void assemble_shared(struct sgl_asm *a, const struct sgl_avertex *v, uint32_t i)
{
	const struct sgl_avertex *p0 = &a->prev[0], *p1 = &a->prev[1], *p2 = &a->prev[2];
	switch (a->mode) {
	case GL_LINE_STRIP:
	case GL_LINE_LOOP:
		if (i >= 1)
			emit2(a, p2, v);
		break;
	case GL_TRIANGLE_STRIP:
		if (i >= 2)
			emit3(a, p1, p2, v, v);
		break;
	case GL_TRIANGLE_FAN:
		if (i >= 2)
			emit3(a, &a->first, p2, v, v);
		break;
	case GL_POLYGON:
		if (i >= 2)
			emit3(a, &a->first, p2, v, &a->first);
		break;
	case GL_QUAD_STRIP:
		if (i >= 3 && i % 2 == 1) {
			emit3(a, p0, p1, v, v);
			emit3(a, p0, v, p2, v);
		}
		break;
	default:
		break;
	}
}

void sgl_asm_vertex(struct sgl_asm *a, const struct sgl_avertex *v)
{
	uint32_t i = a->count++;
	const struct sgl_avertex *p0 = &a->prev[0], *p1 = &a->prev[1], *p2 = &a->prev[2];
	switch (a->mode) {
	case GL_POINTS:
		emit(a, SGL_POINTS, &v, v);
		break;
	case GL_LINES:
		if (i % 2 == 1)
			emit2(a, p2, v);
		break;
	case GL_TRIANGLES:
		if (i % 3 == 2)
			emit3(a, p1, p2, v, v);
		break;
	case GL_QUADS:
		if (i % 4 == 3) {
			emit3(a, p0, p1, p2, v);
			emit3(a, p0, p2, v, v);
		}
		break;
	default:
		assemble_shared(a, v, i);
		break;
	}
	if (i == 0)
		a->first = *v;
	a->prev[0] = a->prev[1];
	a->prev[1] = a->prev[2];
	a->prev[2] = *v;
}

void sgl_asm_end(struct sgl_asm *a)
{
	if (a->mode == GL_LINE_LOOP && a->count >= 2)
		emit2(a, &a->prev[2], &a->first);
	a->count = 0;
}
