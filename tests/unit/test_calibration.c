/* Calibration (calibration.h): keys, ranges and text; the transform's
 * turn and scale; and volume_shift() against a pixel-by-pixel shift of
 * random sparse volumes, at sizes with partial edge tiles and offsets of
 * whole tiles, parts of tiles and past the image, for sources with
 * tiles everywhere and with a few. */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <string.h>

#include "calibration.h"
#include "check.h"
#include "volume.h"

static void test_keys(void)
{
	struct calibration c;
	calibration_identity(&c);
	CHECK(!calibration_has_transform(&c));
	for (unsigned k = 0; k < CALIBRATION_KEYS; k++)
		CHECK_EQ(calibration_key_from_name(calibration_key_name(k)), k);
	CHECK(calibration_key_name(CALIBRATION_KEYS) == NULL);
	CHECK_EQ(calibration_key_from_name("phase"), -ENOENT);
	CHECK(calibration_set_text(&c, CALIBRATION_PHASE, "-12.5") == 0 && c.phase_deg == -12.5f);
	CHECK(calibration_set_text(&c, CALIBRATION_PHASE, "180.5") == -EINVAL && c.phase_deg == -12.5f);
	CHECK(calibration_set_text(&c, CALIBRATION_PHASE, "nan") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_PHASE, "1x") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_PHASE, "") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_AXIS_U, "-7") == 0 && c.axis_u == -7);
	CHECK(calibration_set_text(&c, CALIBRATION_AXIS_U, "2.5") == -EINVAL && c.axis_u == -7);
	CHECK(calibration_set_text(&c, CALIBRATION_AXIS_V, "4097") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_AXIS_V, "3") == 0 && c.axis_v == 3);
	CHECK(calibration_set_text(&c, CALIBRATION_VERTICAL_SCALE, "0.49") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_VERTICAL_SCALE, "inf") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_VERTICAL_SCALE, "1.25") == 0);
	CHECK(calibration_set_text(&c, CALIBRATION_VERTICAL_OFFSET, "0.51") == -EINVAL);
	CHECK(calibration_set_text(&c, CALIBRATION_VERTICAL_OFFSET, "-0.125") == 0 && c.vertical_offset == -0.125f);
	CHECK(calibration_set(&c, 9, 0) == -EINVAL);
	char text[32];
	calibration_format(&c, CALIBRATION_PHASE, text, sizeof(text));
	CHECK(!strcmp(text, "-12.5"));
	calibration_format(&c, CALIBRATION_AXIS_U, text, sizeof(text));
	CHECK(!strcmp(text, "-7"));
	calibration_format(&c, CALIBRATION_VERTICAL_SCALE, text, sizeof(text));
	CHECK(!strcmp(text, "1.25"));
	CHECK(calibration_has_transform(&c));
	/* A quarter of the image at most. */
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	c.axis_u = 32, c.axis_v = -32;
	CHECK(calibration_check(&c, &g) == 0);
	c.axis_u = 33;
	CHECK(calibration_check(&c, &g) == -EINVAL);
}

/* The point at azimuth phi + phase goes to azimuth phi; y is scaled. */
static void test_transform(void)
{
	struct calibration c;
	calibration_identity(&c);
	c.phase_deg = 30.0f;
	c.vertical_scale = 0.8f;
	c.vertical_offset = 0.1f;
	float m[16];
	calibration_transform(&c, m);
	double a = (10.0 + 30.0) * M_PI / 180.0, r = 0.7, y = 0.5;
	double p[4] = { r * cos(a), y, r * sin(a), 1 }, q[3] = { 0 };
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 4; j++)
			q[i] += m[j * 4 + i] * p[j];
	CHECK(fabs(atan2(q[2], q[0]) - 10.0 * M_PI / 180.0) < 1e-6);
	CHECK(fabs(hypot(q[0], q[2]) - r) < 1e-6);
	CHECK(fabs(q[1] - (0.8 * y + 0.1)) < 1e-6);
	CHECK(m[15] == 1.0f && m[12] == 0.0f && m[14] == 0.0f && m[3] == 0.0f && m[7] == 0.0f && m[11] == 0.0f);
	/* The offset alone is a transform too. */
	calibration_identity(&c);
	c.vertical_offset = 0.1f;
	CHECK(calibration_has_transform(&c));
}

static uint32_t rng = 12345;
static uint32_t next(void)
{
	rng = rng * 1664525u + 1013904223u;
	return rng >> 8;
}

/* Image k of v anew, random: tiles empty, of sparse pixels or full; with
 * few, one tile in 16 stored, else three in four. */
static void fill_image(struct volume *v, uint32_t k, bool few)
{
	const struct geometry *g = &v->geom;
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_image_clear(v, k);
	for (uint32_t t = 0; t < volume_tiles_per_image(v); t++) {
		uint32_t kind = few ? (next() % 16 ? 0 : 1 + next() % 3) : next() % 4; /* empty, sparse, sparse, full */
		for (int i = 0; i < VOLUME_TILE_BYTES; i++)
			tile[i] = kind == 0 ? 0 : kind == 3 ? 0xff : (uint8_t)(next() % 7 == 0 ? next() : 0);
		/* Keep the padding past W and H dark. */
		uint32_t tx = t % v->tiles_x, ty = t / v->tiles_x;
		for (int c = 0; c < 3; c++)
			for (uint32_t j = 0; j < VOLUME_TILE; j++)
				for (uint32_t i = 0; i < VOLUME_TILE; i++)
					if (tx * VOLUME_TILE + i >= g->width || ty * VOLUME_TILE + j >= g->height)
						tile[c * VOLUME_TILE_PLANE_BYTES + j * 4 + i / 8] &=
							(uint8_t) ~(0x80u >> (i % 8));
		CHECK(volume_image_append(v, k, t, tile) == 0);
	}
}

static struct volume *random_volume(const struct geometry *g, bool few)
{
	struct volume *v = volume_create(g);
	CHECK(v != NULL);
	for (uint32_t k = 0; k < v->image_count; k++)
		fill_image(v, k, few);
	return v;
}

/* Image k of dst is image k of src moved by (du, dv), pixel by pixel. */
static void check_image_shifted(const struct volume *dst, const struct volume *src, uint32_t k, int du, int dv)
{
	const struct geometry *g = &src->geom;
	for (uint32_t v = 0; v < g->height; v++)
		for (uint32_t u = 0; u < g->width; u++)
			for (int c = 0; c < 3; c++) {
				int64_t su = (int64_t)u - du, sv = (int64_t)v - dv;
				int want = su >= 0 && sv >= 0 && su < g->width && sv < g->height
						   ? volume_pixel(src, k, (uint32_t)su, (uint32_t)sv, c)
						   : 0;
				CHECK_MSG(volume_pixel(dst, k, u, v, c) == want, "shift %d,%d image %u (%u,%u)", du, dv,
					  k, u, v);
			}
	/* Only tiles with something lit are stored; the padding stays dark. */
	const struct volume_image *img = &dst->images[k];
	for (uint32_t i = 0; i < img->tile_count; i++) {
		bool any = false;
		for (int b = 0; b < VOLUME_TILE_BYTES; b++)
			any |= img->tiles[(size_t)i * VOLUME_TILE_BYTES + b] != 0;
		CHECK(any);
	}
}

typedef int (*shift_fn)(struct volume *dst, const struct volume *src, int32_t du, int32_t dv);

static void check_shift_with(shift_fn shift, const struct geometry *g, int du, int dv, bool few)
{
	struct volume *src = random_volume(g, few), *dst = volume_create(g);
	src->seq = 77;
	CHECK(shift(dst, src, du, dv) == 0);
	CHECK_EQ(dst->seq, 77);
	for (uint32_t k = 0; k < src->image_count; k++)
		check_image_shifted(dst, src, k, du, dv);
	volume_destroy(src);
	volume_destroy(dst);
}

/* volume_shift() (AVX2 where the CPU has it) and the scalar one. */
static void check_shift(const struct geometry *g, int du, int dv)
{
	check_shift_with(volume_shift, g, du, dv, false);
	check_shift_with(volume_shift_scalar, g, du, dv, false);
	/* A few tiles each, so that a result tile no stored one reaches
	 * would be missed (the shift makes only those some tile reaches). */
	check_shift_with(volume_shift, g, du, dv, true);
}

static void test_shift(void)
{
	/* 100 x 72: partial edge tiles, W not a multiple of 8. */
	struct geometry g = { .width = 100, .height = 72, .images_per_rev = 6, .half_height = 1, .rpm = 600 };
	static const int offsets[][2] = { { 0, 0 },    { 1, 0 },   { 0, 1 },    { -1, -1 },   { 5, -3 },
					  { -13, 17 }, { 31, 0 },  { 32, -32 }, { -33, 33 },  { 64, 7 },
					  { -99, 71 }, { 100, 0 }, { 0, -72 },  { 250, -300 } };
	for (size_t i = 0; i < sizeof(offsets) / sizeof(offsets[0]); i++)
		check_shift(&g, offsets[i][0], offsets[i][1]);
	struct geometry small;
	CHECK(geometry_from_profile("small", &small) == 0);
	small.images_per_rev = 8;
	check_shift(&small, 3, -2);
	/* Different sizes, or in place: refused. */
	struct volume *a = volume_create(&g), *b = volume_create(&small);
	CHECK(volume_shift(a, b, 1, 1) == -EINVAL);
	CHECK(volume_shift(a, a, 1, 1) == -EINVAL);
	volume_destroy(a);
	volume_destroy(b);
}

int main(void)
{
	test_keys();
	test_transform();
	test_shift();
	return check_done();
}
