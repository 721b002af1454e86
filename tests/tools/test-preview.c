/* Preview of a synthetic volume: a white ring at y = 0 and a red ring at
 * y = 0.5 on the small profile. The PNG must decode, have the asked size, a
 * dark background, and light where the rings project. argv[1]: output PNG. */
#include <errno.h>
#include <math.h>
#include <png.h>
#include <string.h>

#include "preview.h"
#include "testvol.h"

#define SIZE 320

static struct volume *make_rings(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	struct testvol *tv = testvol_create(&g);
	for (int i = 0; i < 4000; i++) {
		double a = 2.0 * M_PI * i / 4000;
		double white[3] = { 0.6 * cos(a), 0.0, 0.6 * sin(a) };
		double red[3] = { 0.6 * cos(a), 0.5, 0.6 * sin(a) };
		testvol_light_point(tv, white, 7);
		testvol_light_point(tv, red, 1);
	}
	struct volume *vol = testvol_to_volume(tv);
	testvol_destroy(tv);
	return vol;
}

static uint8_t *read_png(const char *path, uint32_t *w, uint32_t *h)
{
	png_image img;
	memset(&img, 0, sizeof(img));
	img.version = PNG_IMAGE_VERSION;
	CHECK(png_image_begin_read_from_file(&img, path));
	img.format = PNG_FORMAT_RGB;
	uint8_t *buf = malloc(PNG_IMAGE_SIZE(img));
	CHECK(buf);
	CHECK(png_image_finish_read(&img, NULL, buf, 0, NULL));
	*w = img.width;
	*h = img.height;
	return buf;
}

/* Brightest value of channel c within 2 pixels of (x, y). */
static int peak(const uint8_t *rgb, uint32_t w, uint32_t h, double x, double y, int c)
{
	int best = 0;
	for (int dy = -2; dy <= 2; dy++) {
		for (int dx = -2; dx <= 2; dx++) {
			int px = (int)x + dx, py = (int)y + dy;
			if (px >= 0 && py >= 0 && px < (int)w && py < (int)h)
				best = rgb[3 * ((size_t)py * w + px) + c] > best ? rgb[3 * ((size_t)py * w + px) + c]
										 : best;
		}
	}
	return best;
}

static void check_ring(const uint8_t *rgb, const struct preview_options *opt, double y, int c, int other)
{
	for (int i = 0; i < 8; i++) {
		double a = 2.0 * M_PI * (i + 0.5) / 8, p[3] = { 0.6 * cos(a), y, 0.6 * sin(a) }, px, py;
		CHECK(preview_project(opt, 1.0, p, &px, &py) == 0);
		int lit = peak(rgb, opt->width, opt->height, px, py, c);
		printf("ring y=%.1f angle %3.0f at (%5.1f, %5.1f): %d\n", y, a * 180 / M_PI, px, py, lit);
		CHECK(lit > 120);
		if (other >= 0) /* the red ring has no green */
			CHECK(peak(rgb, opt->width, opt->height, px, py, other) < lit / 2);
	}
}

int main(int argc, char **argv)
{
	CHECK(argc == 2);
	struct volume *vol = make_rings();
	struct preview_options opt;
	preview_default_options(&opt);
	opt.width = opt.height = SIZE;
	opt.outline = false;
	CHECK(preview_volume_to_png(vol, &opt, argv[1]) == 0);

	uint32_t w, h;
	uint8_t *rgb = read_png(argv[1], &w, &h);
	CHECK(w == SIZE && h == SIZE);
	/* corners and the centre (the axis at y = 0, inside the ring) are dark */
	double origin[3] = { 0, 0, 0 }, cx, cy;
	CHECK(preview_project(&opt, 1.0, origin, &cx, &cy) == 0);
	for (int c = 0; c < 3; c++) {
		CHECK(rgb[c] < 16 && rgb[3 * (SIZE - 1) + c] < 16);
		CHECK(rgb[3 * ((size_t)SIZE * SIZE - 1) + c] < 16);
		CHECK(peak(rgb, w, h, cx, cy, c) < 16);
	}
	check_ring(rgb, &opt, 0.0, 1, -1);
	check_ring(rgb, &opt, 0.5, 0, 1);

	/* bad options are refused */
	opt.distance = 1.0;
	CHECK(preview_render(vol, &opt, rgb) == -EINVAL);
	free(rgb);
	volume_destroy(vol);
	return 0;
}
