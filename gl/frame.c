#include "frame.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "ctx.h"
#include "mat.h"
#include "output.h"

/* Calls one frame holds by reference at most; more are copied into the
 * immediate geometry (a program that never ends a frame stays bounded). */
#define MAX_CALLS 65536
/* Fit mode: the box fitted is the bounds grown by this much, and a frame
 * whose bounds' largest half extent falls under SHRINK of the box's is
 * fitted anew. */
#define FIT_SLACK 1.15f
#define FIT_SHRINK 0.4f

static void expand(struct sgl_frame *f, const struct sgl_seg *seg, const float s[16], const uint8_t rgba[4])
{
	sgl_geom_append(&f->imm, &seg->own, s, NULL);
	sgl_geom_append(&f->imm, &seg->inherit, s, rgba);
}

void sgl_frame_add_call(struct sgl_ctx *c, struct sgl_list *l, struct sgl_seg *seg)
{
	if (!sgl_ctx_drawing(c) || (sgl_geom_empty(&seg->own) && sgl_geom_empty(&seg->inherit)))
		return;
	struct sgl_frame *f = &c->frame;
	struct sgl_call call = { .list = l, .seg = seg };
	sgl_ctx_stage_matrix(c, call.s);
	sgl_colour_rgba(&c->cs, call.rgba);
	if (f->n_calls >= MAX_CALLS) {
		expand(f, seg, call.s, call.rgba);
		return;
	}
	if (f->n_calls == f->cap_calls) {
		uint32_t cap = f->cap_calls ? f->cap_calls * 2 : 16;
		struct sgl_call *calls = realloc(f->calls, cap * sizeof(*calls));
		if (!calls)
			abort();
		f->calls = calls;
		f->cap_calls = cap;
	}
	__atomic_add_fetch(&l->refs, 1, __ATOMIC_RELAXED);
	f->calls[f->n_calls++] = call;
}

void sgl_frame_clear(struct sgl_frame *f)
{
	for (uint32_t i = 0; i < f->n_calls; i++)
		sgl_list_unref(f->calls[i].list);
	f->n_calls = 0;
	sgl_geom_reset(&f->imm);
}

static void grow_bounds(float lo[3], float hi[3], const float p[3])
{
	for (int i = 0; i < 3; i++) {
		lo[i] = fminf(lo[i], p[i]);
		hi[i] = fmaxf(hi[i], p[i]);
	}
}

/* The stage bounds of a call: its segment's sphere through s (the box
 * corners where s is projective). */
static void call_bounds(const struct sgl_call *call, float lo[3], float hi[3])
{
	const struct sgl_seg *seg = call->seg;
	const float *s = call->s;
	if (sgl_mat_is_affine(s)) {
		float c[4] = { seg->centre[0], seg->centre[1], seg->centre[2], 1 }, k = 0;
		sgl_mat_apply(s, c, c);
		for (int col = 0; col < 3; col++)
			k = fmaxf(k, sqrtf(s[col * 4] * s[col * 4] + s[col * 4 + 1] * s[col * 4 + 1] +
					   s[col * 4 + 2] * s[col * 4 + 2]));
		float r = seg->radius * k;
		float a[3] = { c[0] - r, c[1] - r, c[2] - r }, b[3] = { c[0] + r, c[1] + r, c[2] + r };
		grow_bounds(lo, hi, a);
		grow_bounds(lo, hi, b);
		return;
	}
	const struct sgl_geom *g[2] = { &seg->own, &seg->inherit };
	for (int i = 0; i < 2; i++) {
		if (sgl_geom_empty(g[i]))
			continue;
		for (int corner = 0; corner < 8; corner++) {
			float p[4] = { corner & 1 ? g[i]->hi[0] : g[i]->lo[0], corner & 2 ? g[i]->hi[1] : g[i]->lo[1],
				       corner & 4 ? g[i]->hi[2] : g[i]->lo[2], 1 };
			sgl_mat_apply(s, p, p);
			if (p[3] > 1e-6f) {
				float q[3] = { p[0] / p[3], p[1] / p[3], p[2] / p[3] };
				grow_bounds(lo, hi, q);
			}
		}
	}
}

static void frame_bounds(const struct sgl_frame *f, float lo[3], float hi[3])
{
	memcpy(lo, f->imm.lo, 3 * sizeof(float));
	memcpy(hi, f->imm.hi, 3 * sizeof(float));
	for (uint32_t i = 0; i < f->n_calls; i++)
		call_bounds(&f->calls[i], lo, hi);
}

static bool inside(const struct sgl_fit *fit, const float lo[3], const float hi[3])
{
	for (int i = 0; i < 3; i++)
		if (lo[i] < fit->c[i] - fit->e[i] || hi[i] > fit->c[i] + fit->e[i])
			return false;
	return true;
}

static float max3(const float v[3])
{
	return fmaxf(v[0], fmaxf(v[1], v[2]));
}

static void refit(struct sgl_fit *fit, const float lo[3], const float hi[3], float h)
{
	float e[3];
	for (int i = 0; i < 3; i++) {
		fit->c[i] = (lo[i] + hi[i]) / 2;
		e[i] = (hi[i] - lo[i]) / 2;
	}
	/* Flat or point-like geometry still gets a finite scale. */
	float floor = fmaxf(max3(e) * 0.05f, 1e-6f);
	for (int i = 0; i < 3; i++)
		fit->e[i] = fmaxf(e[i], floor) * FIT_SLACK;
	float r = sqrtf(fit->e[0] * fit->e[0] + fit->e[2] * fit->e[2]);
	fit->s = fminf(1 / r, h / fit->e[1]);
	fit->valid = true;
	fit->refits++;
	sgl_trace("fit centre %g %g %g half %g %g %g scale %g", fit->c[0], fit->c[1], fit->c[2], fit->e[0], fit->e[1],
		  fit->e[2], fit->s);
}

static void update_fit(struct sgl_fit *fit, const float lo[3], const float hi[3], float h)
{
	if (!(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]))
		return; /* nothing drawn: the fit stays */
	float e[3] = { (hi[0] - lo[0]) / 2, (hi[1] - lo[1]) / 2, (hi[2] - lo[2]) / 2 };
	if (!fit->valid || !inside(fit, lo, hi) || max3(e) * FIT_SLACK < FIT_SHRINK * max3(fit->e))
		refit(fit, lo, hi, h);
}

void sgl_frame_mapping(struct sgl_fit *fit, const float lo[3], const float hi[3], float h, float map[16])
{
	const struct sgl_config *cfg = sgl_config();
	sgl_mat_identity(map);
	if (cfg->map == SGL_MAP_FRUSTUM) {
		/* NDC x and depth fill the square inscribed in the unit
		 * circle, the near plane towards +z (the viewer's side). */
		float k = (float)M_SQRT1_2;
		map[0] = k;
		map[5] = h;
		map[10] = -k;
	} else if (cfg->map == SGL_MAP_FIXED) {
		map[0] = map[5] = map[10] = cfg->scale;
		memcpy(map + 12, cfg->offset, 3 * sizeof(float));
	} else {
		update_fit(fit, lo, hi, h);
		if (!fit->valid)
			return;
		map[0] = map[5] = map[10] = fit->s;
		for (int i = 0; i < 3; i++)
			map[12 + i] = -fit->s * fit->c[i];
	}
}

static const char *const status_names[] = { "sent", "dropped", "offline" };

/* The trace of a frame: its calls and immediate vertices when few. */
static void trace_frame(struct sgl_ctx *c, const char *why, const float map[16], enum sgl_send st)
{
	const struct sgl_frame *f = &c->frame;
	const struct sgl_geom *g = &f->imm;
	for (uint32_t i = 0; i < f->n_calls && f->n_calls <= 64; i++) {
		const struct sgl_call *k = &f->calls[i];
		const float *m = k->s;
		sgl_trace("call list %u segment %u colour %02x%02x%02x%02x s %g %g %g %g %g %g %g %g %g %g %g %g %g %g "
			  "%g "
			  "%g",
			  k->list->name, k->seg->index, k->rgba[0], k->rgba[1], k->rgba[2], k->rgba[3], m[0], m[4],
			  m[8], m[12], m[1], m[5], m[9], m[13], m[2], m[6], m[10], m[14], m[3], m[7], m[11], m[15]);
	}
	for (int kind = 0; kind < SGL_KINDS && sgl_geom_count(g) <= 64; kind++) {
		for (uint32_t i = 0; i < g->n[kind]; i++) {
			const struct sgl_vertex *v = &g->v[kind][i];
			sgl_trace("v %d %g %g %g %02x%02x%02x%02x", kind, v->xyz[0], v->xyz[1], v->xyz[2], v->rgba[0],
				  v->rgba[1], v->rgba[2], v->rgba[3]);
		}
	}
	sgl_trace("frame ctx %u by %s calls %u points %u lines %u triangles %u map %g %g %g %g %g %g %g %g %g %g %g %g "
		  "%s",
		  c->id, why, f->n_calls, g->n[SGL_POINTS], g->n[SGL_LINES], g->n[SGL_TRIS], map[0], map[4], map[8],
		  map[12], map[1], map[5], map[9], map[13], map[2], map[6], map[10], map[14], status_names[st]);
}

void sgl_frame_end(struct sgl_ctx *c, const char *why)
{
	struct sgl_frame *f = &c->frame;
	float h = 1, lo[3] = { 0, 0, 0 }, hi[3] = { 0, 0, 0 }, map[16];
	enum sgl_send st = sgl_out_poll(c->out, &h);
	if (sgl_config()->map == SGL_MAP_FIT)
		frame_bounds(f, lo, hi);
	sgl_frame_mapping(&c->fit, lo, hi, h, map);
	if (f->imm.overflow)
		sgl_warn_once("overflow", "over %u vertices in one frame: the rest are not shown", SGL_GEOM_MAX);
	/* Traced before sending, which may add to the immediate geometry. */
	if (sgl_config()->trace)
		trace_frame(c, why, map, st);
	if (st == SGL_SENT)
		st = sgl_out_send(c->out, f, map);
	sgl_frame_clear(f);
}
