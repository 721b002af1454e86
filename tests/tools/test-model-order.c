/* model_order_spatial() and model_morton_code(): the order is a permutation
 * that keeps each primitive with its colours, sorted by the Morton code of
 * its centroid (model_centroid()) as an independent bit-by-bit interleave
 * computes it, equal codes in their first order; flat and one-primitive
 * arrays. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "testvol.h"

static uint32_t rng_state = 0x12345678u;

static uint32_t next_u32(void)
{
	uint32_t x = rng_state;
	x ^= x << 13;
	x ^= x >> 17;
	x ^= x << 5;
	return rng_state = x;
}

static float unit(void)
{
	return (float)(next_u32() % 100000) / 100000.0f;
}

/* The code as the definition reads: cell i of each axis on 1024 cells over
 * lo .. hi (clamped), bit j of axis a's cell at bit 3 j + a. */
static uint32_t naive_code(const float c[3], const float lo[3], const float hi[3])
{
	uint32_t code = 0;
	for (int a = 0; a < 3; a++) {
		double q = hi[a] > lo[a] ? ((double)c[a] - lo[a]) / ((double)hi[a] - lo[a]) * 1024.0 : 0.0;
		uint32_t cell = q <= 0.0 ? 0 : q >= 1023.0 ? 1023 : (uint32_t)q;
		for (int j = 0; j < 10; j++)
			code |= (cell >> j & 1u) << (3 * j + a);
	}
	return code;
}

static void check_codes(void)
{
	const float lo[3] = { -1, -1, -1 }, hi[3] = { 1, 1, 1 };
	const float corner_lo[3] = { -1, -1, -1 }, corner_hi[3] = { 1, 1, 1 }, out[3] = { 5, -7, 0 };
	CHECK(model_morton_code(corner_lo, lo, hi) == 0);
	CHECK(model_morton_code(corner_hi, lo, hi) == (1u << 30) - 1);
	CHECK(model_morton_code(out, lo, hi) == naive_code(out, lo, hi));
	/* cell (1, 0, 0) is code 1, (0, 1, 0) 2, (0, 0, 1) 4, (2, 0, 0) 8 */
	const float step = 2.0f / 1024.0f;
	const float x1[3] = { -1 + 1.5f * step, -1, -1 }, y1[3] = { -1, -1 + 1.5f * step, -1 };
	const float z1[3] = { -1, -1, -1 + 1.5f * step }, x2[3] = { -1 + 2.5f * step, -1, -1 };
	CHECK(model_morton_code(x1, lo, hi) == 1);
	CHECK(model_morton_code(y1, lo, hi) == 2);
	CHECK(model_morton_code(z1, lo, hi) == 4);
	CHECK(model_morton_code(x2, lo, hi) == 8);
	for (int i = 0; i < 10000; i++) {
		float p[3] = { 2 * unit() - 1, 2 * unit() - 1, 2 * unit() - 1 };
		CHECK(model_morton_code(p, lo, hi) == naive_code(p, lo, hi));
	}
	const float flat_lo[3] = { 0, 3, 0 }, flat_hi[3] = { 1, 3, 1 }, on[3] = { 1, 3, 1 };
	CHECK(model_morton_code(on, flat_lo, flat_hi) == naive_code(on, flat_lo, flat_hi));
	CHECK(model_morton_code(on, flat_lo, flat_hi) == 0x9249249u * 5); /* x and z 1023, y 0 */
}

/* An array of n primitives of verts vertices: random, or with every
 * primitive repeated (same place, another colour) when dup, or flat in y. */
static void fill(float *xyz, uint8_t *rgba, size_t n, unsigned verts, bool dup, bool flat)
{
	for (size_t i = 0; i < n; i++) {
		for (unsigned j = 0; j < 3 * verts; j++)
			xyz[3 * verts * i + j] = flat && j % 3 == 1 ? 0.25f : 4 * unit() - 2;
		if (dup && i % 2 == 1)
			memcpy(&xyz[3 * verts * i], &xyz[3 * verts * (i - 1)], 3 * verts * sizeof(float));
		for (unsigned j = 0; j < 4 * verts; j++)
			rgba[4 * verts * i + j] = (uint8_t)(i * 7 + j); /* marks i */
	}
}

/* After the order: out is in code order (ties by first position) and is
 * in a permutation of in, each primitive with its own colours. */
static void check_order(const float *in, const uint8_t *in_rgba, const float *out, const uint8_t *out_rgba, size_t n,
			unsigned verts)
{
	const size_t fl = 3 * verts, by = 4 * verts;
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	for (size_t i = 0; i < n * verts; i++)
		for (int a = 0; a < 3; a++) {
			lo[a] = fminf(lo[a], in[3 * i + a]);
			hi[a] = fmaxf(hi[a], in[3 * i + a]);
		}
	bool *used = calloc(n, sizeof(bool));
	CHECK(used);
	uint32_t last_code = 0;
	size_t last_from = 0;
	for (size_t i = 0; i < n; i++) {
		size_t from = n;
		for (size_t j = 0; j < n && from == n; j++)
			if (!used[j] && !memcmp(&in[fl * j], &out[fl * i], fl * sizeof(float)) &&
			    !memcmp(&in_rgba[by * j], &out_rgba[by * i], by))
				from = j;
		CHECK(from < n); /* a primitive of the input, with its colours */
		used[from] = true;
		float c[3];
		model_centroid(&out[fl * i], verts, c);
		uint32_t code = naive_code(c, lo, hi);
		CHECK(i == 0 || code > last_code || (code == last_code && from > last_from));
		last_code = code;
		last_from = from;
	}
	free(used);
}

static void check_model(size_t n, bool dup, bool flat)
{
	struct model *m = calloc(1, sizeof(*m));
	CHECK(m);
	size_t counts[3] = { n, n / 2 + 1, 2 * n };
	m->triangle_count = counts[0];
	m->line_count = counts[1];
	m->point_count = counts[2];
	float **xyz[3] = { &m->triangles, &m->lines, &m->points };
	uint8_t **rgba[3] = { &m->triangle_colors, &m->line_colors, &m->point_colors };
	float *copy[3];
	uint8_t *copy_rgba[3];
	for (unsigned a = 0; a < 3; a++) {
		unsigned verts = 3 - a;
		*xyz[a] = malloc(counts[a] * 3 * verts * sizeof(float));
		*rgba[a] = malloc(counts[a] * 4 * verts);
		copy[a] = malloc(counts[a] * 3 * verts * sizeof(float));
		copy_rgba[a] = malloc(counts[a] * 4 * verts);
		CHECK(*xyz[a] && *rgba[a] && copy[a] && copy_rgba[a]);
		fill(*xyz[a], *rgba[a], counts[a], verts, dup, flat);
		memcpy(copy[a], *xyz[a], counts[a] * 3 * verts * sizeof(float));
		memcpy(copy_rgba[a], *rgba[a], counts[a] * 4 * verts);
	}
	CHECK(model_order_spatial(m) == 0);
	for (unsigned a = 0; a < 3; a++) {
		check_order(copy[a], copy_rgba[a], *xyz[a], *rgba[a], counts[a], 3 - a);
		free(copy[a]);
		free(copy_rgba[a]);
	}
	model_destroy(m);
}

/* Without colours, and with nothing or one of a kind; centroids. */
static void check_plain(void)
{
	const float tri[9] = { 0, 0, 0, 3, 0, 0, 0, 3, 3 }, seg[6] = { -1, 2, 4, 1, 2, 0 };
	float c[3];
	model_centroid(tri, 3, c);
	CHECK(c[0] == 1 && c[1] == 1 && c[2] == 1);
	model_centroid(seg, 2, c);
	CHECK(c[0] == 0 && c[1] == 2 && c[2] == 2);
	model_centroid(seg, 1, c);
	CHECK(c[0] == -1 && c[1] == 2 && c[2] == 4);
	struct model *m = calloc(1, sizeof(*m));
	CHECK(m);
	m->point_count = 1;
	m->points = malloc(3 * sizeof(float));
	CHECK(m->points);
	m->points[0] = 1, m->points[1] = 2, m->points[2] = 3;
	CHECK(model_order_spatial(m) == 0);
	CHECK(m->points[0] == 1 && m->points[1] == 2 && m->points[2] == 3 && !m->point_colors);
	m->triangle_count = 300;
	m->triangles = malloc(300 * 9 * sizeof(float));
	CHECK(m->triangles);
	for (size_t i = 0; i < 300 * 9; i++)
		m->triangles[i] = unit();
	CHECK(model_order_spatial(m) == 0);
	CHECK(!m->triangle_colors);
	model_destroy(m);
}

int main(void)
{
	check_codes();
	check_model(500, false, false);
	check_model(400, true, false); /* equal codes keep their order */
	check_model(300, false, true); /* flat in y */
	check_plain();
	printf("model order: ok\n");
	return 0;
}
