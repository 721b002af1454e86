#include "draw.h"

#include <endian.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* Largest colour step, per channel (of 255), between neighbouring pieces
 * of a subdivided primitive; and the most pieces along an edge. */
#define COLOUR_STEP 16.0f
#define MAX_PIECES 16

struct vdata *vdata_ref(struct vdata *v)
{
	v->refs++;
	return v;
}

void vdata_unref(struct vdata *v)
{
	if (!v || --v->refs > 0)
		return;
	if (v->grid) {
		vgrid_unref(v->grid);
		free((void *)v->transfer.lut);
	}
	free(v);
}

struct vgrid *vgrid_ref(struct vgrid *g)
{
	g->refs++;
	return g;
}

void vgrid_unref(struct vgrid *g)
{
	if (!g || --g->refs > 0)
		return;
	free(g->samples);
	free(g->brick_max);
	free(g);
}

uint32_t draw_format_size(uint32_t format)
{
	switch (format) {
	case DRAW_XYZ:
		return 12;
	case DRAW_XYZ_RGBA8:
		return 16;
	case DRAW_XYZ_RGBA_FLOAT:
		return 28;
	}
	return 0;
}

/* One vertex as read: position, and colour with alpha applied, 0..255. */
struct vertex {
	float p[3];
	float rgb[3];
};

static float unit(float x)
{
	return x > 0 ? (x < 1 ? x : 1) : 0; /* NaN: 0 */
}

/* The client may write its memory while the daemon reads it: what a draw
 * is checked and sized on is read once, into the daemon's own memory.
 * Indices are copied, then checked; coloured vertices are copied, then
 * subdivided. Plain positions are read once each, straight into the
 * result. */
struct staged {
	const struct draw_source *s;
	uint32_t *index;    /* copied indices, or NULL: vertex i is i */
	struct vertex *vtx; /* coloured draws: every vertex of the draw, in order */
};

static uint32_t read_index(const struct draw_source *s, uint32_t i)
{
	if (s->index_size == 2) {
		uint16_t v;
		memcpy(&v, s->index + 2 * (size_t)i, 2);
		return le16toh(v);
	}
	uint32_t v;
	memcpy(&v, s->index + 4 * (size_t)i, 4);
	return le32toh(v);
}

/* Vertex i of the draw (the i-th index's vertex when indexed), read from
 * the client's buffer. */
static void fetch(const struct staged *st, uint32_t i, struct vertex *v)
{
	const struct draw_source *s = st->s;
	const uint8_t *p = s->base + (size_t)(st->index ? st->index[i] : i) * s->stride;
	memcpy(v->p, p, 12);
	if (s->format == DRAW_XYZ_RGBA8) {
		uint8_t c[4];
		memcpy(c, p + 12, 4);
		for (int k = 0; k < 3; k++)
			v->rgb[k] = c[k] * (c[3] / 255.0f);
	} else if (s->format == DRAW_XYZ_RGBA_FLOAT) {
		float f[4];
		memcpy(f, p + 12, 16);
		for (int k = 0; k < 3; k++)
			v->rgb[k] = 255.0f * unit(f[k]) * unit(f[3]);
	}
}

/* Vertex i as the draw is built from: the copy when there is one. */
static void vertex_at(const struct staged *st, uint32_t i, struct vertex *v)
{
	if (st->vtx)
		*v = st->vtx[i];
	else
		fetch(st, i, v);
}

static uint32_t draw_count(const struct draw_source *s)
{
	return s->index ? s->index_count : s->vertex_count;
}

static bool whole_primitives(enum draw_mode mode, uint32_t n)
{
	switch (mode) {
	case DRAW_POINTS:
		return true;
	case DRAW_LINES:
		return n % 2 == 0;
	case DRAW_TRIANGLES:
		return n % 3 == 0;
	case DRAW_LINE_STRIP:
		return n != 1;
	}
	return false;
}

/* Vertices per primitive of the result (strips become segments). */
static unsigned prim_vertices(enum draw_mode mode)
{
	static const unsigned n[] = { 1, 2, 3, 2 };
	return n[mode];
}

static uint32_t prim_count(enum draw_mode mode, uint32_t n)
{
	if (mode == DRAW_LINE_STRIP)
		return n ? n - 1 : 0;
	return n / prim_vertices(mode);
}

/* The draw positions of primitive p's vertices. */
static void prim_positions(enum draw_mode mode, uint32_t p, uint32_t pos[3])
{
	unsigned nv = prim_vertices(mode);
	uint32_t first = mode == DRAW_LINE_STRIP ? p : p * nv;
	for (unsigned i = 0; i < nv; i++)
		pos[i] = first + i;
}

static bool coloured(const struct draw_source *s)
{
	return s->format != DRAW_XYZ;
}

/* Pieces along each edge for a primitive whose vertex colours differ:
 * enough that neighbouring pieces differ by at most COLOUR_STEP. */
static unsigned pieces(const struct vertex *v, unsigned nv)
{
	float diff = 0;
	for (unsigned a = 0; a < nv; a++)
		for (unsigned b = a + 1; b < nv; b++)
			for (int c = 0; c < 3; c++)
				diff = fmaxf(diff, fabsf(v[a].rgb[c] - v[b].rgb[c]));
	unsigned k = (unsigned)ceilf(diff / COLOUR_STEP);
	return k < 1 ? 1 : k > MAX_PIECES ? MAX_PIECES : k;
}

static uint32_t pieces_prims(unsigned nv, unsigned k)
{
	return nv == 3 ? k * k : nv == 2 ? k : 1;
}

static void read_prim(const struct staged *st, uint32_t p, struct vertex v[3])
{
	uint32_t pos[3];
	prim_positions(st->s->mode, p, pos);
	for (unsigned i = 0; i < prim_vertices(st->s->mode); i++)
		vertex_at(st, pos[i], &v[i]);
}

/* Writes the result: into xyz (and rgb when coloured), one primitive at a
 * time. */
struct emitter {
	float *xyz;
	uint8_t *rgb;
};

static void emit_vertex(struct emitter *e, const float p[3])
{
	memcpy(e->xyz, p, 12);
	e->xyz += 3;
}

static void emit_colour(struct emitter *e, const float rgb[3])
{
	for (int c = 0; c < 3; c++)
		*e->rgb++ = (uint8_t)fminf(255.0f, rgb[c] + 0.5f);
}

/* a + (b - a) * t + (c - a) * u, for positions and colours alike. */
static void mix(float out[3], const float a[3], const float b[3], const float c[3], float t, float u)
{
	for (int i = 0; i < 3; i++)
		out[i] = a[i] + (b[i] - a[i]) * t + (c[i] - a[i]) * u;
}

static void emit_segment_pieces(struct emitter *e, const struct vertex v[2], unsigned k)
{
	for (unsigned j = 0; j < k; j++) {
		float p[3], col[3];
		mix(p, v[0].p, v[1].p, v[1].p, (float)j / k, 0);
		emit_vertex(e, p);
		mix(p, v[0].p, v[1].p, v[1].p, (float)(j + 1) / k, 0);
		emit_vertex(e, p);
		mix(col, v[0].rgb, v[1].rgb, v[1].rgb, (j + 0.5f) / k, 0);
		emit_colour(e, col);
	}
}

/* The triangle cut into k^2 by a grid of lines parallel to its edges:
 * corner (i, j) is a + (b - a) i/k + (c - a) j/k. Each small triangle
 * takes the colour at its centroid. */
static void emit_triangle_pieces(struct emitter *e, const struct vertex v[3], unsigned k)
{
	static const int up[3][2] = { { 0, 0 }, { 1, 0 }, { 0, 1 } };
	static const int down[3][2] = { { 1, 0 }, { 1, 1 }, { 0, 1 } };
	for (unsigned i = 0; i < k; i++)
		for (unsigned j = 0; i + j < k; j++)
			for (int d = 0; d < 2; d++) {
				if (d == 1 && i + j + 2 > k)
					continue;
				const int(*corner)[2] = d ? down : up;
				float p[3], col[3], third = d ? 2.0f / 3 : 1.0f / 3;
				for (int n = 0; n < 3; n++) {
					mix(p, v[0].p, v[1].p, v[2].p, (float)(i + corner[n][0]) / k,
					    (float)(j + corner[n][1]) / k);
					emit_vertex(e, p);
				}
				mix(col, v[0].rgb, v[1].rgb, v[2].rgb, (i + third) / k, (j + third) / k);
				emit_colour(e, col);
			}
}

static void emit_prim(struct emitter *e, const struct staged *st, uint32_t p)
{
	const struct draw_source *s = st->s;
	struct vertex v[3];
	unsigned nv = prim_vertices(s->mode);
	read_prim(st, p, v);
	if (!coloured(s)) {
		for (unsigned i = 0; i < nv; i++)
			emit_vertex(e, v[i].p);
		return;
	}
	unsigned k = pieces(v, nv);
	if (nv == 3)
		emit_triangle_pieces(e, v, k);
	else if (nv == 2)
		emit_segment_pieces(e, v, k);
	else {
		emit_vertex(e, v[0].p);
		emit_colour(e, v[0].rgb);
	}
}

/* Primitives of the result: subdivision counted when coloured. */
static uint64_t result_prims(const struct staged *st, uint32_t prims)
{
	const struct draw_source *s = st->s;
	if (!coloured(s) || s->mode == DRAW_POINTS)
		return prims;
	uint64_t total = 0;
	unsigned nv = prim_vertices(s->mode);
	for (uint32_t p = 0; p < prims; p++) {
		struct vertex v[3];
		read_prim(st, p, v);
		total += pieces_prims(nv, pieces(v, nv));
	}
	return total;
}

/* Copies the indices, then checks the copy. */
static enum draw_error stage_indices(struct staged *st, uint32_t *bad)
{
	const struct draw_source *s = st->s;
	if (!s->index)
		return DRAW_OK;
	st->index = malloc(((size_t)s->index_count + 1) * sizeof(uint32_t));
	if (!st->index)
		return DRAW_NO_MEMORY;
	for (uint32_t i = 0; i < s->index_count; i++)
		st->index[i] = read_index(s, i);
	for (uint32_t i = 0; i < s->index_count; i++)
		if (st->index[i] >= s->vertex_count) {
			*bad = i;
			return DRAW_BAD_INDEX;
		}
	return DRAW_OK;
}

/* Coloured draws are sized by their colours: read them once. */
static enum draw_error stage_vertices(struct staged *st, uint32_t n)
{
	if (!coloured(st->s))
		return DRAW_OK;
	st->vtx = malloc(((size_t)n + 1) * sizeof(*st->vtx));
	if (!st->vtx)
		return DRAW_NO_MEMORY;
	for (uint32_t i = 0; i < n; i++)
		fetch(st, i, &st->vtx[i]);
	return DRAW_OK;
}

static void unstage(struct staged *st)
{
	free(st->index);
	free(st->vtx);
}

/* v's bounding box; not bounded when a coordinate is not finite. */
static void bound(struct vdata *v)
{
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	bool finite = true;
	for (uint32_t i = 0; i < v->count; i++) {
		for (int a = 0; a < 3; a++) {
			float x = v->xyz[3 * (size_t)i + a];
			finite &= isfinite(x);
			lo[a] = x < lo[a] ? x : lo[a];
			hi[a] = x > hi[a] ? x : hi[a];
		}
	}
	v->bounded = finite && v->count > 0;
	memcpy(v->lo, lo, sizeof(lo));
	memcpy(v->hi, hi, sizeof(hi));
}

/* Builds the result from the staged draw. */
static enum draw_error build(const struct staged *st, uint32_t n, uint64_t max_vertices, struct vdata **out)
{
	const struct draw_source *s = st->s;
	uint32_t prims = prim_count(s->mode, n);
	if (prims == 0)
		return DRAW_OK;
	uint64_t total = result_prims(st, prims);
	uint64_t verts = total * prim_vertices(s->mode);
	if (verts > max_vertices || verts > UINT32_MAX)
		return DRAW_TOO_MANY;
	size_t rgb_bytes = coloured(s) ? (size_t)total * 3 : 0;
	struct vdata *v = malloc(sizeof(*v) + (size_t)verts * 12 + rgb_bytes);
	if (!v)
		return DRAW_NO_MEMORY;
	*v = (struct vdata){
		.refs = 1,
		.prim = s->mode == DRAW_LINE_STRIP ? SCENE_LINES : (enum scene_prim)s->mode,
		.count = (uint32_t)verts,
		.prims = (uint32_t)total,
		.prim_rgb = rgb_bytes ? (uint8_t *)(v->xyz + 3 * (size_t)verts) : NULL,
	};
	struct emitter e = { v->xyz, v->prim_rgb };
	if (!coloured(s) && s->mode != DRAW_LINE_STRIP && !s->index && s->stride == 12)
		memcpy(v->xyz, s->base, (size_t)verts * 12); /* the common case, at memory speed */
	else
		for (uint32_t p = 0; p < prims; p++)
			emit_prim(&e, st, p);
	bound(v);
	*out = v;
	return DRAW_OK;
}

enum draw_error draw_build(const struct draw_source *s, uint64_t max_vertices, struct vdata **out, uint32_t *bad_index)
{
	*out = NULL;
	uint32_t n = draw_count(s);
	if (!whole_primitives(s->mode, n))
		return DRAW_BAD_COUNT;
	if (n > max_vertices)
		return DRAW_TOO_MANY; /* the result has at least n: copy nothing */
	struct staged st = { .s = s };
	enum draw_error r = stage_indices(&st, bad_index);
	if (r == DRAW_OK)
		r = stage_vertices(&st, n);
	if (r == DRAW_OK)
		r = build(&st, n, max_vertices, out);
	unstage(&st);
	return r;
}
