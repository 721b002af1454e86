#include "preview.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PREVIEW_MAX_SIZE 16384
/* Arc samples per voxel at most: enough to smear a rim voxel of a coarse
 * profile into a continuous arc without costing much on fine ones. */
#define PREVIEW_MAX_ARC_SAMPLES 16

static const float background[3] = { 6.0f, 6.0f, 10.0f };
static const float outline_rgb[3] = { 46.0f, 50.0f, 64.0f };

/* Pinhole camera looking at the origin; cam = (p - eye) in the basis
 * right/up/fwd, pixel = centre + focal * (x, -y) / depth. */
struct camera {
	double eye[3], right[3], up[3], fwd[3];
	double focal, cx, cy;
};

/* Float accumulators for the light (RGB) and the outline (coverage). */
struct canvas {
	uint32_t w, h;
	float *light;
	float *outline;
};

void preview_default_options(struct preview_options *opt)
{
	*opt = (struct preview_options){
		.width = 640,
		.height = 640,
		.distance = 3.2,
		.elevation_deg = 20.0,
		.azimuth_deg = 90.0,
		.outline = true,
		.progress_after = 1.0,
	};
}

static double dot3(const double a[3], const double b[3])
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
	out[0] = a[1] * b[2] - a[2] * b[1];
	out[1] = a[2] * b[0] - a[0] * b[2];
	out[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize3(double v[3])
{
	double n = sqrt(dot3(v, v));
	for (int i = 0; i < 3; i++)
		v[i] /= n;
}

/* Camera coordinates of p: x right, y up, z depth (> 0 in front). */
static void camera_coords(const struct camera *cam, const double p[3], double out[3])
{
	double q[3] = { p[0] - cam->eye[0], p[1] - cam->eye[1], p[2] - cam->eye[2] };
	out[0] = dot3(q, cam->right);
	out[1] = dot3(q, cam->up);
	out[2] = dot3(q, cam->fwd);
}

static void camera_orient(struct camera *cam, const struct preview_options *opt)
{
	double el = opt->elevation_deg * M_PI / 180.0, az = opt->azimuth_deg * M_PI / 180.0;
	const double world_up[3] = { 0.0, 1.0, 0.0 };

	cam->eye[0] = opt->distance * cos(el) * cos(az);
	cam->eye[1] = opt->distance * sin(el);
	cam->eye[2] = opt->distance * cos(el) * sin(az);
	for (int i = 0; i < 3; i++)
		cam->fwd[i] = -cam->eye[i];
	normalize3(cam->fwd);
	cross3(cam->fwd, world_up, cam->right);
	normalize3(cam->right);
	cross3(cam->right, cam->fwd, cam->up);
}

/* Frames the display cylinder: the bounding box of its projected rims
 * (its silhouette lies within them) fills 96% of the picture. */
static void camera_frame(struct camera *cam, const struct preview_options *opt, double h)
{
	double lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };

	for (int i = 0; i < 720; i++) {
		double a = 2.0 * M_PI * i / 720.0;
		for (int top = 0; top < 2; top++) {
			double p[3] = { cos(a), top ? h : -h, sin(a) }, c[3];
			camera_coords(cam, p, c);
			double x = c[0] / c[2], y = c[1] / c[2];
			lo[0] = fmin(lo[0], x), hi[0] = fmax(hi[0], x);
			lo[1] = fmin(lo[1], y), hi[1] = fmax(hi[1], y);
		}
	}
	double fx = opt->width / (hi[0] - lo[0]), fy = opt->height / (hi[1] - lo[1]);
	cam->focal = 0.96 * fmin(fx, fy);
	cam->cx = 0.5 * opt->width - cam->focal * 0.5 * (lo[0] + hi[0]);
	cam->cy = 0.5 * opt->height + cam->focal * 0.5 * (lo[1] + hi[1]);
}

/* Adds weight * rgb at (x, y) with a tent filter of radius r >= 1 pixels,
 * so sparse voxels of coarse profiles join up instead of showing as dots. */
static void splat(struct canvas *cv, double x, double y, double r, const float *rgb, float *dst_base, int channels)
{
	x -= 0.5; /* pixel i covers [i, i + 1): its centre is at i + 0.5 */
	y -= 0.5;
	int x0 = (int)ceil(x - r), x1 = (int)floor(x + r);
	int y0 = (int)ceil(y - r), y1 = (int)floor(y + r);
	double norm = 1.0 / (r * r);

	if (x1 < 0 || y1 < 0 || x0 >= (int)cv->w || y0 >= (int)cv->h)
		return;
	for (int py = y0 > 0 ? y0 : 0; py <= y1 && py < (int)cv->h; py++) {
		double wy = 1.0 - fabs(py - y) / r;
		for (int px = x0 > 0 ? x0 : 0; px <= x1 && px < (int)cv->w; px++) {
			double wgt = wy * (1.0 - fabs(px - x) / r) * norm;
			if (wgt <= 0.0)
				continue;
			float *d = dst_base + ((size_t)py * cv->w + px) * channels;
			for (int c = 0; c < channels; c++)
				d[c] += (float)(wgt * rgb[c]);
		}
	}
}

/* Per stored image: the camera-space images of the arc directions the
 * screen sweeps while that image is lit, so a voxel costs a few mul-adds. */
struct arc_table {
	int samples;
	double *dir; /* per image, per sample: camera x, y, z of (cos a, 0, sin a) */
};

static int arc_table_init(struct arc_table *at, const struct volume *vol, const struct camera *cam,
			  const struct preview_options *opt)
{
	double step = 2.0 * M_PI / vol->geom.images_per_rev;
	/* The rim voxel's arc, in pixels, seen from the nearest rim point. */
	double arc_px = cam->focal * step / (opt->distance - 1.0);
	at->samples = (int)fmin(PREVIEW_MAX_ARC_SAMPLES, fmax(1.0, ceil(arc_px)));
	at->dir = malloc(sizeof(double) * 3 * at->samples * vol->image_count);
	if (!at->dir)
		return -ENOMEM;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		for (int j = 0; j < at->samples; j++) {
			double a = geometry_image_angle(&vol->geom, k) + step * ((j + 0.5) / at->samples - 0.5);
			double d[3] = { cos(a), 0.0, sin(a) };
			double *out = &at->dir[3 * ((size_t)k * at->samples + j)];
			out[0] = dot3(d, cam->right);
			out[1] = dot3(d, cam->up);
			out[2] = dot3(d, cam->fwd);
		}
	}
	return 0;
}

/* Everything that is fixed while drawing the voxels of one volume. */
struct voxel_painter {
	const struct volume *vol;
	const struct camera *cam;
	struct arc_table arcs;
	struct canvas *cv;
	double eye_cam[3]; /* -eye in camera coordinates */
	double y_cam[3];   /* (0, 1, 0) in camera coordinates */
	double radius_px;  /* splat radius */
	double d0_sq;      /* squared eye distance from the centre */
};

/* One voxel: the same light for every voxel, wherever it is (no weight for
 * its radius: near the axis voxels crowd, and the picture shows the glow the
 * display shows), spread evenly over the arc its image sweeps at its radius
 * |s| and splatted over its pixel's extent, each share dimmed by the inverse
 * square of its distance from the eye (preview.h). */
static void paint_voxel(struct voxel_painter *vp, uint32_t k, uint32_t u, uint32_t v, unsigned bits)
{
	const struct geometry *g = &vp->vol->geom;
	double s = ((u + 0.5) / g->width) * 2.0 - 1.0;
	double y = g->half_height - (v + 0.5) / g->height * 2.0 * g->half_height;
	double share = vp->d0_sq / vp->arcs.samples;
	float rgb[3];

	const double *dir = &vp->arcs.dir[3 * (size_t)k * vp->arcs.samples];
	for (int j = 0; j < vp->arcs.samples; j++, dir += 3) {
		double cx = s * dir[0] + y * vp->y_cam[0] + vp->eye_cam[0];
		double cy = s * dir[1] + y * vp->y_cam[1] + vp->eye_cam[1];
		double cz = s * dir[2] + y * vp->y_cam[2] + vp->eye_cam[2];
		if (cz <= 1e-6)
			continue;
		/* inverse square law, 1 at the display's centre */
		float w = (float)(share / (cx * cx + cy * cy + cz * cz));
		for (int c = 0; c < 3; c++)
			rgb[c] = (bits >> c) & 1 ? w : 0.0f;
		double px = vp->cam->cx + vp->cam->focal * cx / cz;
		double py = vp->cam->cy - vp->cam->focal * cy / cz;
		splat(vp->cv, px, py, vp->radius_px, rgb, vp->cv->light, 3);
	}
}

/* Visits the set pixels of one row of one tile (4 bytes per plane). */
static void paint_tile_row(struct voxel_painter *vp, uint32_t k, const uint8_t *tile, uint32_t row, uint32_t x0,
			   uint32_t v)
{
	for (uint32_t b = 0; b < VOLUME_TILE / 8; b++) {
		uint8_t p[3];
		for (int c = 0; c < 3; c++)
			p[c] = tile[c * VOLUME_TILE_PLANE_BYTES + row * 4 + b];
		uint8_t any = p[0] | p[1] | p[2];
		for (int bit = 0; any && bit < 8; bit++) {
			uint8_t m = (uint8_t)(0x80 >> bit);
			if (!(any & m))
				continue;
			unsigned bits = (p[0] & m ? 1u : 0u) | (p[1] & m ? 2u : 0u) | (p[2] & m ? 4u : 0u);
			uint32_t u = x0 + b * 8 + bit;
			if (u < vp->vol->geom.width)
				paint_voxel(vp, k, u, v, bits);
		}
	}
}

static void paint_image(struct voxel_painter *vp, uint32_t k)
{
	const struct volume *vol = vp->vol;
	const struct volume_image *img = &vol->images[k];
	const uint8_t *tile = img->tiles;

	for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
		if (!volume_tile_present(img, t))
			continue;
		uint32_t x0 = (t % vol->tiles_x) * VOLUME_TILE, y0 = (t / vol->tiles_x) * VOLUME_TILE;
		for (uint32_t r = 0; r < VOLUME_TILE && y0 + r < vol->geom.height; r++)
			paint_tile_row(vp, k, tile, r, x0, y0 + r);
		tile += VOLUME_TILE_BYTES;
	}
}

/* Progress lines for a long preview (preview_options.progress). */
struct progress {
	FILE *f;
	const char *name;
	double start, next; /* seconds, CLOCK_MONOTONIC */
	bool said;
};

static double seconds_now(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec / 1e9;
}

static void progress_start(struct progress *p, const struct preview_options *opt)
{
	*p = (struct progress){ .f = opt->progress, .name = opt->progress_name ? opt->progress_name : "preview" };
	if (p->f)
		p->next = (p->start = seconds_now()) + opt->progress_after;
}

static void progress_note(struct progress *p, uint32_t done, uint32_t total)
{
	if (!p->f)
		return;
	double now = seconds_now();
	if (now < p->next)
		return;
	fprintf(p->f, "%s: drawing, image %u of %u, %.0f s so far\n", p->name, done, total, now - p->start);
	fflush(p->f);
	p->said = true;
	p->next = now + 2.0;
}

static void progress_done(const struct progress *p)
{
	if (p->f && p->said) {
		fprintf(p->f, "%s: drawn in %.1f s\n", p->name, seconds_now() - p->start);
		fflush(p->f);
	}
}

static int paint_volume(struct canvas *cv, const struct volume *vol, const struct camera *cam,
			const struct preview_options *opt)
{
	struct voxel_painter vp = { .vol = vol, .cam = cam, .cv = cv };
	const double origin[3] = { 0.0, 0.0, 0.0 }, up[3] = { 0.0, 1.0, 0.0 };
	const struct geometry *g = &vol->geom;

	int ret = arc_table_init(&vp.arcs, vol, cam, opt);
	if (ret < 0)
		return ret;
	camera_coords(cam, origin, vp.eye_cam);
	vp.y_cam[0] = dot3(up, cam->right);
	vp.y_cam[1] = dot3(up, cam->up);
	vp.y_cam[2] = dot3(up, cam->fwd);
	/* Pixel pitch of columns and rows seen from the centre's distance. */
	double pitch = cam->focal / opt->distance * fmax(2.0 / g->width, 2.0 * g->half_height / g->height);
	vp.radius_px = fmax(1.0, pitch);
	vp.d0_sq = opt->distance * opt->distance;
	struct progress pr;
	progress_start(&pr, opt);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		paint_image(&vp, k);
		progress_note(&pr, k + 1, vol->image_count);
	}
	progress_done(&pr);
	free(vp.arcs.dir);
	return 0;
}

static void plot_outline_point(struct canvas *cv, const struct camera *cam, const double p[3])
{
	static const float one = 1.0f;
	double c[3];

	camera_coords(cam, p, c);
	if (c[2] <= 1e-6)
		return;
	splat(cv, cam->cx + cam->focal * c[0] / c[2], cam->cy - cam->focal * c[1] / c[2], 1.0, &one, cv->outline, 1);
}

/* Rims at y = +-h and the two vertical silhouette lines. */
static void paint_outline(struct canvas *cv, const struct camera *cam, const struct preview_options *opt, double h)
{
	int n = 4 * (int)(cv->w + cv->h);
	for (int i = 0; i < n; i++) {
		double a = 2.0 * M_PI * i / n;
		double top[3] = { cos(a), h, sin(a) }, bottom[3] = { cos(a), -h, sin(a) };
		plot_outline_point(cv, cam, top);
		plot_outline_point(cv, cam, bottom);
	}
	double ground = hypot(cam->eye[0], cam->eye[2]);
	if (ground <= 1.0)
		return; /* looking down the axis: no silhouette lines */
	double az = atan2(cam->eye[2], cam->eye[0]), off = acos(1.0 / ground);
	for (int side = -1; side <= 1; side += 2) {
		double a = az + side * off;
		for (int i = 0; i <= (int)cv->h * 2; i++) {
			double p[3] = { cos(a), -h + 2.0 * h * i / (cv->h * 2.0), sin(a) };
			plot_outline_point(cv, cam, p);
		}
	}
}

static int compare_float(const void *a, const void *b)
{
	float x = *(const float *)a, y = *(const float *)b;
	return (x > y) - (x < y);
}

/* The tone-map gain, from the brightness of the lit pixels: the 99th
 * percentile maps to 1 - e^-2 (86%), so sparse and dense volumes both show
 * well, and the median to at least 1 - e^-1 (63%), so a small hot spot (a
 * surface crossing the axis glows there, as on the display) cannot dim the
 * rest: the spot saturates instead, still brighter than its surroundings. */
static int exposure_gain(const struct canvas *cv, double *gain)
{
	size_t n = (size_t)cv->w * cv->h, lit = 0;
	float *vals = malloc(sizeof(float) * (n ? n : 1));

	if (!vals)
		return -ENOMEM;
	for (size_t i = 0; i < n; i++) {
		const float *p = &cv->light[3 * i];
		float m = fmaxf(p[0], fmaxf(p[1], p[2]));
		if (m > 0.0f)
			vals[lit++] = m;
	}
	*gain = 1.0;
	if (lit > 0) {
		qsort(vals, lit, sizeof(float), compare_float);
		*gain = fmax(2.0 / vals[(size_t)(0.99 * (lit - 1))], 1.0 / vals[(lit - 1) / 2]);
	}
	free(vals);
	return 0;
}

static int tone_map(const struct canvas *cv, uint8_t *rgb)
{
	double gain;
	int ret = exposure_gain(cv, &gain);
	if (ret < 0)
		return ret;
	for (size_t i = 0; i < (size_t)cv->w * cv->h; i++) {
		float o = cv->outline ? fminf(cv->outline[i], 1.0f) : 0.0f;
		for (int c = 0; c < 3; c++) {
			float light = (float)(1.0 - exp(-gain * cv->light[3 * i + c]));
			float base = fmaxf(background[c], o * outline_rgb[c]);
			float val = base + (255.0f - base) * light;
			rgb[3 * i + c] = (uint8_t)lrintf(fminf(val, 255.0f));
		}
	}
	return 0;
}

static int check_options(double h, const struct preview_options *opt)
{
	if (opt->width == 0 || opt->height == 0 || opt->width > PREVIEW_MAX_SIZE || opt->height > PREVIEW_MAX_SIZE)
		return -EINVAL;
	/* Outside the bounding sphere, every voxel is in front of the eye. */
	if (!(opt->distance > sqrt(1.0 + h * h)) || !isfinite(opt->distance))
		return -EINVAL;
	if (!(fabs(opt->elevation_deg) < 90.0) || !isfinite(opt->azimuth_deg))
		return -EINVAL;
	return 0;
}

int preview_render(const struct volume *vol, const struct preview_options *opt, uint8_t *rgb)
{
	struct camera cam;
	struct canvas cv = { .w = opt->width, .h = opt->height };
	size_t n = (size_t)opt->width * opt->height;
	int ret = check_options(vol->geom.half_height, opt);

	if (ret < 0)
		return ret;
	camera_orient(&cam, opt);
	camera_frame(&cam, opt, vol->geom.half_height);
	cv.light = calloc(3 * n, sizeof(float));
	cv.outline = opt->outline ? calloc(n, sizeof(float)) : NULL;
	if (!cv.light || (opt->outline && !cv.outline)) {
		ret = -ENOMEM;
		goto out_free;
	}
	if (opt->outline)
		paint_outline(&cv, &cam, opt, vol->geom.half_height);
	ret = paint_volume(&cv, vol, &cam, opt);
	if (ret == 0)
		ret = tone_map(&cv, rgb);
out_free:
	free(cv.light);
	free(cv.outline);
	return ret;
}

int preview_project(const struct preview_options *opt, double h, const double p[3], double *x, double *y)
{
	struct camera cam;
	double c[3];

	if (check_options(h, opt) < 0)
		return -EINVAL;
	camera_orient(&cam, opt);
	camera_frame(&cam, opt, h);
	camera_coords(&cam, p, c);
	if (c[2] <= 1e-6)
		return -EINVAL;
	*x = cam.cx + cam.focal * c[0] / c[2];
	*y = cam.cy - cam.focal * c[1] / c[2];
	return 0;
}

int preview_write_png(const char *path, const uint8_t *rgb, uint32_t width, uint32_t height)
{
	png_image img;
	memset(&img, 0, sizeof(img));
	img.version = PNG_IMAGE_VERSION;
	img.width = width;
	img.height = height;
	img.format = PNG_FORMAT_RGB;

	/* The simplified API reports errors in img.message instead of longjmp. */
	errno = 0;
	if (!png_image_write_to_file(&img, path, 0, rgb, 3 * (png_int_32)width, NULL))
		return errno ? -errno : -EIO;
	return 0;
}

int preview_volume_to_png(const struct volume *vol, const struct preview_options *opt, const char *path)
{
	struct preview_options defaults;
	if (!opt) {
		preview_default_options(&defaults);
		opt = &defaults;
	}
	uint8_t *rgb = malloc((size_t)opt->width * opt->height * 3 + 1);
	if (!rgb)
		return -ENOMEM;
	double start = seconds_now();
	int ret = preview_render(vol, opt, rgb);
	if (ret == 0)
		ret = preview_write_png(path, rgb, opt->width, opt->height);
	free(rgb);
	double took = seconds_now() - start;
	if (ret == 0 && opt->progress && took >= opt->progress_after) {
		fprintf(opt->progress, "%s: written, %.1f s in all\n",
			opt->progress_name ? opt->progress_name : "preview", took);
		fflush(opt->progress);
	}
	return ret;
}
