#include "slot.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#define NO_EDGE 4.0f

/* Azimuth of slope s in octant o: even octants grow with s from o * pi/4,
 * odd ones shrink with s from (o + 1) * pi/4. */
static double azimuth(unsigned o, double s)
{
	double base = M_PI / 4.0 * o;
	return o % 2 == 0 ? base + atan(s) : base + M_PI / 4.0 - atan(s);
}

static uint16_t slot_at(uint32_t n, double phi)
{
	long long k = llround(phi / (2.0 * M_PI / n)) % (long long)n;
	return (uint16_t)(k < 0 ? k + n : k);
}

/* Slope of every boundary (j + 1/2) D inside octant o goes into its bucket. */
static void place_edges(struct slot_table *t, unsigned o, struct slot_bucket *row)
{
	/* Boundaries that rounding puts a hair outside the octant (on one of
	 * the four planes) still count, at slope 0 or 1. */
	double d = 2.0 * M_PI / t->n, lo = M_PI / 4.0 * o, hi = lo + M_PI / 4.0, eps = 1e-12;
	for (long long j = (long long)floor((lo - eps) / d - 0.5); (j + 0.5) * d <= hi + eps; j++) {
		double a = (j + 0.5) * d;
		if (a < lo - eps)
			continue;
		double local = fmin(fmax(o % 2 == 0 ? a - lo : hi - a, 0.0), M_PI / 4.0);
		double s = tan(local);
		uint32_t i = (uint32_t)fmin(s * t->buckets, t->buckets);
		row[i].edge = (float)s;
	}
}

static void fill_slots(struct slot_table *t, unsigned o, struct slot_bucket *row)
{
	/* A quarter slot either side of a boundary is safely inside the two
	 * slots it separates (boundaries are a whole slot apart). */
	double q = M_PI / (2.0 * t->n), dir = o % 2 == 0 ? 1.0 : -1.0;
	for (uint32_t i = 0; i <= t->buckets; i++) {
		double mid = fmin((i + 0.5) / t->buckets, 1.0);
		if (row[i].edge == NO_EDGE) {
			row[i].below = row[i].above = slot_at(t->n, azimuth(o, mid));
			continue;
		}
		double a = azimuth(o, row[i].edge);
		row[i].below = slot_at(t->n, a - dir * q);
		row[i].above = slot_at(t->n, a + dir * q);
	}
	/* The near test's flags (slot.h): a neighbour's edge within twice
	 * its width of the shared border. */
	const float close = 2.0f * SLOT_NEAR;
	for (uint32_t i = 0; i <= t->buckets; i++) {
		float lo = (float)i / (float)t->buckets, hi = (float)(i + 1) / (float)t->buckets;
		if (i > 0 && row[i - 1].edge != NO_EDGE && row[i - 1].edge > lo - close)
			row[i].above |= SLOT_NEAR_LOW;
		if (i < t->buckets && row[i + 1].edge != NO_EDGE && row[i + 1].edge < hi + close)
			row[i].above |= SLOT_NEAR_HIGH;
	}
}

int slot_table_init(struct slot_table *t, uint32_t n)
{
	/* Boundaries are at least D apart in angle, so at least D apart in
	 * slope (d tan >= d angle): buckets narrower than D hold one at most. */
	uint32_t buckets = 16;
	while (buckets < n)
		buckets *= 2;
	t->n = n;
	t->buckets = buckets;
	t->b = calloc(8 * (size_t)(buckets + 1), sizeof(*t->b));
	if (!t->b)
		return -ENOMEM;
	for (unsigned o = 0; o < 8; o++) {
		struct slot_bucket *row = &t->b[o * (buckets + 1)];
		for (uint32_t i = 0; i <= buckets; i++)
			row[i].edge = NO_EDGE;
		place_edges(t, o, row);
		fill_slots(t, o, row);
	}
	return 0;
}

void slot_table_finish(struct slot_table *t)
{
	free(t->b);
	t->b = NULL;
}
