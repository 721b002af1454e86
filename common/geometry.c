#include "geometry.h"

#include <errno.h>
#include <math.h>
#include <string.h>

static const struct {
	const char *name;
	struct geometry geom;
} profiles[] = {
	/* Actuality Perspecta: 198 images of 768x768 per half turn, 730 rpm. */
	{ "perspecta", { 768, 768, 396, true, 1.0f, 730.0f, GEOMETRY_BRIGHTNESS_EXACT } },
	/* Small and quick, for tests. */
	{ "small", { 128, 128, 128, true, 1.0f, 1800.0f, GEOMETRY_BRIGHTNESS_EXACT } },
};

int geometry_from_profile(const char *name, struct geometry *out)
{
	for (size_t i = 0; i < sizeof(profiles) / sizeof(profiles[0]); i++) {
		if (strcmp(profiles[i].name, name) == 0) {
			*out = profiles[i].geom;
			return 0;
		}
	}
	return -ENOENT;
}

int geometry_validate(const struct geometry *g)
{
	if (g->width < 8 || g->width > 8192 || g->height < 8 || g->height > 8192)
		return -EINVAL;
	if (g->images_per_rev < 4 || g->images_per_rev > 16384)
		return -EINVAL;
	if (g->mirrored && g->images_per_rev % 2 != 0)
		return -EINVAL;
	if (!(g->half_height > 0.01f && g->half_height < 100.0f))
		return -EINVAL;
	if (!(g->rpm > 1.0f && g->rpm < 100000.0f))
		return -EINVAL;
	if (!geometry_brightness_name(g->brightness))
		return -EINVAL;
	return 0;
}

static const char *const brightness_names[] = { "exact", "even", "uniform" };

const char *geometry_brightness_name(unsigned brightness)
{
	return brightness < sizeof(brightness_names) / sizeof(brightness_names[0])
		       ? brightness_names[brightness]
		       : NULL;
}

int geometry_brightness_parse(const char *name, uint8_t *out)
{
	for (unsigned i = 0; i < sizeof(brightness_names) / sizeof(brightness_names[0]); i++) {
		if (!strcmp(name, brightness_names[i])) {
			*out = (uint8_t)i;
			return 0;
		}
	}
	return -EINVAL;
}

double geometry_r0_px(const struct geometry *g)
{
	return g->images_per_rev / (2.0 * M_PI);
}

uint32_t geometry_turn_source(const struct geometry *g, uint32_t k, uint32_t t, bool *mirror)
{
	uint32_t m = geometry_images_per_volume(g);
	uint32_t j = k >= t ? k - t : k + g->images_per_rev - t;
	*mirror = j >= m; /* never unmirrored: M = N */
	return *mirror ? j - m : j;
}

uint32_t geometry_images_per_volume(const struct geometry *g)
{
	return g->mirrored ? g->images_per_rev / 2 : g->images_per_rev;
}

double geometry_image_angle(const struct geometry *g, uint32_t k)
{
	return 2.0 * M_PI * (double)k / (double)g->images_per_rev;
}

static uint32_t wrap_image(double idx, uint32_t n)
{
	long long k = llround(idx) % (long long)n;
	return (uint32_t)(k < 0 ? k + n : k);
}

uint32_t geometry_image_of_azimuth(const struct geometry *g, double phi)
{
	double d = 2.0 * M_PI / g->images_per_rev;
	return wrap_image(phi / d, g->images_per_rev);
}

uint32_t geometry_image_of_azimuth_back(const struct geometry *g, double phi)
{
	double d = 2.0 * M_PI / g->images_per_rev;
	return wrap_image((phi - M_PI) / d, g->images_per_rev);
}
