/* A visual check of the preview: light what a renderer would light for the
 * bunny's vertices (docs/design.md section 3 point ownership) at the small and the
 * perspecta profiles, and write previews to look at. The checks are coarse
 * (the bunny's picture is lit where it should be and nowhere near the
 * corners); the pictures are for a person.
 * argv[1]: tests/data, argv[2]: output folder. */
#include <math.h>
#include <string.h>

#include "model.h"
#include "preview.h"
#include "testvol.h"

static struct volume *bunny_volume(const struct model *m, const char *profile)
{
	struct geometry g;
	CHECK(geometry_from_profile(profile, &g) == 0);
	struct testvol *tv = testvol_create(&g);
	for (size_t i = 0; i < 3 * m->triangle_count; i++) {
		const float *v = &m->triangles[3 * i];
		double p[3] = { v[0], v[1], v[2] };
		testvol_light_point(tv, p, 7);
	}
	struct volume *vol = testvol_to_volume(tv);
	testvol_destroy(tv);
	return vol;
}

/* Lit pixels, and their bounding box, as a fraction of the picture. */
static void check_picture(const uint8_t *rgb, uint32_t size)
{
	size_t lit = 0;
	uint32_t x0 = size, x1 = 0, y0 = size, y1 = 0;
	for (uint32_t y = 0; y < size; y++) {
		for (uint32_t x = 0; x < size; x++) {
			if (rgb[3 * ((size_t)y * size + x) + 1] < 64)
				continue;
			lit++;
			x0 = x < x0 ? x : x0, x1 = x > x1 ? x : x1;
			y0 = y < y0 ? y : y0, y1 = y > y1 ? y : y1;
		}
	}
	printf("  lit pixels %zu, box x %u..%u y %u..%u\n", lit, x0, x1, y0, y1);
	CHECK(lit > (size_t)size * size / 200);
	CHECK(x1 - x0 > size / 3 && y1 - y0 > size / 3);
	CHECK(x0 > size / 50 && y0 > size / 50 && x1 < size - size / 50 && y1 < size - size / 50);
}

static void render(const struct model *m, const char *profile, const char *out_dir, double az)
{
	struct volume *vol = bunny_volume(m, profile);
	struct preview_options opt;
	char path[4096];
	preview_default_options(&opt);
	opt.azimuth_deg = az;
	snprintf(path, sizeof(path), "%s/preview-bunny-%s-az%03.0f.png", out_dir, profile, az);
	uint8_t *rgb = malloc((size_t)opt.width * opt.height * 3);
	CHECK(rgb);
	CHECK(preview_render(vol, &opt, rgb) == 0);
	CHECK(preview_write_png(path, rgb, opt.width, opt.height) == 0);
	printf("%s: %llu tiles -> %s\n", profile, (unsigned long long)volume_tile_count(vol), path);
	check_picture(rgb, opt.width);
	free(rgb);
	volume_destroy(vol);
}

int main(int argc, char **argv)
{
	char path[4096], err[512];
	CHECK(argc == 3);
	snprintf(path, sizeof(path), "%s/bunny.ply", argv[1]);
	struct model *m = model_load(path, err, sizeof(err));
	CHECK(m);
	struct model_fit fit;
	CHECK(model_compute_fit(m, 1.0f, 0.95f, &fit) == 0);
	model_apply_fit(m, &fit);

	render(m, "small", argv[2], 90.0);
	render(m, "perspecta", argv[2], 90.0);
	render(m, "perspecta", argv[2], 0.0);
	model_destroy(m);
	return 0;
}
