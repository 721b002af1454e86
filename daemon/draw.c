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
	if (v && --v->refs == 0)
		free(v);
}

void mat4_mul(float out[16], const float a[16], const float b[16])
{
	for (int c = 0; c < 4; c++)
		for (int r = 0; r < 4; r++) {
			float s = 0;
			for (int k = 0; k < 4; k++)
				s += a[k * 4 + r] * b[c * 4 + k];
			out[c * 4 + r] = s;
		}
}

uint32_t draw_format_size(uint32_t format)
{
	switch (format) {
	case DRAW_XYZ: return 12;
	case DRAW_XYZ_RGBA8: return 16;
	case DRAW_XYZ_RGBA_FLOAT: return 28;
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

static uint32_t vertex_index(const struct draw_source *s, uint32_t i)
{
	if (!s->index)
		return i;
	if (s->index_size == 2) {
		uint16_t v;
		memcpy(&v, s->index + 2 * (size_t)i, 2);
		return le16toh(v);
	}
	uint32_t v;
	memcpy(&v, s->index + 4 * (size_t)i, 4);
	return le32toh(v);
}

/* Vertex i of the draw (the i-th index's vertex when indexed). */
static void fetch(const struct draw_source *s, uint32_t i, struct vertex *v)
{
	const uint8_t *p = s->base + (size_t)vertex_index(s, i) * s->stride;
	memcpy(v->p, p, 12);
	if (s->format == DRAW_XYZ_RGBA8) {
		for (int c = 0; c < 3; c++)
			v->rgb[c] = p[12 + c] * (p[15] / 255.0f);
	} else if (s->format == DRAW_XYZ_RGBA_FLOAT) {
		float f[4];
		memcpy(f, p + 12, 16);
		for (int c = 0; c < 3; c++)
			v->rgb[c] = 255.0f * unit(f[c]) * unit(f[3]);
	}
}

static uint32_t draw_count(const struct draw_source *s)
{
	return s->index ? s->index_count : s->vertex_count;
}

static bool whole_primitives(enum draw_mode mode, uint32_t n)
{
	switch (mode) {
	case DRAW_POINTS: return true;
	case DRAW_LINES: return n % 2 == 0;
	case DRAW_TRIANGLES: return n % 3 == 0;
	case DRAW_LINE_STRIP: return n != 1;
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

static void read_prim(const struct draw_source *s, uint32_t p, struct vertex v[3])
{
	uint32_t pos[3];
	prim_positions(s->mode, p, pos);
	for (unsigned i = 0; i < prim_vertices(s->mode); i++)
		fetch(s, pos[i], &v[i]);
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

static void emit_prim(struct emitter *e, const struct draw_source *s, uint32_t p)
{
	struct vertex v[3];
	unsigned nv = prim_vertices(s->mode);
	read_prim(s, p, v);
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
static uint64_t result_prims(const struct draw_source *s, uint32_t prims)
{
	if (!coloured(s) || s->mode == DRAW_POINTS)
		return prims;
	uint64_t total = 0;
	unsigned nv = prim_vertices(s->mode);
	for (uint32_t p = 0; p < prims; p++) {
		struct vertex v[3];
		read_prim(s, p, v);
		total += pieces_prims(nv, pieces(v, nv));
	}
	return total;
}

static bool indices_valid(const struct draw_source *s, uint32_t *bad)
{
	for (uint32_t i = 0; s->index && i < s->index_count; i++)
		if (vertex_index(s, i) >= s->vertex_count) {
			*bad = i;
			return false;
		}
	return true;
}

enum draw_error draw_build(const struct draw_source *s, uint64_t max_vertices, struct vdata **out,
			   uint32_t *bad_index)
{
	*out = NULL;
	uint32_t n = draw_count(s);
	if (!whole_primitives(s->mode, n))
		return DRAW_BAD_COUNT;
	if (!indices_valid(s, bad_index))
		return DRAW_BAD_INDEX;
	uint32_t prims = prim_count(s->mode, n);
	if (prims == 0)
		return DRAW_OK;
	uint64_t total = result_prims(s, prims);
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
			emit_prim(&e, s, p);
	*out = v;
	return DRAW_OK;
}
