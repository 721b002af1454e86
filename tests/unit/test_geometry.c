/* common/geometry: profiles, validation and the docs/design.md section 3
 * formulas (columns, rows, ownership of azimuths), edges and clamping. */
#include <errno.h>
#include <math.h>

#include "check.h"
#include "geometry.h"

static void check_profiles(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("perspecta", &g) == 0);
	CHECK(g.width == 768 && g.height == 768 && g.images_per_rev == 396 && g.mirrored);
	CHECK(g.half_height == 1.0f && g.rpm == 730.0f);
	CHECK(geometry_images_per_volume(&g) == 198);
	CHECK(geometry_row_bytes(&g) == 96);
	CHECK(geometry_validate(&g) == 0);
	CHECK(geometry_from_profile("small", &g) == 0);
	CHECK(g.width == 128 && g.height == 128 && g.images_per_rev == 128 && g.mirrored);
	CHECK(geometry_images_per_volume(&g) == 64);
	CHECK(geometry_from_profile("nope", &g) == -ENOENT);
}

static void check_validate(void)
{
	struct geometry ok = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT }, g;
	CHECK(geometry_validate(&ok) == 0);
	CHECK(geometry_images_per_volume(&ok) == 50);
	CHECK(geometry_row_bytes(&ok) == 13);
	g = ok, g.width = 7;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.height = 9000;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.images_per_rev = 51, g.mirrored = true;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.images_per_rev = 3;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.half_height = NAN;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.half_height = 0;
	CHECK(geometry_validate(&g) == -EINVAL);
	g = ok, g.rpm = 0;
	CHECK(geometry_validate(&g) == -EINVAL);
}

static void check_columns_rows(void)
{
	struct geometry g = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	CHECK(geometry_column(&g, -1.0) == 0);
	CHECK(geometry_column(&g, 0.0) == 50);
	CHECK(geometry_column(&g, -1e-12) == 49);
	CHECK(geometry_column(&g, 1.0) == 99); /* clamped */
	CHECK(geometry_column(&g, 5.0) == 99);
	CHECK(geometry_column(&g, -5.0) == 0);
	CHECK(geometry_column(&g, NAN) == 0);
	CHECK(geometry_column(&g, 1e300) == 99);
	for (uint32_t u = 0; u < g.width; u++)
		CHECK(geometry_column(&g, -1.0 + (u + 0.5) * 2.0 / g.width) == u);
	CHECK(geometry_row(&g, 0.75) == 0);
	CHECK(geometry_row(&g, 0.0) == 36);
	CHECK(geometry_row(&g, 1e-12) == 35);
	CHECK(geometry_row(&g, -0.75) == 71); /* clamped */
	CHECK(geometry_row(&g, 9.0) == 0);
	CHECK(geometry_row(&g, -9.0) == 71);
	for (uint32_t v = 0; v < g.height; v++)
		CHECK(geometry_row(&g, 0.75 - (v + 0.5) * 1.5 / g.height) == v);
}

static void check_azimuths(void)
{
	struct geometry g = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	double d = 2 * M_PI / 50;
	CHECK(geometry_image_angle(&g, 0) == 0.0);
	CHECK(fabs(geometry_image_angle(&g, 25) - M_PI) < 1e-12);
	CHECK(geometry_image_of_azimuth(&g, 0.0) == 0);
	CHECK(geometry_image_of_azimuth(&g, 3.2 * d) == 3);
	CHECK(geometry_image_of_azimuth(&g, 3.7 * d) == 4);
	CHECK(geometry_image_of_azimuth(&g, -0.7 * d) == 49);
	CHECK(geometry_image_of_azimuth(&g, M_PI) == 25);
	CHECK(geometry_image_of_azimuth(&g, 2 * M_PI - 0.1 * d) == 0);
	CHECK(geometry_image_of_azimuth_back(&g, M_PI) == 0);
	CHECK(geometry_image_of_azimuth_back(&g, 0.0) == 25);
	CHECK(geometry_image_of_azimuth_back(&g, 3.2 * d) == 28);
	CHECK(geometry_image_of_azimuth_back(&g, -M_PI / 2) == 12 ||
	      geometry_image_of_azimuth_back(&g, -M_PI / 2) == 13);
	/* Every azimuth has its two lobes half a turn apart (N even). */
	for (int i = 0; i < 1000; i++) {
		double phi = -M_PI + 2 * M_PI * (i + 0.37) / 1000;
		uint32_t a = geometry_image_of_azimuth(&g, phi), b = geometry_image_of_azimuth_back(&g, phi);
		CHECK(a < 50 && b < 50 && (a + 25) % 50 == b);
	}
}

int main(void)
{
	check_profiles();
	check_validate();
	check_columns_rows();
	check_azimuths();
	return check_done();
}
