/* daemon/turn: a transform turned about the axis by whole images, and moved
 * along it by whole rows where rows are asked for, is recognised against its
 * base, with the number of images and rows; anything else (another angle, a
 * turn about another axis, a move off the axis or by part of a row, a scale)
 * is not. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "turn.h"

static void pose(float t[16], double a, double s, double x, double y, double z)
{
	memset(t, 0, 16 * sizeof(float));
	t[0] = (float)(s * cos(a));
	t[2] = (float)(s * sin(a));
	t[5] = (float)s;
	t[8] = (float)(-s * sin(a));
	t[10] = (float)(s * cos(a));
	t[12] = (float)x;
	t[13] = (float)y;
	t[14] = (float)z;
	t[15] = 1;
}

/* t = R_y(a) * b, in float (t may be b). */
static void turned(float t[16], const float b_in[16], double a)
{
	float b[16];
	memcpy(b, b_in, sizeof(b));
	for (int c = 0; c < 4; c++) {
		t[c * 4] = (float)(cos(a) * b[c * 4] - sin(a) * b[c * 4 + 2]);
		t[c * 4 + 1] = b[c * 4 + 1];
		t[c * 4 + 2] = (float)(sin(a) * b[c * 4] + cos(a) * b[c * 4 + 2]);
		t[c * 4 + 3] = b[c * 4 + 3];
	}
}

/* Moves along the axis by whole rows, with and without a turn. */
static void check_lifts(const float base[16], uint32_t n)
{
	const double row = 2.0 * 0.9 / 768; /* a row of perspecta-like rows */
	float t[16];
	uint32_t m;
	int32_t lift;
	CHECK(turn_find_lift(base, base, n, row, &m, &lift) && m == 0 && lift == 0);
	for (long k = -700; k <= 700; k += 61) {
		turned(t, base, 2 * M_PI * 5 / n);
		t[13] = (float)(base[13] + k * row);
		CHECK(turn_find_lift(base, t, n, row, &m, &lift));
		CHECK_EQ(m, 5u);
		CHECK_EQ(lift, (int32_t)k);
		/* Without rows asked for, a move is no turn. */
		CHECK(k == 0 || !turn_find(base, t, n, &m));
	}
	/* A third of a row, or a move off the axis: no. */
	memcpy(t, base, sizeof(t));
	t[13] += (float)(4.33 * row);
	CHECK(!turn_find_lift(base, t, n, row, &m, &lift));
	memcpy(t, base, sizeof(t));
	t[13] += (float)(4 * row);
	t[12] += 0.001f;
	CHECK(!turn_find_lift(base, t, n, row, &m, &lift));
	/* A client's float moves, a row a frame for 600 frames: each is
	 * recognised against the base. */
	memcpy(t, base, sizeof(t));
	for (int f = 1; f <= 600; f++) {
		t[13] += (float)row;
		CHECK(turn_find_lift(base, t, n, row, &m, &lift));
		CHECK(m == 0 && lift == f);
	}
	/* Beyond the largest lift: no. */
	memcpy(t, base, sizeof(t));
	t[13] += (float)((TURN_MAX_LIFT + 1) * row);
	CHECK(!turn_find_lift(base, t, n, row, &m, &lift));
}

int main(void)
{
	const uint32_t n = 396;
	float base[16], t[16];
	uint32_t m;
	pose(base, 0.3, 0.8, 0.2, -0.1, 0.35);
	CHECK(turn_find(base, base, n, &m) && m == 0);
	for (long k = -800; k <= 800; k += 37) {
		turned(t, base, 2 * M_PI * (double)k / n);
		CHECK(turn_find(base, t, n, &m));
		CHECK_EQ(m, (uint32_t)(((k % (long)n) + (long)n) % (long)n));
	}
	/* Half an image off, a twentieth of one off: no. */
	turned(t, base, 2 * M_PI * 5.5 / n);
	CHECK(!turn_find(base, t, n, &m));
	turned(t, base, 2 * M_PI * 5.05 / n);
	CHECK(!turn_find(base, t, n, &m));
	/* Turned and moved, scaled, or turned about x: no. */
	turned(t, base, 2 * M_PI * 3 / n);
	t[13] += 0.001f;
	CHECK(!turn_find(base, t, n, &m));
	turned(t, base, 2 * M_PI * 3 / n);
	for (int i = 0; i < 12; i++)
		t[i] *= 1.001f;
	CHECK(!turn_find(base, t, n, &m));
	float rx[16];
	memcpy(rx, base, sizeof(rx));
	for (int c = 0; c < 4; c++) { /* about x by 3 images */
		double a = 2 * M_PI * 3 / n, y = base[c * 4 + 1], z = base[c * 4 + 2];
		rx[c * 4 + 1] = (float)(cos(a) * y - sin(a) * z);
		rx[c * 4 + 2] = (float)(sin(a) * y + cos(a) * z);
	}
	CHECK(!turn_find(base, rx, n, &m));
	/* Nothing off the axis: no turn to find. */
	float axis[16] = { 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0.5f, 0, 1 };
	CHECK(!turn_find(axis, axis, n, &m));
	/* A client's own float turns, accumulated frame by frame: each is
	 * recognised against the base. */
	float cur[16];
	memcpy(cur, base, sizeof(cur));
	for (int f = 1; f <= 400; f++) {
		turned(cur, cur, 2 * M_PI / n);
		CHECK(turn_find(base, cur, n, &m));
		CHECK_EQ(m, (uint32_t)(f % (int)n));
	}
	check_lifts(base, n);
	return check_done();
}
