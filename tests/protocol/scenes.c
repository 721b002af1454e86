/* Shapes, checks and helpers shared by the protocol test programs
 * (test_protocol.c, test_devices.c). */
#include "scenes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

struct geometry small(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	return g;
}

int col(double s)
{
	struct geometry g = small();
	return (int)geometry_column(&g, s) + test_calibration()->axis_u;
}

int row(double y)
{
	struct geometry g = small();
	const struct calibration *cal = test_calibration();
	return (int)geometry_row(&g, y * cal->vertical_scale + cal->vertical_offset) + cal->axis_v;
}

double col_s(int u)
{
	return (u - test_calibration()->axis_u + 0.5) * 2.0 / W - 1.0;
}

double row_y(int v)
{
	const struct calibration *cal = test_calibration();
	return (1.0 - (v - cal->axis_v + 0.5) * 2.0 / H - cal->vertical_offset) / cal->vertical_scale;
}

/* ---- shapes ---- */

uint32_t axis_line(float *v)
{
	const float p[] = { 0, -0.6f, 0, 0, 0.6f, 0 };
	memcpy(v, p, sizeof(p));
	return 2;
}

uint32_t disk(float *v, double r, double y, int segs)
{
	uint32_t n = 0;
	for (int i = 0; i < segs; i++) {
		double a0 = 2 * M_PI * i / segs, a1 = 2 * M_PI * (i + 1) / segs;
		float t[] = { 0,
			      (float)y,
			      0,
			      (float)(r * cos(a0)),
			      (float)y,
			      (float)(r * sin(a0)),
			      (float)(r * cos(a1)),
			      (float)y,
			      (float)(r * sin(a1)) };
		memcpy(v + 3 * n, t, sizeof(t));
		n += 3;
	}
	return n;
}

static void sphere_point(float *out, double r, int i, int j, int slices, int stacks)
{
	double th = M_PI * j / stacks, ph = 2 * M_PI * i / slices;
	out[0] = (float)(r * sin(th) * cos(ph));
	out[1] = (float)(r * cos(th));
	out[2] = (float)(r * sin(th) * sin(ph));
}

uint32_t sphere(float *v, double r, int slices, int stacks)
{
	uint32_t n = 0;
	for (int j = 0; j < stacks; j++)
		for (int i = 0; i < slices; i++) {
			float a[3], b[3], c[3], d[3];
			sphere_point(a, r, i, j, slices, stacks);
			sphere_point(b, r, i + 1, j, slices, stacks);
			sphere_point(c, r, i + 1, j + 1, slices, stacks);
			sphere_point(d, r, i, j + 1, slices, stacks);
			float *t = v + 3 * n;
			memcpy(t, a, 12), memcpy(t + 3, b, 12), memcpy(t + 6, c, 12);
			memcpy(t + 9, a, 12), memcpy(t + 12, c, 12), memcpy(t + 15, d, 12);
			n += 6;
		}
	return n;
}

void check_axis_line(const struct volume *vol, int c)
{
	int top = row(0.6), bottom = row(-0.6);
	for (uint32_t k = 0; k < NV; k++) {
		for (int v = top; v <= bottom; v++)
			CHECK(lit_near(vol, k, col(0), v, c, 1));
		for (int v = 0; v < H; v++)
			for (int u = 0; u < W; u++)
				if (volume_pixel(vol, k, (uint32_t)u, (uint32_t)v, c))
					CHECK(abs(u - col(0)) <= 1 && v >= top - 1 && v <= bottom + 1);
	}
}

void check_shows_axis_line(struct spindle *sp)
{
	struct volume *vol = capture_volume(sp);
	for (int c = 0; c < 3; c++)
		check_axis_line(vol, c);
	volume_destroy(vol);
}

uint64_t mono_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };

void shift_x(float m[16], float dx)
{
	memcpy(m, identity, sizeof(identity));
	m[12] = dx;
}

struct spindle_layer *show_triangles(struct spindle *sp, struct spindle_frame *frame, const float *v, uint32_t n,
				     uint8_t r, uint8_t g, uint8_t b)
{
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, (size_t)n * 12);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	CHECK(buf && list && layer);
	CHECK(spindle_list_set_color(list, r, g, b, 255) == 0);
	CHECK(spindle_list_triangles(list, buf, 0, n, 0) == 0);
	CHECK(spindle_layer_set_list(layer, list) == 0);
	CHECK(spindle_commit_and_wait(sp, frame) == 0);
	CHECK(frame->volume_seq > 0 && frame->time_ns > 0);
	return layer;
}

struct spindle_status status_of(struct spindle *sp)
{
	struct spindle_status st;
	CHECK(spindle_get_status(sp, &st) == 0);
	return st;
}

int run_named_tests(const struct named_test *tests, size_t count, int argc, char **argv)
{
	for (size_t i = 0; i < count; i++) {
		if (argc < 2 || strcmp(argv[1], tests[i].name) == 0) {
			tests[i].run();
			printf("ok %s\n", tests[i].name);
		}
	}
	return check_done();
}

uint64_t count_lit_image(const struct volume *vol, uint32_t k, int c)
{
	uint64_t n = 0;
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t u = 0; u < W; u++)
			n += volume_pixel(vol, k, u, y, c);
	return n;
}

uint64_t count_lit(const struct volume *vol, int c)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < vol->image_count; k++)
		n += count_lit_image(vol, k, c);
	return n;
}
