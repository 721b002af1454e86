/* Which slot of the revolution an azimuth falls in, from slopes instead of
 * atan2 (docs/design.md section 5, binning).
 *
 * Slot j of N is the closed wedge of azimuths [(j - 1/2) D, (j + 1/2) D],
 * D = 2 pi / N: the s >= 0 lobe of image j. The four planes through the
 * axis x = 0, z = 0, x = z, x = -z cut the plane into eight octants (the
 * outcodes); inside an octant the azimuth is a monotonic function of the
 * slope t = min(|x|, |z|) / max(|x|, |z|) in [0, 1], so a table of the slot
 * boundaries' slopes, bucketed so that each bucket holds at most one
 * boundary, gives the slot with one division, one load and one compare. */
#ifndef SPINDLE_SLOT_H
#define SPINDLE_SLOT_H

#include <stdbool.h>
#include <stdint.h>

#define SLOT_AXIS UINT32_MAX /* the point is on the axis: no azimuth */

/* A bucket, 8 bytes (one 64-bit gather in the vector paths): its edge,
 * the slots below and above it (N <= 16384 fits 14 bits), and two flags
 * for the near test. A slope is near when it lies within 1e-5 of the
 * bucket's edge, or of a border of the bucket whose neighbour beyond it
 * has its edge within 2e-5 of that border: any boundary within 1e-5 of a
 * slope is the edge of its bucket or of a neighbour, and then within
 * 1e-5 of the border between them. */
#define SLOT_ABOVE 0x3FFFu
#define SLOT_NEAR_LOW 0x4000u  /* the bucket below has an edge close to this one's lower border */
#define SLOT_NEAR_HIGH 0x8000u /* the bucket above, close to the upper border */
#define SLOT_NEAR 1e-5f        /* the near test's width, in slope */
struct slot_bucket {
	float edge;     /* slope of the boundary in this bucket, or 4 (none) */
	uint16_t below; /* slot for slopes < edge */
	uint16_t above; /* slot for slopes >= edge (SLOT_ABOVE), and the SLOT_NEAR_ flags */
};

struct slot_table {
	uint32_t n;            /* slots per revolution N */
	uint32_t buckets;      /* per octant, a power of two; bucket i covers [i, i+1) / buckets */
	struct slot_bucket *b; /* 8 * (buckets + 1) */
};

/* Returns 0 or -ENOMEM. */
int slot_table_init(struct slot_table *t, uint32_t n);
void slot_table_finish(struct slot_table *t);

/* The slot of azimuth atan2(z, x), or SLOT_AXIS when x = z = 0. *near is
 * set when the azimuth lies so close to a slot boundary that rounding may
 * have put it on the wrong side (then the neighbouring slot may be the
 * true one); it is left alone otherwise. x and z must be finite. */
static inline uint32_t slot_of(const struct slot_table *t, float x, float z, bool *near)
{
	float ax = x < 0.0f ? -x : x, az = z < 0.0f ? -z : z;
	/* Quadrant q: 0 (x >= 0, z >= 0), 1 (x < 0, z >= 0), 2, 3. Inside it,
	 * the angle from the quadrant's first axis (+x, +z, -x, -z) grows
	 * with perp / radial. */
	unsigned q = z < 0.0f ? (x < 0.0f ? 2u : 3u) : (x < 0.0f ? 1u : 0u);
	float perp = q & 1u ? ax : az, radial = q & 1u ? az : ax;
	unsigned octant;
	float s;
	if (perp <= radial) {
		if (radial == 0.0f)
			return SLOT_AXIS;
		octant = 2 * q;
		s = perp / radial;
	} else {
		octant = 2 * q + 1;
		s = radial / perp;
	}
	/* s times the bucket count, a power of two, is exact, and so is
	 * where s lies in its bucket (frac, 0 .. 1) */
	float sn = s * (float)t->buckets, frac = sn - (float)(uint32_t)sn, close = SLOT_NEAR * (float)t->buckets;
	const struct slot_bucket *e = &t->b[octant * (t->buckets + 1) + (uint32_t)sn];
	float d = s - e->edge;
	if ((d < SLOT_NEAR && d > -SLOT_NEAR) || ((e->above & SLOT_NEAR_LOW) && frac < close) ||
	    ((e->above & SLOT_NEAR_HIGH) && 1.0f - frac < close))
		*near = true;
	return s >= e->edge ? e->above & SLOT_ABOVE : e->below;
}

#endif
