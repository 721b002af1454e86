/* The test patterns (patterns.h). Each is lines and triangles with their
 * own colours; radii stay inside 0.95 and heights inside 0.9 h so that
 * nothing is clamped at the cylinder's edge. */
#include "patterns.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char pattern_names[] = "axis, rings, grid-cube, colour-bars, walls, slice-index";

/* A model being built: lines and triangles grow as they are added. */
struct builder {
	struct model *m;
	size_t line_cap, line_colour_cap, tri_cap, tri_colour_cap; /* in segments, triangles */
	int err;
};

static void grow(void **p, size_t *cap, size_t need, size_t size)
{
	if (need <= *cap)
		return;
	size_t n = *cap ? *cap * 2 : 64;
	while (n < need)
		n *= 2;
	void *q = realloc(*p, n * size);
	if (q) {
		*p = q;
		*cap = n;
	}
}

static void line(struct builder *b, const float a[3], const float c[3], const uint8_t rgb[3])
{
	struct model *m = b->m;
	grow((void **)&m->lines, &b->line_cap, m->line_count + 1, 6 * sizeof(float));
	grow((void **)&m->line_colors, &b->line_colour_cap, m->line_count + 1, 8);
	if (b->line_cap < m->line_count + 1 || b->line_colour_cap < m->line_count + 1) {
		b->err = ENOMEM;
		return;
	}
	memcpy(m->lines + 6 * m->line_count, a, 3 * sizeof(float));
	memcpy(m->lines + 6 * m->line_count + 3, c, 3 * sizeof(float));
	for (int v = 0; v < 2; v++) {
		memcpy(m->line_colors + 8 * m->line_count + 4 * v, rgb, 3);
		m->line_colors[8 * m->line_count + 4 * v + 3] = 255;
	}
	m->line_count++;
}

static void triangle(struct builder *b, const float a[3], const float c[3], const float d[3], const uint8_t rgb[3])
{
	struct model *m = b->m;
	grow((void **)&m->triangles, &b->tri_cap, m->triangle_count + 1, 9 * sizeof(float));
	grow((void **)&m->triangle_colors, &b->tri_colour_cap, m->triangle_count + 1, 12);
	if (b->tri_cap < m->triangle_count + 1 || b->tri_colour_cap < m->triangle_count + 1) {
		b->err = ENOMEM;
		return;
	}
	const float *v[3] = { a, c, d };
	for (int i = 0; i < 3; i++) {
		memcpy(m->triangles + 9 * m->triangle_count + 3 * i, v[i], 3 * sizeof(float));
		memcpy(m->triangle_colors + 12 * m->triangle_count + 4 * i, rgb, 3);
		m->triangle_colors[12 * m->triangle_count + 4 * i + 3] = 255;
	}
	m->triangle_count++;
}

/* A vertical rectangle from radius r0 to r1 at azimuth a (degrees, from +x
 * towards +z), heights y0 to y1. */
static void wall(struct builder *b, double a, double r0, double r1, float y0, float y1, const uint8_t rgb[3])
{
	float c = (float)cos(a * M_PI / 180), s = (float)sin(a * M_PI / 180);
	float p0[3] = { r0 * c, y0, r0 * s }, p1[3] = { r1 * c, y0, r1 * s };
	float p2[3] = { r1 * c, y1, r1 * s }, p3[3] = { r0 * c, y1, r0 * s };
	triangle(b, p0, p1, p2, rgb);
	triangle(b, p0, p2, p3, rgb);
}

static void circle(struct builder *b, double r, float y, const uint8_t rgb[3])
{
	for (int i = 0; i < 96; i++) {
		double a0 = 2 * M_PI * i / 96, a1 = 2 * M_PI * (i + 1) / 96;
		float p[3] = { (float)(r * cos(a0)), y, (float)(r * sin(a0)) };
		float q[3] = { (float)(r * cos(a1)), y, (float)(r * sin(a1)) };
		line(b, p, q, rgb);
	}
}

static const uint8_t white[3] = { 255, 255, 255 }, red[3] = { 255, 0, 0 }, green[3] = { 0, 255, 0 },
		     blue[3] = { 0, 0, 255 }, yellow[3] = { 255, 255, 0 };

/* A line along the rotation axis, bottom to top: every image lights its
 * centre column, so it shows where the axis falls on the screen. */
static void axis(struct builder *b, float h)
{
	line(b, (float[3]){ 0, -0.9f * h, 0 }, (float[3]){ 0, 0.9f * h, 0 }, white);
}

/* Circles at radii 0.25, 0.5, 0.75 and 0.95 on three heights: round and
 * concentric when the axis centre and the phase are right. */
static void rings(struct builder *b, float h)
{
	static const double radius[4] = { 0.25, 0.5, 0.75, 0.95 };
	const uint8_t *colour[4] = { red, green, blue, white };
	for (int k = 0; k < 3; k++)
		for (int i = 0; i < 4; i++)
			circle(b, radius[i], (k - 1) * 0.6f * h, colour[i]);
}

/* A cube of half size 0.6 (0.6 h high) with a 4 x 4 grid on each face:
 * straight edges and square cells when the geometry is right. */
static void grid_cube(struct builder *b, float h)
{
	const float s = 0.6f, t = 0.6f * h;
	for (int i = 0; i <= 4; i++) {
		float u = -s + 2 * s * i / 4, v = -t + 2 * t * i / 4;
		for (int side = -1; side <= 1; side += 2) {
			float x = side * s;
			line(b, (float[3]){ x, -t, u }, (float[3]){ x, t, u }, white); /* faces x = +-s */
			line(b, (float[3]){ x, v, -s }, (float[3]){ x, v, s }, white);
			line(b, (float[3]){ u, -t, x }, (float[3]){ u, t, x }, yellow); /* faces z = +-s */
			line(b, (float[3]){ -s, v, x }, (float[3]){ s, v, x }, yellow);
			float y = side * t;
			line(b, (float[3]){ u, y, -s }, (float[3]){ u, y, s }, green); /* top and bottom */
			line(b, (float[3]){ -s, y, u }, (float[3]){ s, y, u }, green);
		}
	}
}

/* Twelve radial bars, 30 degrees apart: red, green and blue at 64, 128,
 * 192 and 255, for each channel's brightness and its dither. */
static void colour_bars(struct builder *b, float h)
{
	for (int c = 0; c < 3; c++)
		for (int l = 0; l < 4; l++) {
			uint8_t rgb[3] = { 0, 0, 0 };
			rgb[c] = (uint8_t)(64 * (l + 1) - (l == 3));
			wall(b, 30.0 * (4 * c + l), 0.3, 0.9, -0.5f * h, 0.5f * h, rgb);
		}
}

/* Four half-walls from the axis out at 0, 90, 180 and 270 degrees, red,
 * green, blue and white: their directions show the display's azimuths. */
static void walls(struct builder *b, float h)
{
	const uint8_t *colour[4] = { red, green, blue, white };
	for (int i = 0; i < 4; i++)
		wall(b, 90.0 * i, 0.02, 0.95, -0.8f * h, 0.8f * h, colour[i]);
}

/* Posts at radius 0.9 every 10 degrees, a tall one at 0 and middle ones
 * every 90: like a dial. A phase error turns the whole dial against the
 * screen's true angle; a timing error smears the posts. */
static void slice_index(struct builder *b, float h)
{
	for (int d = 0; d < 360; d += 10) {
		double a = d * M_PI / 180;
		float top = d == 0 ? 0.8f * h : d % 90 == 0 ? 0.5f * h : 0.2f * h;
		float p[3] = { (float)(0.9 * cos(a)), -0.8f * h, (float)(0.9 * sin(a)) };
		float q[3] = { p[0], top, p[2] };
		line(b, p, q, d == 0 ? red : d % 90 == 0 ? yellow : white);
	}
	circle(b, 0.9, -0.8f * h, white);
}

struct model *pattern_build(const char *name, float h)
{
	static const struct {
		const char *name;
		void (*make)(struct builder *b, float h);
	} patterns[] = {
		{ "axis", axis },           { "rings", rings },
		{ "grid-cube", grid_cube }, { "colour-bars", colour_bars },
		{ "walls", walls },         { "slice-index", slice_index },
	};
	for (size_t i = 0; i < sizeof(patterns) / sizeof(patterns[0]); i++) {
		if (strcmp(name, patterns[i].name) != 0)
			continue;
		struct builder b = { .m = calloc(1, sizeof(struct model)) };
		if (b.m)
			patterns[i].make(&b, h > 0 ? h : 1.0f);
		if (!b.m || b.err) {
			model_destroy(b.m);
			errno = ENOMEM;
			return NULL;
		}
		return b.m;
	}
	errno = EINVAL;
	return NULL;
}
