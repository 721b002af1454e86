/* Primitives put in spatial order (model.h, model_order_spatial()): each
 * array sorted by the Morton code (Z-order) of its primitives' centroids on
 * a grid of 1024 cells a side over the array's bounding box (finer than
 * perspecta's 768 voxels across), ties kept in file order. */
#include "model.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GRID_BITS 10
#define RADIX_BITS 10 /* three passes over a 30-bit code */

struct keyed {
	uint32_t key, index;
};

/* The low 10 bits of v spread to every third bit (bit i to bit 3 i). */
static uint32_t spread3(uint32_t v)
{
	uint32_t x = v & ((1u << GRID_BITS) - 1);
	x = (x | x << 16) & 0x030000ffu;
	x = (x | x << 8) & 0x0300f00fu;
	x = (x | x << 4) & 0x030c30c3u;
	x = (x | x << 2) & 0x09249249u;
	return x;
}

uint32_t model_morton_code(const float c[3], const float lo[3], const float hi[3])
{
	uint32_t code = 0;
	for (int i = 0; i < 3; i++) {
		double extent = (double)hi[i] - lo[i], q = 0.0;
		if (extent > 0.0)
			q = ((double)c[i] - lo[i]) / extent * (1u << GRID_BITS);
		/* clamped: the top face and a centroid's rounding past the box */
		uint32_t cell = q > 0.0 ? (uint32_t)fmin(q, (1u << GRID_BITS) - 1) : 0;
		code |= spread3(cell) << i;
	}
	return code;
}

/* A stable sort of a[0 .. n-1] by key (LSD radix, tmp as large as a):
 * the result is in a. */
static void radix_sort(struct keyed *a, struct keyed *tmp, size_t n)
{
	for (unsigned shift = 0; shift < 3 * GRID_BITS; shift += RADIX_BITS) {
		size_t count[(1u << RADIX_BITS) + 1] = { 0 };
		for (size_t i = 0; i < n; i++)
			count[(a[i].key >> shift & ((1u << RADIX_BITS) - 1)) + 1]++;
		for (unsigned b = 0; b < 1u << RADIX_BITS; b++)
			count[b + 1] += count[b];
		for (size_t i = 0; i < n; i++)
			tmp[count[a[i].key >> shift & ((1u << RADIX_BITS) - 1)]++] = a[i];
		memcpy(a, tmp, n * sizeof(*a));
	}
}

void model_centroid(const float *v, unsigned verts, float out[3])
{
	for (int i = 0; i < 3; i++) {
		double s = 0.0;
		for (unsigned j = 0; j < verts; j++)
			s += v[3 * j + i];
		out[i] = (float)(s / verts);
	}
}

/* The box of the n vertices at xyz: finite (model_load() checks them; a
 * NaN would only land in cell 0). */
static void bounds(const float *xyz, size_t n, float lo[3], float hi[3])
{
	for (int c = 0; c < 3; c++)
		lo[c] = hi[c] = xyz[c];
	for (size_t i = 0; i < n; i++)
		for (int c = 0; c < 3; c++) {
			float v = xyz[3 * i + c];
			lo[c] = v < lo[c] ? v : lo[c];
			hi[c] = v > hi[c] ? v : hi[c];
		}
}

/* Sorts the n primitives of verts vertices in *xyz (and their colours,
 * 4 bytes a vertex, when *rgba is not NULL): 0, or -ENOMEM (-E2BIG past
 * 2^32 primitives) with both left as they were. */
static int order_array(float **xyz, uint8_t **rgba, size_t n, unsigned verts)
{
	if (n < 2)
		return 0;
	if (n > UINT32_MAX)
		return -E2BIG;
	const size_t floats = 3 * (size_t)verts, bytes = 4 * (size_t)verts;
	float lo[3], hi[3];
	bounds(*xyz, n * verts, lo, hi);
	struct keyed *k = malloc(2 * n * sizeof(*k));
	float *sorted = malloc(n * floats * sizeof(float));
	uint8_t *colours = *rgba ? malloc(n * bytes) : NULL;
	if (!k || !sorted || (*rgba && !colours)) {
		free(k);
		free(sorted);
		free(colours);
		return -ENOMEM;
	}
	for (size_t i = 0; i < n; i++) {
		float c[3];
		model_centroid(*xyz + i * floats, verts, c);
		k[i] = (struct keyed){ model_morton_code(c, lo, hi), (uint32_t)i };
	}
	radix_sort(k, k + n, n);
	for (size_t i = 0; i < n; i++) {
		memcpy(sorted + i * floats, *xyz + k[i].index * floats, floats * sizeof(float));
		if (colours)
			memcpy(colours + i * bytes, *rgba + k[i].index * bytes, bytes);
	}
	free(k);
	free(*xyz);
	*xyz = sorted;
	if (colours) {
		free(*rgba);
		*rgba = colours;
	}
	return 0;
}

int model_order_spatial(struct model *m)
{
	int r = order_array(&m->triangles, &m->triangle_colors, m->triangle_count, 3);
	if (r == 0)
		r = order_array(&m->lines, &m->line_colors, m->line_count, 2);
	if (r == 0)
		r = order_array(&m->points, &m->point_colors, m->point_count, 1);
	return r;
}
