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

/* A volume whose images each hold every tile with probability fill,
 * random bits; NULL when out of memory. */
static struct volume *random_fill(const struct geometry *g, double fill)
{
	struct volume *src = volume_create(g);
	uint8_t tile[VOLUME_TILE_BYTES];
	struct rng rng = rng_seed(0x53484654u);
	int err = !src;
	for (uint32_t k = 0; src && !err && k < src->image_count; k++)
		for (uint32_t t = 0; !err && t < volume_tiles_per_image(src); t++) {
			if ((double)(rng_next(&rng) >> 11) * 0x1p-53 >= fill)
				continue;
			fill_random(tile, sizeof(tile), rng_next(&rng));
			/* Edge tiles keep their padding dark: shift whole tiles in. */
			uint32_t x_end = g->width - t % src->tiles_x * VOLUME_TILE;
			uint32_t y_end = g->height - t / src->tiles_x * VOLUME_TILE;
			if (x_end < VOLUME_TILE || y_end < VOLUME_TILE)
				continue;
			err = volume_image_append(src, k, t, tile) < 0;
		}
	if (err) {
		volume_destroy(src);
		return NULL;
	}
	return src;
}

double micro_shift_ms(const struct geometry *g, double fill, int32_t du, int32_t dv, int runs, uint64_t *tiles)
{
	struct volume *src = random_fill(g, fill), *dst = volume_create(g);
	int err = !src || !dst || runs < 1 || runs > MAX_RUNS;
	double ms[MAX_RUNS];
	for (int i = 0; !err && i < runs; i++) {
		int64_t t0 = now_ns();
		err = volume_shift(dst, src, du, dv) < 0;
		ms[i] = (double)(now_ns() - t0) / 1e6;
	}
	if (!err)
		*tiles = volume_tile_count(src);
	volume_destroy(src);
	volume_destroy(dst);
	return err ? -1 : median(ms, runs);
}
