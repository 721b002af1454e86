#include "section.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Clipping a triangle by two planes yields at most 5 vertices; Sutherland-
 * Hodgman on degenerate input can repeat some, never more than double. */
#define SECTION_MAX_VERTS 12

int section_canvas_init(struct section_canvas *c, const struct geometry *g)
{
	*c = (struct section_canvas){ .geom = *g }; /* bright NULL: exact until set */
	c->tiles_x = volume_tiles_across(g->width);
	c->tiles_y = volume_tiles_across(g->height);
	size_t tiles = (size_t)c->tiles_x * c->tiles_y;
	c->rgb = calloc(tiles, HALFTONE_TILE_BYTES);
	c->rows = calloc(tiles, sizeof(*c->rows));
	int e;
	if (frexp(2.0 * g->half_height, &e) == 0.5)
		c->row_scale = 1.0 / (2.0 * g->half_height); /* exact */
	c->weighted_plane = c->tiles_x * VOLUME_TILE;
	/* Zeroed: the vector spans read whole half rows of it (masked). */
	c->weighted = calloc((size_t)c->weighted_plane, 3);
	c->plain_bits = calloc(tiles * VOLUME_TILE, sizeof(*c->plain_bits));
	c->plain_rows = calloc(tiles, sizeof(*c->plain_rows));
	c->lit_bits = calloc(tiles * SECTION_LIT_TILE, sizeof(*c->lit_bits));
	c->lit_rows = calloc(tiles, sizeof(*c->lit_rows));
	if (!c->rgb || !c->rows || !c->weighted || !c->plain_bits || !c->plain_rows || !c->lit_bits || !c->lit_rows) {
		section_canvas_finish(c);
		return -ENOMEM;
	}
	return 0;
}

void section_canvas_finish(struct section_canvas *c)
{
	free(c->rgb);
	free(c->rows);
	free(c->weighted);
	free(c->plain_bits);
	free(c->plain_rows);
	free(c->lit_bits);
	free(c->lit_rows);
	free(c->scratch);
	c->scratch = NULL;
	c->scratch_floats = 0;
	c->rgb = NULL;
	c->rows = NULL;
	c->weighted = NULL;
	c->plain_bits = NULL;
	c->plain_rows = NULL;
	c->lit_bits = NULL;
	c->lit_rows = NULL;
}

void section_canvas_clear_tile(struct section_canvas *c, uint32_t t)
{
	uint8_t *tile = c->rgb + (size_t)t * HALFTONE_TILE_BYTES;
	uint32_t rows = c->rows[t];
	if (rows == UINT32_MAX) {
		memset(tile, 0, HALFTONE_TILE_BYTES);
	} else {
		for (; rows; rows &= rows - 1) {
			uint32_t y = (uint32_t)__builtin_ctz(rows);
			for (int p = 0; p < 3; p++)
				memset(tile + p * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES, 0, HALFTONE_ROW_BYTES);
		}
	}
	c->rows[t] = 0;
	for (uint32_t p = c->plain_rows[t]; p; p &= p - 1)
		c->plain_bits[(size_t)t * VOLUME_TILE + (uint32_t)__builtin_ctz(p)] = 0;
	c->plain_rows[t] = 0;
	uint32_t *lit = c->lit_bits + (size_t)t * SECTION_LIT_TILE;
	for (uint32_t p = c->lit_rows[t]; p; p &= p - 1) { /* stores, not a memset call's start */
		uint32_t y = (uint32_t)__builtin_ctz(p);
		lit[y] = lit[VOLUME_TILE + y] = lit[2 * VOLUME_TILE + y] = 0;
	}
	c->lit_rows[t] = 0;
}

uint32_t section_canvas_next(const struct section_canvas *c, uint32_t t)
{
	const uint32_t *rows = c->rows, *plain = c->plain_rows, *lit = c->lit_rows, tiles = c->tiles_x * c->tiles_y;
	for (uint64_t a, b, pa, pb, la, lb; t + 4 <= tiles; t += 4) { /* four at a time through the untouched */
		memcpy(&a, rows + t, sizeof(a));
		memcpy(&b, rows + t + 2, sizeof(b));
		memcpy(&pa, plain + t, sizeof(pa));
		memcpy(&pb, plain + t + 2, sizeof(pb));
		memcpy(&la, lit + t, sizeof(la));
		memcpy(&lb, lit + t + 2, sizeof(lb));
		if (a | b | pa | pb | la | lb)
			break;
	}
	while (t < tiles && !rows[t] && !plain[t] && !lit[t])
		t++;
	return t;
}

void section_canvas_pack_lit(const struct section_canvas *c, uint32_t t, uint8_t *out, bool fresh)
{
	const uint8_t *bits = (const uint8_t *)(c->lit_bits + (size_t)t * SECTION_LIT_TILE);
	if (fresh)
		volume_tile_copy(out, bits);
	else
		volume_tile_or(out, bits);
}

bool section_canvas_pack_plain(const struct section_canvas *c, uint32_t t, const uint32_t pattern[3][16], uint8_t *out)
{
	const uint32_t *bits = c->plain_bits + (size_t)t * VOLUME_TILE;
	uint32_t any = 0;
	for (int i = 0; i < 3; i++) {
		uint8_t *plane = out + i * VOLUME_TILE_PLANE_BYTES;
		for (uint32_t rows = c->plain_rows[t]; rows; rows &= rows - 1) { /* the others have no bits */
			uint32_t y = (uint32_t)__builtin_ctz(rows), row;
			memcpy(&row, plane + 4 * y, sizeof(row));
			row |= bits[y] & pattern[i][y % 16];
			memcpy(plane + 4 * y, &row, sizeof(row));
			any |= row;
		}
	}
	return any != 0;
}

void section_canvas_plain(struct section_canvas *c, const uint8_t *rgb)
{
	c->plain = rgb != NULL && !c->general;
	if (c->plain)
		memcpy(c->plain_rgb, rgb, 3);
}

void section_canvas_lit(struct section_canvas *c, const struct brightness_tables *tables)
{
	c->lit_tables = tables;
}

void section_wedge_init(struct section_wedge *w, const struct geometry *g, uint32_t k)
{
	double n = g->images_per_rev;
	double theta = geometry_image_angle(g, k);
	double a = 2.0 * M_PI * (k - 0.5) / n, b = 2.0 * M_PI * (k + 0.5) / n;
	w->image = k;
	w->dx = cos(theta);
	w->dz = sin(theta);
	/* sin(phi - a) >= 0 and sin(b - phi) >= 0, times the radius. */
	w->n1x = -sin(a);
	w->n1z = cos(a);
	w->n2x = sin(b);
	w->n2z = -cos(b);
}

/* Per-channel MAX over bytes [a, b] of a canvas row (canvas order). */
static inline void max_bytes(uint8_t *row, uint32_t a, uint32_t b, uint8_t value)
{
	for (uint32_t j = a; j <= b; j++)
		row[j] = row[j] < value ? value : row[j];
}

/* Half a canvas tile row (16 bytes), and the pixel of each byte of the
 * row's two halves (halftone_pos()). */
typedef uint8_t span_half __attribute__((vector_size(16)));
static const span_half span_pixel[2] = { { 7, 6, 5, 4, 3, 2, 1, 0, 15, 14, 13, 12, 11, 10, 9, 8 },
					 { 23, 22, 21, 20, 19, 18, 17, 16, 31, 30, 29, 28, 27, 26, 25, 24 } };

void section_canvas_max_tile(struct section_canvas *c, uint32_t t, const uint8_t *src)
{
	uint32_t rows;
	memcpy(&rows, src, sizeof(rows));
	c->rows[t] |= rows;
	uint8_t *dst = c->rgb + (size_t)t * HALFTONE_TILE_BYTES;
	src += sizeof(rows);
	for (; rows; rows &= rows - 1) {
		size_t y = (size_t)__builtin_ctz(rows) * HALFTONE_ROW_BYTES;
		for (size_t p = y; p < 3 * HALFTONE_PLANE_BYTES; p += HALFTONE_PLANE_BYTES) {
			for (size_t h = 0; h < HALFTONE_ROW_BYTES; h += sizeof(span_half)) {
				span_half a, b;
				memcpy(&a, dst + p + h, sizeof(a));
				memcpy(&b, src + p + h, sizeof(b));
				a = a ^ ((a ^ b) & (span_half)(a < b)); /* MAX */
				memcpy(dst + p + h, &a, sizeof(a));
			}
		}
	}
}

/* Per-byte MAX of value into the bytes of pixels a..b (a <= b <= 31) of a
 * canvas tile row, without a branch per pixel: the halves holding them
 * are read and written whole, their other bytes unchanged. */
static inline void max_pixels(uint8_t *r, uint32_t a, uint32_t b, uint8_t value)
{
	span_half lo = { 0 }, hi = { 0 }, val = { 0 };
	lo += (uint8_t)a;
	hi += (uint8_t)b;
	val += value;
	for (uint32_t h = a / 16; h <= b / 16; h++) {
		span_half row, lit;
		memcpy(&row, r + 16 * h, sizeof(row));
		lit = (span_half)((span_pixel[h] >= lo) & (span_pixel[h] <= hi)) & val;
		row = row ^ ((row ^ lit) & (span_half)(row < lit));
		memcpy(r + 16 * h, &row, sizeof(row));
	}
}

/* The bit of a plain bits' byte that each byte of a canvas row half holds:
 * both are in pixel order x ^ 7. */
static const span_half plain_bit = { 1, 2, 4, 8, 0x10, 0x20, 0x40, 0x80, 1, 2, 4, 8, 0x10, 0x20, 0x40, 0x80 };

void section_canvas_fold(struct section_canvas *c, uint32_t t)
{
	uint8_t *tile = c->rgb + (size_t)t * HALFTONE_TILE_BYTES;
	uint32_t *bits = c->plain_bits + (size_t)t * VOLUME_TILE;
	for (uint32_t rows = c->plain_rows[t]; rows; rows &= rows - 1) {
		uint32_t y = (uint32_t)__builtin_ctz(rows), m = bits[y];
		bits[y] = 0;
		for (int h = 0; h < 2; h++) {
			span_half sel = { 0 };
			for (int j = 0; j < 8; j++) {
				sel[j] = (uint8_t)(m >> (16 * h));
				sel[8 + j] = (uint8_t)(m >> (16 * h + 8));
			}
			span_half lit = (span_half)((sel & plain_bit) != 0);
			for (int i = 0; i < 3; i++) {
				uint8_t *r = tile + i * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES + 16 * h;
				span_half row, val = lit & c->plain_rgb[i];
				memcpy(&row, r, sizeof(row));
				row = row ^ ((row ^ val) & (span_half)(row < val)); /* MAX */
				memcpy(r, &row, sizeof(row));
			}
		}
	}
	c->rows[t] |= c->plain_rows[t];
	c->plain_rows[t] = 0;
}

/* section_span()'s byte loops: what the tests compare max_pixels() with
 * (section_canvas.general). */
static void span_bytes(uint8_t *base, uint32_t a, uint32_t b, const uint8_t rgb[3])
{
	for (int i = 0; i < 3; i++) {
		if (!rgb[i])
			continue;
		uint8_t *r = base + i * HALFTONE_PLANE_BYTES;
		/* Pixels a..b are bytes a^7..b^7: whole groups of 8
		 * stay whole, partial groups at the ends reverse. */
		uint32_t ga = a & ~7u, gb = b & ~7u;
		if (ga == gb) {
			max_bytes(r, ga + 7 - (b & 7), ga + 7 - (a & 7), rgb[i]);
		} else {
			max_bytes(r, ga, ga + 7 - (a & 7), rgb[i]);
			if (gb > ga + 8)
				max_bytes(r, ga + 8, gb - 1, rgb[i]);
			max_bytes(r, gb + 7 - (b & 7), gb + 7, rgb[i]);
		}
	}
}

void section_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1, const uint8_t rgb[3])
{
	uint32_t row = (v / VOLUME_TILE) * c->tiles_x, y = v % VOLUME_TILE;
	if (section_is_plain(c, rgb)) {
		section_plain_span(c, v, u0, u1);
		return;
	}
	for (uint32_t u = u0; u <= u1;) {
		uint32_t t = row + u / VOLUME_TILE;
		uint32_t a = u % VOLUME_TILE, b = (u | 31) < u1 ? 31 : u1 % VOLUME_TILE;
		uint8_t *base = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + y * HALFTONE_ROW_BYTES;
		if (c->general) {
			span_bytes(base, a, b, rgb);
		} else {
			for (int i = 0; i < 3; i++)
				if (rgb[i])
					max_pixels(base + i * HALFTONE_PLANE_BYTES, a, b, rgb[i]);
		}
		c->rows[t] |= 1u << y;
		u += b - a + 1;
	}
}

/* A primitive's brightness weights in one image, worked out the first time
 * a piece of it reaches the thinned band (most primitives never do). */
struct section_weight {
	const struct brightness_map *m;
	const double (*v)[3];
	int n;
	double dx, dz;
	bool ready;
	struct brightness_weight w;
};

/* The weighted colour of columns a..b (inside the band) of one polygon,
 * into c->weighted in the canvas's own order (plane i at i * weighted_plane,
 * column u at byte (u & ~31) + halftone_pos(u & 31)): brightness_apply()'s
 * rule, the weight worked out once per column for every row of the
 * polygon. Returns WEIGH_DARK where every value is zero, WEIGH_SAME where
 * every one is rgb's (a weight of 1 throughout), else WEIGH_LIT. */
enum weighed { WEIGH_DARK, WEIGH_LIT, WEIGH_SAME };

static enum weighed weigh_columns(struct section_canvas *c, struct section_weight *wt, uint32_t a, uint32_t b,
				  const uint8_t rgb[3])
{
	if (!wt->ready) {
		brightness_weight_of(wt->m, wt->v, wt->n, wt->dx, wt->dz, &wt->w);
		wt->ready = true;
	}
	const float *rate = wt->w.rate, kw = wt->w.kw, inv = wt->w.inv_cross;
	/* The rates rise with the distance from the axis: where the column
	 * nearest it keeps its weight of 1, every column does. */
	uint32_t near = wt->m->width / 2;
	near = near < a ? a : near > b ? b : near;
	if (kw >= 1.0f && rate[near] * inv >= 1.0f)
		return WEIGH_SAME;
	/* kw <= 1, so w <= 1: at w = 1, c * w + 1e-3 rounds down to c, as
	 * brightness_apply() returns it; no branch per channel. */
	const float cf[3] = { rgb[0], rgb[1], rgb[2] };
	const size_t plane = c->weighted_plane;
	uint8_t any = 0, diff = 0;
	for (uint32_t u = a; u <= b; u++) {
		float w = rate[u] * inv;
		w = w > kw ? kw : w;
		uint8_t *out = c->weighted + (u & ~31u) + halftone_pos(u & 31u);
		uint8_t r = (uint8_t)(cf[0] * w + 1e-3f), g = (uint8_t)(cf[1] * w + 1e-3f),
			bl = (uint8_t)(cf[2] * w + 1e-3f);
		out[0] = r;
		out[plane] = g;
		out[2 * plane] = bl;
		any |= r | g | bl;
		diff |= (r ^ rgb[0]) | (g ^ rgb[1]) | (bl ^ rgb[2]);
	}
	return !any ? WEIGH_DARK : diff ? WEIGH_LIT : WEIGH_SAME;
}

/* Per-channel MAX of canvas row bytes [ja, jb] with src's. */
static inline void max_from(uint8_t *row, const uint8_t *src, uint32_t ja, uint32_t jb)
{
	for (uint32_t j = ja; j <= jb; j++)
		row[j] = row[j] < src[j] ? src[j] : row[j];
}

/* max_pixels() with each byte's value from src (the same canvas order),
 * both halves of the row whatever a and b: no branch at all, where
 * max_from()'s loops of 1 to 8 bytes, or a loop over the halves,
 * mispredict. */
static inline void max_pixels_from(uint8_t *r, const uint8_t *src, uint32_t a, uint32_t b)
{
	span_half lo = { 0 }, hi = { 0 };
	lo += (uint8_t)a;
	hi += (uint8_t)b;
	for (uint32_t h = 0; h < 2; h++) {
		span_half row, val, lit;
		memcpy(&row, r + 16 * h, sizeof(row));
		memcpy(&val, src + 16 * h, sizeof(val));
		lit = (span_half)((span_pixel[h] >= lo) & (span_pixel[h] <= hi)) & val;
		row = row ^ ((row ^ lit) & (span_half)(row < lit));
		memcpy(r + 16 * h, &row, sizeof(row));
	}
}

/* Pixels pa..pb of one plane of a canvas tile row: MAX with src's bytes
 * (the general path byte by byte, as span_bytes() for section_span()). */
static inline void weighted_pixels(const struct section_canvas *c, uint8_t *r, const uint8_t *src, uint32_t pa,
				   uint32_t pb)
{
	if (!c->general) {
		max_pixels_from(r, src, pa, pb);
		return;
	}
	uint32_t ga = pa & ~7u, gb = pb & ~7u;
	if (ga == gb) {
		max_from(r, src, ga + 7 - (pb & 7), ga + 7 - (pa & 7));
	} else {
		max_from(r, src, ga, ga + 7 - (pa & 7));
		if (gb > ga + 8)
			max_from(r, src, ga + 8, gb - 1);
		max_from(r, src, gb + 7 - (pb & 7), gb + 7);
	}
}

/* Columns u0..u1 of row v: those in [a, b] with their weighted colour
 * (weigh_columns(); lit: whether any is not zero), the rest as
 * section_span() does; byte ranges as section_span() takes them. */
static void weighted_span(struct section_canvas *c, uint32_t a, uint32_t b, bool lit, uint32_t v, uint32_t u0,
			  uint32_t u1, const uint8_t rgb[3])
{
	uint32_t lo = u0 > a ? u0 : a, hi = u1 < b ? u1 : b;
	if (u0 < lo)
		section_span(c, v, u0, lo - 1, rgb);
	if (u1 > hi)
		section_span(c, v, hi + 1, u1, rgb);
	if (!lit)
		return;
	uint32_t row = (v / VOLUME_TILE) * c->tiles_x, y = v % VOLUME_TILE;
	if (lo == hi) { /* one pixel: most primitives of a dense mesh */
		uint32_t t = row + lo / VOLUME_TILE, at = halftone_pos(lo % VOLUME_TILE);
		uint8_t *px = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + y * HALFTONE_ROW_BYTES + at;
		const uint8_t *sr = c->weighted + (lo & ~31u) + at;
		for (int i = 0; i < 3; i++) {
			uint8_t value = sr[(size_t)i * c->weighted_plane], was = px[i * HALFTONE_PLANE_BYTES];
			px[i * HALFTONE_PLANE_BYTES] = was < value ? value : was;
		}
		c->rows[t] |= 1u << y;
		return;
	}
	for (uint32_t u = lo; u <= hi;) {
		uint32_t t = row + u / VOLUME_TILE;
		uint32_t pa = u % VOLUME_TILE, pb = (u | 31) < hi ? 31 : hi % VOLUME_TILE;
		uint8_t *base = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + y * HALFTONE_ROW_BYTES;
		const uint8_t *src = c->weighted + (u & ~31u);
		for (int i = 0; i < 3; i++) /* a channel of 0 weighs 0 everywhere: no MAX */
			if (rgb[i])
				weighted_pixels(c, base + i * HALFTONE_PLANE_BYTES, src + (size_t)i * c->weighted_plane,
						pa, pb);
		c->rows[t] |= 1u << y;
		u += pb - pa + 1;
	}
}

/* How a piece whose s range is [lo, hi] is weighted: where its columns
 * (mirrored when mirror) reach the thinned band, [*a, *b] are those in
 * the band and the result weigh_columns()'s; WEIGH_SAME where they do
 * not, or where the weights leave the colours as they are, so that the
 * plain spans' bytes and rows do without the weighted ones' work. */
static enum weighed band_weighing(struct section_canvas *c, struct section_weight *wt, double lo, double hi,
				  bool mirror, const uint8_t rgb[3], uint32_t *a, uint32_t *b)
{
	const struct brightness_map *m = wt->m;
	/* The band's s range is symmetric about the axis (mirroring keeps it). */
	if (!(hi >= -m->band_s && lo <= m->band_s))
		return WEIGH_SAME;
	uint32_t u0 = geometry_column(&c->geom, lo), u1 = geometry_column(&c->geom, hi);
	if (mirror) {
		uint32_t t = c->geom.width - 1 - u0;
		u0 = c->geom.width - 1 - u1;
		u1 = t;
	}
	if (!(lo <= hi && u1 >= m->band_lo && u0 <= m->band_hi))
		return WEIGH_SAME;
	*a = u0 > m->band_lo ? u0 : m->band_lo;
	*b = u1 < m->band_hi ? u1 : m->band_hi;
	return weigh_columns(c, wt, *a, *b, rgb);
}

void section_weighted_runs(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			   const uint8_t rgb[3], double lo, double hi, const struct section_run *runs, unsigned count)
{
	struct section_weight wt = { .m = c->bright, .v = v, .n = n, .dx = w->dx, .dz = w->dz };
	uint32_t a = 0, b = 0;
	enum weighed lit = band_weighing(c, &wt, lo, hi, false, rgb, &a, &b);
	for (unsigned i = 0; i < count; i++) {
		const struct section_run *r = &runs[i];
		if (lit != WEIGH_SAME && r->u1 >= a && r->u0 <= b) /* raster_rows()'s choice */
			weighted_span(c, a, b, lit == WEIGH_LIT, r->v, r->u0, r->u1, rgb);
		else
			section_span(c, r->v, r->u0, r->u1, rgb);
	}
}

/* Minimum and maximum of finite values (fmin/fmax are library calls). */
static inline double dmin(double a, double b)
{
	return a < b ? a : b;
}

static inline double dmax(double a, double b)
{
	return a > b ? a : b;
}

/* One Sutherland-Hodgman pass keeping sign * (nx x + nz z) >= 0 (closed, so
 * geometry on the axis survives every wedge). Returns the vertex count. */
static int clip_plane(const double (*in)[3], int n, double (*out)[3], double nx, double nz)
{
	int m = 0;
	for (int i = 0; i < n; i++) {
		const double *p = in[i], *q = in[i + 1 < n ? i + 1 : 0];
		double dp = nx * p[0] + nz * p[2], dq = nx * q[0] + nz * q[2];
		if (dp >= 0.0)
			memcpy(out[m++], p, sizeof(out[0]));
		if ((dp >= 0.0) != (dq >= 0.0)) {
			double t = dp / (dp - dq);
			for (int j = 0; j < 3; j++)
				out[m][j] = p[j] + t * (q[j] - p[j]);
			m++;
		}
	}
	return m;
}

/* The polygon's edges, for crossing horizontal lines without dividing. */
struct edges {
	int n;
	double y0[SECTION_MAX_VERTS], y1[SECTION_MAX_VERTS];   /* y0 <= y1 */
	double s0[SECTION_MAX_VERTS], dsdy[SECTION_MAX_VERTS]; /* s at y0 */
};

static inline __attribute__((always_inline)) void edges_init(struct edges *e, const double (*q)[2], int n)
{
	e->n = n;
	for (int i = 0; i < n; i++) {
		const double *a = q[i], *b = q[i + 1 < n ? i + 1 : 0];
		if (a[1] > b[1]) {
			const double *t = a;
			a = b;
			b = t;
		}
		e->y0[i] = a[1];
		e->y1[i] = b[1];
		e->s0[i] = a[0];
		e->dsdy[i] = b[1] > a[1] ? (b[0] - a[0]) / (b[1] - a[1]) : 0.0;
	}
}

/* Widens [*lo, *hi] by where the edges cross the line y = y. */
static void edges_cross(const struct edges *e, double y, double *lo, double *hi)
{
	for (int i = 0; i < e->n; i++) {
		if (y < e->y0[i] || y > e->y1[i] || e->y1[i] == e->y0[i])
			continue;
		double s = e->s0[i] + (y - e->y0[i]) * e->dsdy[i];
		*lo = dmin(*lo, s);
		*hi = dmax(*hi, s);
	}
}

/* Conservative rasterisation of a convex polygon in (s, y): per row, the s
 * range of the polygon within the row's slab gives the columns. The outer
 * rows' slabs extend to infinity: that is the clamp to the image. */
/* Widens [*lo, *hi] by coordinate axis (0 s, 1 y) of the vertices whose y
 * lies in [ylo, yhi]. */
static void vertices_in_slab(const double (*q)[2], int n, double ylo, double yhi, int axis, double *lo, double *hi)
{
	for (int i = 0; i < n; i++) {
		if (q[i][1] >= ylo && q[i][1] <= yhi) {
			*lo = dmin(*lo, q[i][axis]);
			*hi = dmax(*hi, q[i][axis]);
		}
	}
}

/* geometry_row(), by a product where 2h is a power of two (perspecta,
 * small): x / 2^k and x 2^-k are the same rounding of the same number. */
static inline uint32_t canvas_row(const struct section_canvas *c, double y)
{
	double h = c->geom.half_height;
	if (c->row_scale == 0.0 || c->general)
		return geometry_row(&c->geom, y);
	return geometry_clamp_index_((h - y) * c->row_scale * c->geom.height, c->geom.height);
}

/* The body of project_raster() and project_raster_mirrored(), with mirror
 * a constant in each: the unmirrored path tests nothing per row. */
static inline __attribute__((always_inline)) void raster_rows(struct section_canvas *c, const double (*q)[2], int n,
							      const uint8_t rgb[3], uint32_t wa, uint32_t wb, bool wlit,
							      bool mirror, bool weighted)
{
	const struct geometry *g = &c->geom;
	double ymin = INFINITY, ymax = -INFINITY;
	vertices_in_slab(q, n, -INFINITY, INFINITY, 1, &ymin, &ymax);
	if (n <= 0)
		return;
	double h = g->half_height, row_h = 2.0 * h / g->height;
	/* A hair of slack so rounding at a row edge never loses a touch. */
	double eps = 1e-9 * row_h;
	uint32_t v0 = canvas_row(c, ymax), v1 = canvas_row(c, ymin);
	/* Per row, the polygon's s range inside the slab comes from its
	 * vertices in the slab and its edges' crossings of the slab's two
	 * lines (s is linear along an edge). The outer rows' slabs are open,
	 * so a polygon in one row (most small primitives) needs no edges. */
	struct edges e;
	if (v1 > v0)
		edges_init(&e, q, n);
	for (uint32_t v = v0; v <= v1; v++) {
		double yhi = v == v0 ? INFINITY : h - v * row_h + eps;
		double ylo = v == v1 ? -INFINITY : h - (v + 1) * row_h - eps;
		double lo = INFINITY, hi = -INFINITY;
		vertices_in_slab(q, n, ylo, yhi, 0, &lo, &hi);
		if (v != v0)
			edges_cross(&e, yhi, &lo, &hi);
		if (v != v1)
			edges_cross(&e, ylo, &lo, &hi);
		if (lo <= hi) {
			uint32_t u0 = geometry_column(g, lo), u1 = geometry_column(g, hi);
			if (mirror) {
				uint32_t t = g->width - 1 - u0;
				u0 = g->width - 1 - u1;
				u1 = t;
			}
			if (weighted && u1 >= wa && u0 <= wb)
				weighted_span(c, wa, wb, wlit, v, u0, u1, rgb);
			else
				section_span(c, v, u0, u1, rgb);
		}
	}
}

/* raster_rows(), with the weights' checks only for a polygon whose
 * columns reach the thinned band (most never do: the same loop as the
 * exact model's). */
static inline __attribute__((always_inline)) void raster_convex(struct section_canvas *c, const double (*q)[2], int n,
								const uint8_t rgb[3], struct section_weight *wt,
								bool mirror)
{
	if (wt) {
		double lo = INFINITY, hi = -INFINITY;
		uint32_t a = 0, b = 0;
		vertices_in_slab(q, n, -INFINITY, INFINITY, 0, &lo, &hi);
		enum weighed lit = band_weighing(c, wt, lo, hi, mirror, rgb, &a, &b);
		if (lit != WEIGH_SAME) {
			raster_rows(c, q, n, rgb, a, b, lit == WEIGH_LIT, mirror, true);
			return;
		}
	}
	raster_rows(c, q, n, rgb, 0, 0, false, mirror, false);
}

/* Sections the convex polygon v (already inside the lobe's wedge) and
 * rasterises its projection (mirrored: project_raster_mirrored()). */
static inline __attribute__((always_inline)) void project_body(struct section_canvas *c, const struct section_wedge *w,
							       const double (*v)[3], int n, const uint8_t rgb[3],
							       struct section_weight *wt, bool mirror)
{
	double q[SECTION_MAX_VERTS][2];
	for (int i = 0; i < n; i++) {
		q[i][0] = v[i][0] * w->dx + v[i][2] * w->dz;
		q[i][1] = v[i][1];
	}
	raster_convex(c, (const double(*)[2])q, n, rgb, wt, mirror);
}

static void project_raster(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			   const uint8_t rgb[3], struct section_weight *wt)
{
	project_body(c, w, v, n, rgb, wt, false);
}

static void project_raster_mirrored(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3],
				    int n, const uint8_t rgb[3], struct section_weight *wt)
{
	project_body(c, w, v, n, rgb, wt, true);
}

/* One lobe: sign 1 keeps n1.p >= 0 and n2.p >= 0, sign -1 the opposite
 * side. d1, d2 are the vertices' n1.p and n2.p: a primitive wholly inside
 * needs no clipping, one wholly outside either plane nothing. The body of
 * section_lobe() and section_lobe_mirrored(), mirror a constant in each. */
static inline __attribute__((always_inline)) void lobe_body(
	struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n, const double *d1,
	const double *d2, double sign, const uint8_t rgb[3], struct section_weight *wt, bool mirror)
{
	int in1 = 0, in2 = 0;
	for (int i = 0; i < n; i++) {
		in1 += sign * d1[i] >= 0.0;
		in2 += sign * d2[i] >= 0.0;
	}
	if (in1 == 0 || in2 == 0)
		return;
	double a[SECTION_MAX_VERTS][3], b[SECTION_MAX_VERTS][3];
	const double(*piece)[3] = v;
	if (in1 != n || in2 != n) {
		/* A plane every vertex is inside leaves them as they are. */
		const double(*cut)[3] = v;
		if (in1 != n || c->general) {
			n = clip_plane(v, n, a, sign * w->n1x, sign * w->n1z);
			if (n == 0)
				return;
			cut = (const double(*)[3])a;
		}
		n = clip_plane(cut, n, b, sign * w->n2x, sign * w->n2z);
		if (n == 0)
			return;
		piece = (const double(*)[3])b;
	}
	if (mirror)
		project_raster_mirrored(c, w, piece, n, rgb, wt);
	else
		project_raster(c, w, piece, n, rgb, wt);
}

static void section_lobe(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			 const double *d1, const double *d2, double sign, const uint8_t rgb[3],
			 struct section_weight *wt)
{
	lobe_body(c, w, v, n, d1, d2, sign, rgb, wt, false);
}

static void section_lobe_mirrored(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
				  const double *d1, const double *d2, double sign, const uint8_t rgb[3],
				  struct section_weight *wt)
{
	lobe_body(c, w, v, n, d1, d2, sign, rgb, wt, true);
}

/* The range [*lo, *hi] of d1[i] + d2[i] over the vertices: 2 sin(D / 2)
 * times their s (linear), which both the band and the lobes are read from. */
static inline void s_range(const double *d1, const double *d2, int n, double *lo, double *hi)
{
	*lo = INFINITY;
	*hi = -INFINITY;
	for (int i = 0; i < n; i++) {
		*lo = dmin(*lo, d1[i] + d2[i]);
		*hi = dmax(*hi, d1[i] + d2[i]);
	}
}

/* The weights' state for v in w's image, or NULL when the model is EXACT
 * or v lies wholly outside the band in this image (its pieces' s ranges lie
 * within its vertices'; [lo, hi] from s_range(): brightness_map.band_d). */
static inline struct section_weight *weight_start(const struct section_canvas *c, const struct section_wedge *w,
						  const double (*v)[3], int n, double lo, double hi,
						  struct section_weight *wt)
{
	if (!c->bright || !brightness_active(c->bright))
		return NULL;
	if (hi < -c->bright->band_d || lo > c->bright->band_d)
		return NULL;
	*wt = (struct section_weight){ .m = c->bright, .v = v, .n = n, .dx = w->dx, .dz = w->dz };
	return wt;
}

/* Which lobes the clipping can leave a piece in: bit 0 s >= 0, bit 1
 * s < 0. d1 + d2 is linear (2 sin(D / 2) s; [lo, hi] from s_range()):
 * where it is below -m at every vertex, m = 1e-12 of the largest |x|, |z|
 * (X), no point of the primitive has d1 >= 0 and d2 >= 0, and none of the
 * clip's either: the first plane keeps vertices with d2 < -m, and its cut
 * points p + t (q - p) have |d1| and the error of their d2 under 50 ulps of
 * X (t = dp / (dp - dq) divides by a difference of opposite signs: no
 * cancellation), so their d2 stays below 0 and the second plane keeps
 * nothing. Likewise above m for the s < 0 lobe. Most primitives lie in one lobe; the other's clip would
 * cost about as much as the piece. */
static inline unsigned lobes_reached(const struct section_canvas *c, const double (*v)[3], int n, double lo, double hi)
{
	double xz = 0.0;
	if (c->general || (lo <= 0.0 && hi >= 0.0))
		return 3;
	for (int i = 0; i < n; i++)
		xz = dmax(xz, dmax(fabs(v[i][0]), fabs(v[i][2])));
	double m = 1e-12 * xz;
	return (hi < -m ? 0u : 1u) | (lo > m ? 0u : 2u);
}

/* The body of section_prim() and section_prim_mirror(), mirror a
 * constant in each. */
static inline __attribute__((always_inline)) void prim_body(struct section_canvas *c, const struct section_wedge *w,
							    const double (*v)[3], int n, const uint8_t rgb[3],
							    bool mirror)
{
	double d1[3], d2[3], lo, hi;
	for (int i = 0; i < n; i++) {
		d1[i] = w->n1x * v[i][0] + w->n1z * v[i][2];
		d2[i] = w->n2x * v[i][0] + w->n2z * v[i][2];
	}
	s_range(d1, d2, n, &lo, &hi);
	struct section_weight state, *wt = weight_start(c, w, v, n, lo, hi, &state);
	unsigned lobes = lobes_reached(c, v, n, lo, hi);
	for (int l = 0; l < 2; l++) {
		if (!(lobes >> l & 1))
			continue;
		if (mirror)
			section_lobe_mirrored(c, w, v, n, d1, d2, l ? -1.0 : 1.0, rgb, wt);
		else
			section_lobe(c, w, v, n, d1, d2, l ? -1.0 : 1.0, rgb, wt);
	}
}

void section_prim(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
		  const uint8_t rgb[3])
{
	prim_body(c, w, v, n, rgb, false);
}

void section_prim_mirror(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			 const uint8_t rgb[3], bool mirror)
{
	if (mirror)
		prim_body(c, w, v, n, rgb, true);
	else
		prim_body(c, w, v, n, rgb, false);
}
