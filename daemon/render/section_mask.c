/* Point masks (bin.h, struct bin_point_mask) lit on a canvas: a dense
 * draw of one-pixel points of one colour binned as a bit per voxel. */
#include "section.h"

#include <string.h>

/* Tile t's mask rows lit as bytes: each set bit a section_pixel(). */
static void mask_tile_bytes(struct section_canvas *c, uint32_t t, const uint32_t *rows, const uint8_t rgb[3])
{
	uint32_t u0 = (t % c->tiles_x) * VOLUME_TILE, v0 = (t / c->tiles_x) * VOLUME_TILE;
	for (uint32_t y = 0; y < VOLUME_TILE; y++)
		for (uint32_t bits = rows[y]; bits; bits &= bits - 1)
			section_pixel(c, u0 + ((uint32_t)__builtin_ctz(bits) ^ 7), v0 + y, rgb);
}

/* Sixteen rows of a tile at once (the compiler's vectors: whatever the
 * target has). */
typedef uint32_t rows16 __attribute__((vector_size(64)));

typedef uint32_t rows8 __attribute__((vector_size(32)));
typedef uint32_t rows4 __attribute__((vector_size(16)));

#define LOAD16(v, p) memcpy(&(v), (p), sizeof(rows16))

/* The OR of v's sixteen lanes, halving. */
static inline uint32_t or_lanes(const rows16 *v)
{
	rows8 a, b;
	rows4 c, d;
	memcpy(&a, v, sizeof(a));
	memcpy(&b, (const char *)v + sizeof(a), sizeof(b));
	a |= b;
	memcpy(&c, &a, sizeof(c));
	memcpy(&d, (const char *)&a + sizeof(c), sizeof(d));
	c |= d;
	return c[0] | c[1] | c[2] | c[3];
}

/* Tile t's mask rows (half[0], half[1]: rows 0..15, 16..31) lit as lit
 * bits: ANDed with pat, its colour's pattern under the tile's table, what
 * section_lit_pixel() lights for each of them. */
static void mask_tile_lit(struct section_canvas *c, uint32_t t, const rows16 half[2],
			  const struct halftone_pattern *pat)
{
	uint32_t *lit = c->lit_bits + (size_t)t * SECTION_LIT_TILE;
	rows16 set[2] = { 0 };
	for (int i = 0; i < 3; i++) { /* the pattern's rows are y % 16 */
		rows16 pl, was;
		LOAD16(pl, pat->bits[i]);
		for (int h = 0; h < 2; h++) {
			rows16 bits = half[h] & pl;
			LOAD16(was, lit + i * VOLUME_TILE + 16 * h);
			was |= bits;
			memcpy(lit + i * VOLUME_TILE + 16 * h, &was, sizeof(was));
			set[h] |= bits;
		}
	}
	/* row y's flag: bit y where it has a bit set */
	const rows16 weight = { 1u << 0, 1u << 1, 1u << 2,  1u << 3,  1u << 4,  1u << 5,  1u << 6,  1u << 7,
				1u << 8, 1u << 9, 1u << 10, 1u << 11, 1u << 12, 1u << 13, 1u << 14, 1u << 15 };
	rows16 flags = ((rows16)(set[0] != 0) & weight) | ((rows16)(set[1] != 0) & (weight << 16));
	c->lit_rows[t] |= or_lanes(&flags);
}

void section_canvas_mask(struct section_canvas *c, uint32_t k, const uint32_t *bits, const uint8_t rgb[3],
			 struct halftone_patterns *p, halftone_fn fn)
{
	/* A tile column at a time: its tiles share a table (brightness.h),
	 * so rgb's pattern is looked up once a column, where it has bits. */
	for (uint32_t tx = 0; tx < c->tiles_x; tx++) {
		const struct halftone_pattern *pat = NULL;
		for (uint32_t t = tx; t < c->tiles_x * c->tiles_y; t += c->tiles_x) {
			const uint32_t *rows = bits + (size_t)t * VOLUME_TILE;
			if (!c->lit_tables) {
				mask_tile_bytes(c, t, rows, rgb);
				continue;
			}
			rows16 half[2], any;
			LOAD16(half[0], rows);
			LOAD16(half[1], rows + 16);
			any = half[0] | half[1];
			if (!or_lanes(&any))
				continue;
			if (!pat)
				pat = halftone_pattern(p, rgb, brightness_table(c->lit_tables, k, tx), fn);
			mask_tile_lit(c, t, half, pat);
		}
	}
}
