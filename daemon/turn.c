/* Turns about the axis by whole images (turn.h). */
#include "turn.h"

#include <math.h>

/* The lift of t against base (its y move in whole rows of row_h), or 0. */
static long whole_rows(const float base[16], const float t[16], double row_h)
{
	if (!(row_h > 0))
		return 0;
	double rows = round(((double)t[13] - base[13]) / row_h);
	return fabs(rows) <= TURN_MAX_LIFT ? (long)rows : 0;
}

bool turn_find(const float base[16], const float t[16], uint32_t n, uint32_t *steps)
{
	int32_t lift;
	return turn_find_lift(base, t, n, 0, steps, &lift);
}

bool turn_find_lift(const float base[16], const float t[16], uint32_t n, double row_h, uint32_t *steps, int32_t *lift)
{
	if (n == 0)
		return false;
	/* Each column's (x, z) turns by the angle: cross and dot products
	 * summed over the columns give it, weighted by their lengths. */
	double cross = 0, dot = 0, norm = 0, scale = 1;
	for (int c = 0; c < 4; c++) {
		double bx = base[c * 4], bz = base[c * 4 + 2], tx = t[c * 4], tz = t[c * 4 + 2];
		cross += bx * tz - bz * tx;
		dot += bx * tx + bz * tz;
		norm += bx * bx + bz * bz;
	}
	for (int i = 0; i < 16; i++)
		if (fabs(t[i]) > scale)
			scale = fabs(t[i]);
	if (norm < 1e-12)
		return false;
	double step = 2 * M_PI / n;
	long m = lround(atan2(cross, dot) / step), rows = whole_rows(base, t, row_h);
	double a = m * step, ca = cos(a), sa = sin(a);
	for (int c = 0; c < 4; c++) {
		double bx = base[c * 4], bz = base[c * 4 + 2];
		double want[4] = { ca * bx - sa * bz, base[c * 4 + 1], sa * bx + ca * bz, base[c * 4 + 3] };
		if (c == 3)
			want[1] += (double)rows * row_h;
		for (int r = 0; r < 4; r++)
			if (fabs(want[r] - t[c * 4 + r]) > TURN_TOLERANCE * scale)
				return false;
	}
	*steps = (uint32_t)(((m % (long)n) + (long)n) % (long)n);
	*lift = (int32_t)rows;
	return true;
}
