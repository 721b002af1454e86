/* Preview of synthetic volumes on the small profile.
 *
 * Rings: a white ring at y = 0 and a red ring at y = 0.5. The PNG must
 * decode, have the asked size, a dark background, and light where the rings
 * project.
 *
 * Disks: every voxel carries the same light, spread over its world cell (a
 * wedge r * D deep at radius r), with no weight for its radius. A horizontal
 * disk lit as exact rendering lights it (one voxel per image per column)
 * crowds its voxels near the axis, light per area r0 / r with r0 = 1 / D
 * pixels, and must preview brighter near the axis than further out, as it
 * glows on the display; a disk whose columns within r0 of the axis are lit
 * in only a fraction r * D of the images (what even brightness aims at) has
 * one voxel per pixel of area there and must preview about equally bright
 * at the axis, near it and just inside r0. (Beyond r0 every image lights
 * every column in both, and the light falls as r0 / r in both.) argv[1]: output PNG (the rings;
 * the disks' pictures go next to it). */
#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
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

/* A horizontal disk of radius 0.9 at y = 0. even: columns within r0 of the
 * axis lit in a fraction r * D of the images, spread evenly over them (each
 * column with its own phase, so the lit images do not line up). */
static struct volume *make_disk(bool even)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	struct testvol *tv = testvol_create(&g);
	uint32_t v = geometry_row(&g, 0.0);
	double step = 2.0 * M_PI / g.images_per_rev;
	for (uint32_t u = 0; u < g.width; u++) {
		double r_px = fabs(u + 0.5 - 0.5 * g.width);
		if (r_px > 0.9 * 0.5 * g.width)
			continue;
		double f = even ? fmin(1.0, r_px * step) : 1.0, phase = fmod(u * 0.6180339887, 1.0);
		for (uint32_t k = 0; k < tv->images; k++) {
			if (floor((k + 1) * f + phase) != floor(k * f + phase))
				testvol_set(tv, k, u, v, 7);
		}
	}
	struct volume *vol = testvol_to_volume(tv);
	testvol_destroy(tv);
	return vol;
}

/* The light behind a picture value of channel 1 (green), up to the tone
 * map's gain: v = bg + (255 - bg) (1 - e^(-gain L)) (preview.h), with
 * bg = 6 without the outline; saturation reads as 254.5. */
static double light_of(uint8_t v)
{
	double x = fmin((v - 6.0) / 249.0, 248.5 / 249.0);
	return x > 0.0 ? -log(1.0 - x) : 0.0;
}

/* Mean light (light_of) over the 5x5 pixels about where p projects. */
static double light_at(const uint8_t *rgb, const struct preview_options *opt, double x, double z)
{
	double p[3] = { x, 0.0, z }, px, py, sum = 0.0;
	CHECK(preview_project(opt, 1.0, p, &px, &py) == 0);
	for (int dy = -2; dy <= 2; dy++) {
		for (int dx = -2; dx <= 2; dx++) {
			int ix = (int)px + dx, iy = (int)py + dy;
			CHECK(ix >= 0 && iy >= 0 && ix < (int)opt->width && iy < (int)opt->height);
			sum += light_of(rgb[3 * ((size_t)iy * opt->width + ix) + 1]);
		}
	}
	return sum / 25.0;
}

/* Light at the axis, near it (radius 0.1: 6.4 pixels of an image) and just
 * inside r0 (radius 0.28: 17.9 pixels; r0 is 20.4), the latter two averaged
 * over the points left and right of the axis as seen: at the same distance
 * from the eye as the axis, nearly, so the inverse square law plays no
 * part. */
static void disk_light(const char *png, bool even, double *axis, double *near, double *far)
{
	struct volume *vol = make_disk(even);
	struct preview_options opt;
	preview_default_options(&opt);
	opt.width = opt.height = SIZE;
	opt.outline = false;
	CHECK(preview_volume_to_png(vol, &opt, png) == 0);
	uint32_t w, h;
	uint8_t *rgb = read_png(png, &w, &h);
	CHECK(w == SIZE && h == SIZE);
	*axis = light_at(rgb, &opt, 0.0, 0.0);
	*near = 0.5 * (light_at(rgb, &opt, -0.1, 0.0) + light_at(rgb, &opt, 0.1, 0.0));
	*far = 0.5 * (light_at(rgb, &opt, -0.28, 0.0) + light_at(rgb, &opt, 0.28, 0.0));
	printf("%s disk -> %s: light at the axis %.3f, at r 0.1 %.3f, at r 0.28 %.3f\n", even ? "even" : "exact", png,
	       *axis, *near, *far);
	free(rgb);
	volume_destroy(vol);
}

static void check_disks(const char *rings_png)
{
	char png[4096];
	const char *slash = strrchr(rings_png, '/');
	int dir_len = slash ? (int)(slash - rings_png + 1) : 0;
	double axis, near, far;

	snprintf(png, sizeof(png), "%.*spreview-disk-exact.png", dir_len, rings_png);
	disk_light(png, false, &axis, &near, &far);
	/* 1/r: 2.8 times brighter at 0.1 than at 0.28 (a weight |s| would make
	 * them equal; the tone map's saturation can take a little off), at
	 * least as bright at the axis, and the rest not black */
	CHECK(far > 0.3);
	CHECK(near > 2.0 * far);
	CHECK(axis > 2.0 * far);

	snprintf(png, sizeof(png), "%.*spreview-disk-even.png", dir_len, rings_png);
	disk_light(png, true, &axis, &near, &far);
	CHECK(far > 0.3);
	CHECK(fabs(near / far - 1.0) < 0.3);
	CHECK(fabs(axis / far - 1.0) < 0.3);
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

/* Progress lines: none for a quick picture by default; with the first
 * line due at once, the drawing's lines, then how long it took in all. */
static void check_progress(const struct volume *vol, const char *png)
{
	struct preview_options opt;
	preview_default_options(&opt);
	opt.width = opt.height = SIZE;
	char *text = NULL;
	size_t len = 0;
	FILE *f = open_memstream(&text, &len);
	CHECK(f != NULL);
	opt.progress = f;
	opt.progress_name = "x.png";
	CHECK(preview_volume_to_png(vol, &opt, png) == 0);
	fflush(f);
	if (len)
		fprintf(stderr, "a quick preview said: %s", text);
	CHECK(len == 0);
	opt.progress_after = 0.0;
	CHECK(preview_volume_to_png(vol, &opt, png) == 0);
	fclose(f);
	fprintf(stderr, "%s", text);
	CHECK(strstr(text, "x.png: drawing, image 1 of ") && strstr(text, "x.png: drawn in ") &&
	      strstr(text, "x.png: written, "));
	free(text);
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

	check_disks(argv[1]);
	check_progress(vol, argv[1]);

	/* bad options are refused */
	opt.distance = 1.0;
	CHECK(preview_render(vol, &opt, rgb) == -EINVAL);
	free(rgb);
	volume_destroy(vol);
	return 0;
}
