#include "bin.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "section.h"

int bin_init(struct bin_set *b, const struct geometry *g)
{
	memset(b, 0, sizeof(*b));
	b->image_count = geometry_images_per_volume(g);
	b->start = calloc(b->image_count + 1, sizeof(*b->start));
	b->stamp = calloc(b->image_count, sizeof(*b->stamp));
	if (!b->start || !b->stamp) {
		bin_finish(b);
		return -ENOMEM;
	}
	return 0;
}

void bin_finish(struct bin_set *b)
{
	free(b->prims);
	free(b->start);
	free(b->index);
	free(b->stamp);
	memset(b, 0, sizeof(*b));
}

/* Column-major affine transform; false if the result is not finite. */
static bool transform(const float m[16], const float *xyz, double out[3])
{
	double x = xyz[0], y = xyz[1], z = xyz[2];
	for (int i = 0; i < 3; i++) {
		out[i] = (double)m[i] * x + (double)m[4 + i] * y + (double)m[8 + i] * z + m[12 + i];
		if (!isfinite(out[i]))
			return false;
	}
	return true;
}

static int grow_prims(struct bin_set *b, size_t need)
{
	if (need <= b->prim_cap)
		return 0;
	if (need > UINT32_MAX - 1)
		return -E2BIG;
	size_t cap = b->prim_cap ? b->prim_cap : 256;
	while (cap < need)
		cap *= 2;
	struct bin_prim *p = realloc(b->prims, cap * sizeof(*p));
	if (!p)
		return -ENOMEM;
	b->prims = p;
	b->prim_cap = cap;
	return 0;
}

static int add_draw(struct bin_set *b, const struct scene_draw *d)
{
	int nv = d->prim == SCENE_POINTS ? 1 : d->prim == SCENE_LINES ? 2
		: d->prim == SCENE_TRIANGLES ? 3 : 0;
	if (nv == 0 || !d->xyz)
		return 0;
	uint32_t n = d->count / (uint32_t)nv;
	int r = grow_prims(b, (size_t)b->prim_count + n);
	if (r < 0)
		return r;
	for (uint32_t i = 0; i < n; i++) {
		struct bin_prim *p = &b->prims[b->prim_count];
		bool ok = true;
		for (int j = 0; j < nv && ok; j++)
			ok = transform(d->transform, d->xyz + ((size_t)i * nv + j) * 3, p->v[j]);
		if (!ok)
			continue; /* NaN or infinite: nothing sensible to light */
		p->nverts = (uint8_t)nv;
		memcpy(p->rgb, d->rgb, 3);
		b->prim_count++;
	}
	return 0;
}

/* The smallest arc of azimuths [*lo, *hi] (hi - lo < pi) holding the
 * primitive's xz projection. False when that projection may contain or touch
 * the axis: then every image can see it. */
static bool azimuth_arc(const struct bin_prim *p, double *lo, double *hi)
{
	double a[3] = { 0.0, 0.0, 0.0 };
	int n = p->nverts;
	for (int i = 0; i < n; i++) {
		if (p->v[i][0] == 0.0 && p->v[i][2] == 0.0)
			return false;
		a[i] = atan2(p->v[i][2], p->v[i][0]);
		for (int j = i; j > 0 && a[j - 1] > a[j]; j--) {
			double t = a[j];
			a[j] = a[j - 1];
			a[j - 1] = t;
		}
	}
	/* The convex hull misses the axis iff some angular gap exceeds pi. */
	double gap = a[0] + 2.0 * M_PI - a[n - 1];
	*lo = a[0];
	*hi = a[n - 1];
	for (int i = 0; i + 1 < n; i++) {
		if (a[i + 1] - a[i] > gap) {
			gap = a[i + 1] - a[i];
			*lo = a[i + 1];
			*hi = a[i] + 2.0 * M_PI;
		}
	}
	return gap > M_PI + 1e-9;
}

static void add(struct bin_set *b, uint32_t k, uint32_t prim, uint32_t *cursor)
{
	if (b->stamp[k] == prim + 1)
		return;
	b->stamp[k] = prim + 1;
	if (cursor)
		b->index[cursor[k]++] = prim;
	else
		b->start[k + 1]++;
}

/* Images j (of N) whose closed wedge [jD - D/2, jD + D/2] meets [lo, hi],
 * widened by one image each side against rounding. */
static void add_arc(struct bin_set *b, const struct geometry *g, double lo, double hi,
		    uint32_t prim, uint32_t *cursor)
{
	long long n = g->images_per_rev;
	double d = 2.0 * M_PI / (double)n;
	long long j0 = (long long)ceil(lo / d - 0.5) - 1;
	long long j1 = (long long)floor(hi / d + 0.5) + 1;
	if (j1 - j0 + 1 >= n)
		j1 = j0 + n - 1;
	for (long long j = j0; j <= j1; j++)
		add(b, (uint32_t)(((j % n) + n) % n) % b->image_count, prim, cursor);
}

static void bin_prim(struct bin_set *b, const struct geometry *g, uint32_t prim,
		     uint32_t *cursor)
{
	const struct bin_prim *p = &b->prims[prim];
	double lo, hi;
	if (p->nverts == 1) {
		uint32_t img[2];
		section_point_images(g, p->v[0], img);
		add(b, img[0], prim, cursor);
		add(b, img[1], prim, cursor);
	} else if (!azimuth_arc(p, &lo, &hi)) {
		for (uint32_t k = 0; k < b->image_count; k++)
			add(b, k, prim, cursor);
	} else {
		add_arc(b, g, lo, hi, prim, cursor);               /* lobe s >= 0 */
		add_arc(b, g, lo - M_PI, hi - M_PI, prim, cursor); /* lobe s < 0 */
	}
}

/* Counts per image, then fills: index entries of one image come out in
 * increasing primitive order, so renders are deterministic. */
static int fill_bins(struct bin_set *b, const struct geometry *g)
{
	uint32_t m = b->image_count;
	memset(b->start, 0, (m + 1) * sizeof(*b->start));
	memset(b->stamp, 0, m * sizeof(*b->stamp));
	for (uint32_t i = 0; i < b->prim_count; i++)
		bin_prim(b, g, i, NULL);
	uint64_t total = 0;
	for (uint32_t k = 0; k < m; k++) {
		total += b->start[k + 1];
		if (total > UINT32_MAX)
			return -E2BIG;
		b->start[k + 1] = (uint32_t)total;
	}
	if (total > b->index_cap) {
		uint32_t *idx = realloc(b->index, total * sizeof(*idx));
		if (!idx)
			return -ENOMEM;
		b->index = idx;
		b->index_cap = total;
	}
	uint32_t *cursor = malloc(m * sizeof(*cursor));
	if (!cursor)
		return -ENOMEM;
	memcpy(cursor, b->start, m * sizeof(*cursor));
	memset(b->stamp, 0, m * sizeof(*b->stamp));
	for (uint32_t i = 0; i < b->prim_count; i++)
		bin_prim(b, g, i, cursor);
	free(cursor);
	return 0;
}

int bin_build(struct bin_set *b, const struct geometry *g, const struct scene *scene)
{
	b->prim_count = 0;
	for (uint32_t i = 0; scene && i < scene->draw_count; i++) {
		int r = add_draw(b, &scene->draws[i]);
		if (r < 0)
			return r;
	}
	return fill_bins(b, g);
}
