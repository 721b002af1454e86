#include "brightness.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "volume.h"

void brightness_map_finish(struct brightness_map *m)
{
	free(m->rate);
	free(m->line_rate);
	free(m->n);
	free(m->phase);
	free(m->solid);
	free(m->lanes);
	m->lanes = NULL;
	m->rate = NULL;
	m->line_rate = NULL;
	m->n = NULL;
	m->phase = NULL;
	m->solid = NULL;
}

/* The pattern's offset at radius index i, row class y (0..15), in 0..M-1.
 * Any offset keeps each column's pattern over images evenly spaced. These
 * start neighbouring columns far apart (a golden-ratio step per column: no
 * radial spokes of images lit at once), and give a column's 16 row classes
 * offsets a sixteenth of M apart, in bit-reversed order, so that within
 * one image every column lights its share of the rows, spread out: a
 * surface lying in one image (a wall, in the uniform model) keeps its
 * density in every image. (A 2-D golden-ratio sequence over (i, y) left
 * fewer holes in the uniform model but missed its density by a fifth in
 * some images.) Integer arithmetic, for the GL renderers' table too. */
static uint16_t phase_of(uint32_t i, uint32_t y, uint32_t images)
{
	uint32_t rev = ((y & 1u) << 3) | ((y & 2u) << 1) | ((y & 4u) >> 1) | ((y & 8u) >> 3);
	uint32_t f = (i * 40503u + rev * 4096u) & 0xffffu; /* 40503 / 65536: the golden ratio's part */
	return (uint16_t)((f * images) >> 16);
}

/* Whether (c * mul) >> 16 (mul BRIGHTNESS_KEEP: c) is w's value of every
 * byte c at column u. */
static bool solid_exact(const struct brightness_map *m, const struct brightness_weight *w, uint32_t u, uint32_t mul)
{
	for (uint32_t c = 0; c < 256; c++)
		if ((c * mul) >> 16 != brightness_apply(m, w, u, (uint8_t)c))
			return false;
	return true;
}

/* brightness_map.solid[u]: KEEP, or m from ceil(65536 w) or a neighbour,
 * checked against brightness_apply() for every byte (with n / M weights at
 * M <= 256 images per volume, ceil(65536 n / M) always is). */
static uint32_t solid_mul_of(const struct brightness_map *m, uint32_t u)
{
	const struct brightness_weight w = { m->rate, m->wall, 1.0f };
	if (solid_exact(m, &w, u, BRIGHTNESS_KEEP))
		return BRIGHTNESS_KEEP;
	double base = ceil(fmin(m->rate[u], m->wall) * 65536.0);
	for (double c = base - 1.0; c <= base + 1.0; c += 1.0)
		if (c >= 0.0 && c <= 65535.0 && solid_exact(m, &w, u, (uint32_t)c))
			return (uint32_t)c;
	return BRIGHTNESS_FLOAT;
}

/* Column u's images per crossing (n), weights and place in the band. */
static void set_column(struct brightness_map *m, const struct geometry *g, uint32_t u, double d_angle, double density)
{
	double M = m->images, r = fabs(u + 0.5 - g->width / 2.0);
	double even = fmin(M, fmax(1.0, floor(M * r * d_angle + 0.5))), n = M;
	if (g->brightness == GEOMETRY_BRIGHTNESS_EVEN)
		n = even;
	double rate = n / M;
	if (g->brightness == GEOMETRY_BRIGHTNESS_UNIFORM) {
		/* The weight unrounded: at a few images per volume rounding n
		 * would miss the density by up to a half. */
		rate = fmin(1.0, density * r * d_angle);
		n = fmin(M, fmax(1.0, floor(M * rate + 0.5)));
	}
	m->n[u] = (uint16_t)n;
	m->rate[u] = (float)rate;
	m->line_rate[u] = g->brightness == GEOMETRY_BRIGHTNESS_EXACT ? 1.0f : (float)(even / M);
	if (n < M || m->wall < 1.0f) {
		if (m->band_lo > m->band_hi)
			m->band_lo = u;
		m->band_hi = u;
	}
}

/* brightness_map.lanes[tu] from the columns' rates and multipliers. */
static void set_lanes(struct brightness_map *m, uint32_t tu)
{
	struct brightness_lanes *l = &m->lanes[tu];
	bool any = false, by_mul = true;
	for (uint32_t p = 0; p < 32; p++) {
		uint32_t u = tu * 32 + (p ^ 7);
		float w = u < m->width ? m->rate[u] : 1.0f; /* brightness_apply(), a crossing weight of 1 */
		w = w > m->wall ? m->wall : w;
		l->weight[p] = w < 1.0f ? w : 1.0f;
		any |= w < 1.0f;
		uint32_t k = u < m->width ? m->solid[u] : BRIGHTNESS_KEEP;
		by_mul &= k != BRIGHTNESS_FLOAT;
		l->mul[p] = k < BRIGHTNESS_KEEP ? (uint16_t)k : 0;
		l->keep |= (uint32_t)(k == BRIGHTNESS_KEEP) << p;
	}
	l->weighed = any;
	l->by_mul = by_mul;
}

int brightness_map_init(struct brightness_map *m, const struct geometry *g)
{
	*m = (struct brightness_map){ .model = g->brightness, .width = g->width, .band_lo = 1, .band_hi = 0 };
	m->images = geometry_images_per_volume(g);
	m->rate = malloc(g->width * sizeof(*m->rate));
	m->line_rate = malloc(g->width * sizeof(*m->line_rate));
	m->n = malloc(g->width * sizeof(*m->n));
	uint32_t radii = g->width / 2 + 1;
	m->phase = malloc(radii * 16 * sizeof(*m->phase));
	m->solid = malloc(g->width * sizeof(*m->solid));
	m->lanes = calloc(volume_tiles_across(g->width), sizeof(*m->lanes));
	if (!m->rate || !m->line_rate || !m->n || !m->phase || !m->solid || !m->lanes) {
		brightness_map_finish(m);
		return -ENOMEM;
	}
	for (uint32_t i = 0; i < radii; i++)
		for (uint32_t y = 0; y < 16; y++)
			m->phase[i * 16 + y] = phase_of(i, y, m->images);
	double d_angle = 2.0 * M_PI / g->images_per_rev;
	/* UNIFORM's density: a crossing surface's at the rim. */
	double density = geometry_r0_px(g) / (g->width / 2.0);
	m->wall = g->brightness == GEOMETRY_BRIGHTNESS_UNIFORM ? (float)density : 1.0f;
	for (uint32_t u = 0; u < g->width; u++)
		set_column(m, g, u, d_angle, density);
	/* Outside the band every weight is 1: every byte stays. */
	for (uint32_t u = 0; u < g->width; u++)
		m->solid[u] = u >= m->band_lo && u <= m->band_hi ? solid_mul_of(m, u) : BRIGHTNESS_KEEP;
	for (uint32_t tu = 0; tu < volume_tiles_across(g->width); tu++)
		set_lanes(m, tu);
	/* Columns band_lo..band_hi lie within |s| < band_s (symmetric). */
	if (brightness_active(m)) {
		m->band_s =
			fmax(fabs(2.0 * m->band_lo / g->width - 1.0), fabs(2.0 * (m->band_hi + 1) / g->width - 1.0));
		m->band_d = 2.0 * sin(M_PI / g->images_per_rev) * m->band_s * (1.0 + 1e-9) + 1e-12;
	}
	return 0;
}

uint8_t brightness_threshold(const struct brightness_map *m, uint32_t k, uint32_t u, uint32_t v)
{
	if (u < m->band_lo || u > m->band_hi)
		return halftone_threshold(k, u, v);
	/* Bresenham over images: x < n[u] in exactly n[u] of any M
	 * consecutive images, evenly spaced; floor(255 x / M) rises with x
	 * (strictly while M <= 255), so a crossing white primitive's weighted
	 * value floor(255 n / M) is lit exactly there. */
	uint32_t i = brightness_radius_index(m->width, u);
	uint32_t x = (uint32_t)(((uint64_t)k * m->n[u] + m->phase[i * 16 + v % 16]) % m->images);
	return (uint8_t)(255u * x / m->images);
}

/* brightness_weight_of()'s cross2 of triangle v, whose side v0 v1 is t,
 * into *cross2. false: it has no area, and t is now its longest side, to
 * weigh as a segment. */
static inline bool triangle_cross2(const double (*v)[3], double t[3], double dx, double dz, double *cross2)
{
	double a[3] = { v[2][0] - v[0][0], v[2][1] - v[0][1], v[2][2] - v[0][2] };
	double nx = t[1] * a[2] - t[2] * a[1], ny = t[2] * a[0] - t[0] * a[2], nz = t[0] * a[1] - t[1] * a[0];
	double n2 = nx * nx + ny * ny + nz * nz;
	double l01 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2], l02 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
	/* |n|^2 = l01 l02 sin^2 of the angle at v0: no area when that
	 * is tiny against the sides' lengths. */
	if (n2 > 1e-12 * l01 * l02) {
		/* |n x e|^2 / |n|^2: the normal's part in the plane. */
		double ne = -dz * nx + dx * nz;
		*cross2 = (n2 - ne * ne) / n2;
		return true;
	}
	/* No area: its longest side. */
	double b[3] = { v[2][0] - v[1][0], v[2][1] - v[1][1], v[2][2] - v[1][2] };
	double l12 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
	if (l02 >= l01 && l02 >= l12)
		memcpy(t, a, sizeof(a));
	else if (l12 >= l01)
		memcpy(t, b, sizeof(b));
	return false;
}

void brightness_weight_of(const struct brightness_map *m, const double (*v)[3], int n, double dx, double dz,
			  struct brightness_weight *out)
{
	/* e = (-dz, 0, dx): the slice plane's normal. cross2 = p_cross^2. */
	double cross2 = 0.0;
	double t[3] = { v[1][0] - v[0][0], v[1][1] - v[0][1], v[1][2] - v[0][2] };
	bool segment = n == 2;
	if (n == 3)
		segment = !triangle_cross2(v, t, dx, dz, &cross2);
	if (segment) {
		double len2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2], te = -dz * t[0] + dx * t[2];
		if (!(len2 > 0.0)) {
			*out = (struct brightness_weight){ m->line_rate, 1.0f, 1e30f };
			return;
		}
		cross2 = te * te / len2;
	}
	cross2 = cross2 > 0.0 ? cross2 : 0.0;
	out->rate = segment ? m->line_rate : m->rate;
	out->kw = 1.0f;
	if (!segment && m->wall < 1.0f) { /* the uniform model's wall term */
		double wall = sqrt(fmax(0.0, 1.0 - cross2));
		if (wall > m->wall)
			out->kw = (float)(m->wall / wall);
	}
	out->inv_cross = cross2 > 1e-40 ? (float)fmin(1.0 / sqrt(cross2), 1e30) : 1e30f;
}

int brightness_tables_init(struct brightness_tables *t, const struct brightness_map *m)
{
	*t = (struct brightness_tables){ .images = m->images };
	t->base = calloc(m->images, sizeof(*t->base));
	if (!t->base)
		return -ENOMEM;
	for (uint32_t k = 0; k < m->images; k++)
		halftone_table_init(&t->base[k], k);
	if (!brightness_active(m))
		return 0;
	t->band_tx0 = m->band_lo / VOLUME_TILE;
	t->band_tiles = m->band_hi / VOLUME_TILE - t->band_tx0 + 1;
	t->band = calloc((size_t)m->images * t->band_tiles, sizeof(*t->band));
	if (!t->band) {
		brightness_tables_finish(t);
		return -ENOMEM;
	}
	for (uint32_t k = 0; k < m->images; k++) {
		for (uint32_t b = 0; b < t->band_tiles; b++) {
			struct halftone_table *tab = &t->band[(size_t)k * t->band_tiles + b];
			for (uint32_t y = 0; y < 16; y++) {
				for (uint32_t x = 0; x < HALFTONE_ROW_BYTES; x++) {
					uint32_t u = (t->band_tx0 + b) * VOLUME_TILE + x;
					/* Past the image's edge the canvas is zero. */
					tab->thr[y][halftone_pos(x)] =
						u < m->width ? brightness_threshold(m, k, u, y) : 254;
				}
			}
		}
	}
	return 0;
}

void brightness_tables_finish(struct brightness_tables *t)
{
	free(t->base);
	free(t->band);
	t->base = NULL;
	t->band = NULL;
}
