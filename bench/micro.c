#include "micro.h"

#include <stdlib.h>
#include <string.h>

#include "log.h"
#include "rng.h"
#include "volume.h"

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

/* Median of n values, sorting them. */
static double median(double *v, int n)
{
	qsort(v, (size_t)n, sizeof(*v), cmp_double);
	return n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

#define MAX_RUNS 64

double micro_memcpy_gbps(size_t bytes, int runs)
{
	char *src = malloc(bytes), *dst = malloc(bytes);
	if (!src || !dst || runs < 1 || runs > MAX_RUNS) {
		free(src);
		free(dst);
		return -1;
	}
	memset(src, 0x5a, bytes);
	memset(dst, 0, bytes);
	double rate[MAX_RUNS];
	for (int i = 0; i < runs; i++) {
		int64_t t0 = now_ns();
		memcpy(dst, src, bytes);
		int64_t t1 = now_ns();
		/* Keep the copy observable. */
		src[(size_t)i % bytes] = dst[bytes - 1 - (size_t)i % bytes];
		rate[i] = (double)bytes / (double)(t1 - t0 > 0 ? t1 - t0 : 1);
	}
	free(src);
	free(dst);
	return median(rate, runs);
}

static void fill_random(uint8_t *p, size_t n, uint64_t seed)
{
	struct rng rng = rng_seed(seed);
	for (size_t i = 0; i < n; i += 8) {
		uint64_t v = rng_next(&rng);
		for (size_t j = 0; j < 8 && i + j < n; j++)
			p[i + j] = (uint8_t)(v >> (8 * j));
	}
}

double micro_halftone_gbps(halftone_fn fn, uint32_t tiles, int runs)
{
	uint8_t *canvas = malloc((size_t)tiles * HALFTONE_TILE_BYTES);
	uint8_t *out = malloc((size_t)tiles * VOLUME_TILE_BYTES);
	if (!canvas || !out || runs < 1 || runs > MAX_RUNS) {
		free(canvas);
		free(out);
		return -1;
	}
	fill_random(canvas, (size_t)tiles * HALFTONE_TILE_BYTES, 0x48414c46u);
	memset(out, 0, (size_t)tiles * VOLUME_TILE_BYTES);
	struct halftone_table table;
	halftone_table_init(&table, 5);
	double rate[MAX_RUNS];
	volatile int sink = 0;
	for (int i = 0; i < runs; i++) {
		int any = 0;
		int64_t t0 = now_ns();
		for (uint32_t t = 0; t < tiles; t++)
			any += fn(canvas + (size_t)t * HALFTONE_TILE_BYTES, UINT32_MAX, &table,
				  out + (size_t)t * VOLUME_TILE_BYTES);
		int64_t t1 = now_ns();
		sink += any;
		rate[i] = (double)tiles * HALFTONE_TILE_BYTES / (double)(t1 - t0 > 0 ? t1 - t0 : 1);
	}
	(void)sink;
	free(canvas);
	free(out);
	return median(rate, runs);
}
