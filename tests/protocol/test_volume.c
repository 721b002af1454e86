/* Volumes through libspindle (protocol 6, docs/volumes.md), on the small
 * profile's daemon:
 *
 * sphere:  a 24^3 uint8 ball in a volume placed by a list transform lights
 *          every pixel whose centre lies inside the ball by more than half a
 *          sample's diagonal, and none outside it by more (nearest);
 * destroy: a destroyed volume is gone from the next volume shown, and its
 *          bytes from memory_used;
 * lut:     a two-entry lookup table colours the low half of a ramp red and
 *          the high half green;
 * errors:  a size of 0, a buffer too short, a window of width 0 and a
 *          draw of a non-volume are invalid_value / invalid_object, fatal to
 *          that client only;
 * quota:   a volume over max-buffer-bytes is the quota error;
 * big:     a volume over the daemon's step (8 MiB) is made a few slices per
 *          turn of its loop: the requests sent behind it wait for it (the
 *          ball shows exactly as the small one does), and a client that
 *          hangs up or destroys the volume while it is made leaves the
 *          daemon as it was. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scenes.h"

enum { N = 24 };

/* The ball's samples: 255 inside radius 0.4 of the unit cube's centre. */
static uint8_t *ball(void)
{
	static uint8_t v[N * N * N];
	for (uint32_t z = 0; z < N; z++)
		for (uint32_t y = 0; y < N; y++)
			for (uint32_t x = 0; x < N; x++) {
				double dx = (x + 0.5) / N - 0.5, dy = (y + 0.5) / N - 0.5, dz = (z + 0.5) / N - 0.5;
				v[(z * N + y) * N + x] = dx * dx + dy * dy + dz * dz <= 0.16 ? 255 : 0;
			}
	return v;
}

/* A layer showing vol (a unit cube of samples) scaled by s about the
 * origin, nearest, threshold 128, window 64/128 (255 at full colour,
 * which every threshold of the halftone lights); committed and shown. */
static struct spindle_layer *show_volume(struct spindle *sp, struct spindle_volume *vol, float s, uint8_t r, uint8_t g,
					 uint8_t b)
{
	struct spindle_list *l = spindle_list_create(sp);
	struct spindle_layer *y = spindle_layer_create(sp);
	const float m[16] = { s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, -s / 2, -s / 2, -s / 2, 1 };
	CHECK(l && y && spindle_list_set_transform(l, m) == 0 && spindle_list_set_color(l, r, g, b, 255) == 0);
	CHECK(spindle_list_draw_volume(l, vol, SPINDLE_NEAREST, 128, 64, 128) == 0);
	CHECK(spindle_layer_set_list(y, l) == 0);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	return y;
}

static struct spindle_volume *make_volume(struct spindle *sp, const void *data, enum spindle_volume_type type,
					  uint32_t bytes)
{
	struct spindle_buffer *buf = spindle_buffer_create(sp, data, bytes);
	CHECK(buf != NULL);
	const uint32_t size[3] = { N, N, N };
	const float spacing[3] = { 1.0f / N, 1.0f / N, 1.0f / N };
	struct spindle_volume *vol = spindle_volume_create(sp, buf, 0, type, size, spacing);
	CHECK(vol != NULL);
	spindle_buffer_destroy(buf); /* the daemon has its copy */
	return vol;
}

/* The ball of an n^3 volume shown scaled by s lights every pixel inside
 * it by more than half a sample's diagonal, and none outside it by more. */
static void check_ball(struct spindle *sp, float s, uint32_t n)
{
	struct volume *vol = capture_volume(sp);
	double R = 0.4 * s, margin = s / n * sqrt(3.0) / 2;
	uint64_t inside = 0, lit = 0;
	for (uint32_t k = 0; k < NV; k++)
		for (int v = 0; v < H; v++)
			for (int u = 0; u < W; u++) {
				double dist = hypot(col_s(u), row_y(v)) - R;
				bool on = volume_pixel(vol, k, (uint32_t)u, (uint32_t)v, 0);
				if (dist < -margin) {
					inside++;
					CHECK_MSG(on, "image %u (%d, %d): inside the ball, dark", k, u, v);
				} else if (dist > margin) {
					CHECK_MSG(!on, "image %u (%d, %d): outside the ball, lit", k, u, v);
				}
				lit += on;
			}
	CHECK(inside > 10000 && lit >= inside);
	volume_destroy(vol);
}

static void test_sphere(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	const float s = 1.4f;
	show_volume(sp, make_volume(sp, ball(), SPINDLE_VOLUME_U8, N * N * N), s, 255, 255, 255);
	check_ball(sp, s, N);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static uint64_t memory_used(struct spindle *sp)
{
	struct spindle_status st;
	CHECK(spindle_get_status(sp, &st) == 0 && st.limits_known);
	return st.limits.memory_used;
}

static void test_destroy(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	uint64_t before = memory_used(sp);
	struct spindle_volume *v = make_volume(sp, ball(), SPINDLE_VOLUME_U8, N * N * N);
	show_volume(sp, v, 1.4f, 255, 255, 255);
	CHECK(memory_used(sp) >= before + N * N * N);
	struct volume *shown = capture_volume(sp);
	CHECK(count_lit(shown, 0) > 1000);
	volume_destroy(shown);
	spindle_volume_destroy(v);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0); /* a frame after the destroy */
	shown = capture_volume(sp);
	CHECK_MSG(count_lit(shown, 0) == 0, "the destroyed volume still shows");
	CHECK(memory_used(sp) < before + N * N * N);
	volume_destroy(shown);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void test_lut(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	/* A ramp along y: 0 at the bottom to 255 at the top, everything lit
	 * (threshold 0), window 0..256: the low half entry 0, the high half 1. */
	static uint8_t ramp[N * N * N];
	for (uint32_t z = 0; z < N; z++)
		for (uint32_t y = 0; y < N; y++)
			for (uint32_t x = 0; x < N; x++)
				ramp[(z * N + y) * N + x] = (uint8_t)(y * 255 / (N - 1));
	struct spindle_volume *v = make_volume(sp, ramp, SPINDLE_VOLUME_U8, N * N * N);
	const uint8_t lut[8] = { 255, 0, 0, 255, 0, 255, 0, 255 };
	struct spindle_buffer *lb = spindle_buffer_create(sp, lut, sizeof(lut));
	struct spindle_list *l = spindle_list_create(sp);
	struct spindle_layer *y = spindle_layer_create(sp);
	const float s = 1.0f, m[16] = { s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, -s / 2, -s / 2, -s / 2, 1 };
	CHECK(lb && l && y && spindle_list_set_transform(l, m) == 0);
	CHECK(spindle_list_set_volume_lut(l, lb, 0, 2) == 0);
	CHECK(spindle_list_draw_volume(l, v, SPINDLE_NEAREST, 0, 128, 256) == 0);
	CHECK(spindle_layer_set_list(y, l) == 0);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	struct volume *vol = capture_volume(sp);
	int low = row(-0.3), high = row(0.3); /* well inside each half */
	CHECK(volume_pixel(vol, 0, (uint32_t)col(0.1), (uint32_t)low, 0) &&
	      !volume_pixel(vol, 0, (uint32_t)col(0.1), (uint32_t)low, 1));
	CHECK(volume_pixel(vol, 0, (uint32_t)col(0.1), (uint32_t)high, 1) &&
	      !volume_pixel(vol, 0, (uint32_t)col(0.1), (uint32_t)high, 0));
	CHECK(count_lit(vol, 2) == 0);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* Each bad request kills its own connection with code; a witness lives. */
static void expect_fatal(struct spindle *sp, struct spindle *witness, uint32_t code)
{
	CHECK(spindle_roundtrip(sp) == -EPIPE);
	CHECK_EQ(spindle_get_error_code(sp), code);
	spindle_disconnect(sp);
	CHECK(spindle_roundtrip(witness) == 0);
}

static void test_errors(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *witness = client_connect(&d);
	const uint8_t bytes[16] = { 0 };
	const float spacing[3] = { 1, 1, 1 };
	const uint32_t zero[3] = { 4, 0, 4 }, big[3] = { 4, 4, 4 }, one[3] = { 2, 2, 2 };
	struct spindle *sp = client_connect(&d);
	struct spindle_buffer *b = spindle_buffer_create(sp, bytes, sizeof(bytes));
	CHECK(spindle_volume_create(sp, b, 0, SPINDLE_VOLUME_U8, zero, spacing) != NULL);
	expect_fatal(sp, witness, SPINDLE_ERROR_INVALID_VALUE);
	sp = client_connect(&d); /* 64 samples from a 16-byte buffer */
	b = spindle_buffer_create(sp, bytes, sizeof(bytes));
	CHECK(spindle_volume_create(sp, b, 0, SPINDLE_VOLUME_U8, big, spacing) != NULL);
	expect_fatal(sp, witness, SPINDLE_ERROR_INVALID_VALUE);
	sp = client_connect(&d); /* a window of width 0 */
	b = spindle_buffer_create(sp, bytes, sizeof(bytes));
	struct spindle_volume *v = spindle_volume_create(sp, b, 0, SPINDLE_VOLUME_U16, one, spacing);
	struct spindle_list *l = spindle_list_create(sp);
	CHECK(v && l && spindle_roundtrip(sp) == 0);
	CHECK(spindle_list_draw_volume(l, v, SPINDLE_TRILINEAR, 0, 10, 0) == 0);
	expect_fatal(sp, witness, SPINDLE_ERROR_INVALID_VALUE);
	sp = client_connect(&d); /* a lookup table of one entry */
	b = spindle_buffer_create(sp, bytes, sizeof(bytes));
	l = spindle_list_create(sp);
	CHECK(spindle_list_set_volume_lut(l, b, 0, 1) == 0);
	expect_fatal(sp, witness, SPINDLE_ERROR_INVALID_VALUE);
	spindle_disconnect(witness);
	daemon_stop(&d);
}

static void test_quota(void)
{
	struct daemon d;
	daemon_start_config(&d, "max-buffer-bytes = 20000\n");
	struct spindle *witness = client_connect(&d);
	struct spindle *sp = client_connect(&d);
	/* The buffer (13,824 bytes) and the volume's copy of it: over 20,000. */
	make_volume(sp, ball(), SPINDLE_VOLUME_U8, N * N * N);
	expect_fatal(sp, witness, SPINDLE_ERROR_QUOTA);
	spindle_disconnect(witness);
	daemon_stop(&d);
}

enum { NB = 320 }; /* 32.8 MB of uint8: four steps */

static struct spindle_volume *big_ball(struct spindle *sp, bool keep_buffer, struct spindle_buffer **buf_out)
{
	uint8_t *v = malloc((size_t)NB * NB * NB);
	CHECK(v != NULL);
	for (uint32_t z = 0; z < NB; z++)
		for (uint32_t y = 0; y < NB; y++)
			for (uint32_t x = 0; x < NB; x++) {
				double dx = (x + 0.5) / NB - 0.5, dy = (y + 0.5) / NB - 0.5, dz = (z + 0.5) / NB - 0.5;
				v[((size_t)z * NB + y) * NB + x] = dx * dx + dy * dy + dz * dz <= 0.16 ? 255 : 0;
			}
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, (size_t)NB * NB * NB);
	free(v);
	CHECK(buf != NULL);
	const uint32_t size[3] = { NB, NB, NB };
	const float spacing[3] = { 1.0f / NB, 1.0f / NB, 1.0f / NB };
	struct spindle_volume *vol = spindle_volume_create(sp, buf, 0, SPINDLE_VOLUME_U8, size, spacing);
	CHECK(vol != NULL);
	if (keep_buffer)
		*buf_out = buf;
	else
		spindle_buffer_destroy(buf);
	return vol;
}

static void test_big(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *witness = client_connect(&d);
	uint64_t before = memory_used(witness);
	/* Shown: the draw and commit queued behind the volume wait for it. */
	struct spindle *sp = client_connect(&d);
	struct spindle_layer *y = show_volume(sp, big_ball(sp, false, NULL), 1.4f, 255, 255, 255);
	CHECK(y != NULL);
	check_ball(sp, 1.4f, NB); /* as the small one: every slab's bricks made */
	/* Another client's volume while a third is served. */
	struct spindle *other = client_connect(&d);
	struct spindle_volume *ov = big_ball(other, false, NULL);
	CHECK(spindle_flush(other) == 0);
	CHECK(spindle_roundtrip(witness) == 0);
	CHECK(spindle_roundtrip(other) == 0);
	/* Destroyed right behind its create, with its buffer. */
	struct spindle_buffer *b = NULL;
	struct spindle_volume *gone = big_ball(other, true, &b);
	spindle_volume_destroy(gone);
	spindle_buffer_destroy(b);
	spindle_volume_destroy(ov);
	CHECK(spindle_roundtrip(other) == 0);
	spindle_disconnect(other);
	/* Hung up while its volume is made. */
	struct spindle *quitter = client_connect(&d);
	big_ball(quitter, false, NULL);
	CHECK(spindle_flush(quitter) == 0);
	spindle_disconnect(quitter);
	spindle_disconnect(sp);
	/* Back to where it was, once the daemon has let them go. */
	uint64_t now = 0;
	for (int i = 0; i < 200 && (now = memory_used(witness)) > before; i++)
		usleep(10000);
	CHECK_MSG(now <= before, "memory_used %llu, %llu before", (unsigned long long)now, (unsigned long long)before);
	spindle_disconnect(witness);
	daemon_stop(&d);
}

static const struct named_test tests[] = {
	{ "sphere", test_sphere }, { "destroy", test_destroy }, { "lut", test_lut },
	{ "errors", test_errors }, { "quota", test_quota },     { "big", test_big },
};

int main(int argc, char **argv)
{
	return run_named_tests(tests, sizeof(tests) / sizeof(tests[0]), argc, argv);
}
