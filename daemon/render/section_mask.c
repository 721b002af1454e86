/* Point masks (bin.h, struct bin_point_mask) lit on a canvas: a dense
 * draw of one-pixel points of one colour binned as a bit per voxel. */
#include "section.h"

/* Tile t's mask rows lit as bytes: each set bit a section_pixel(). */
static void mask_tile_bytes(struct section_canvas *c, uint32_t t, const uint32_t *rows, const uint8_t rgb[3])
{
	uint32_t u0 = (t % c->tiles_x) * VOLUME_TILE, v0 = (t / c->tiles_x) * VOLUME_TILE;
	for (uint32_t y = 0; y < VOLUME_TILE; y++)
		for (uint32_t bits = rows[y]; bits; bits &= bits - 1)
			section_pixel(c, u0 + ((uint32_t)__builtin_ctz(bits) ^ 7), v0 + y, rgb);
}

/* Tile t's mask rows lit as lit bits: ANDed with rgb's pattern under the
 * tile's table, what section_lit_pixel() lights for each of them. */
static void mask_tile_lit(struct section_canvas *c, uint32_t k, uint32_t t, const uint32_t *rows,
			  const uint8_t rgb[3], struct halftone_patterns *p, halftone_fn fn)
{
	uint32_t any = 0;
	for (uint32_t y = 0; y < VOLUME_TILE; y++)
		any |= rows[y];
	if (!any)
		return;
	const struct halftone_table *thr = brightness_table(c->lit_tables, k, t % c->tiles_x);
	const uint32_t(*pat)[16] = (const uint32_t(*)[16])halftone_pattern(p, rgb, thr, fn)->bits;
	uint32_t *lit = c->lit_bits + (size_t)t * SECTION_LIT_TILE, set = 0;
	for (uint32_t y = 0; y < VOLUME_TILE; y++) {
		uint32_t r = rows[y] & pat[0][y % 16], g = rows[y] & pat[1][y % 16], b = rows[y] & pat[2][y % 16];
		lit[y] |= r;
		lit[VOLUME_TILE + y] |= g;
		lit[2 * VOLUME_TILE + y] |= b;
		set |= (uint32_t)((r | g | b) != 0) << y;
	}
	c->lit_rows[t] |= set;
}

void section_canvas_mask(struct section_canvas *c, uint32_t k, const uint32_t *bits, const uint8_t rgb[3],
			 struct halftone_patterns *p, halftone_fn fn)
{
	uint32_t tiles = c->tiles_x * c->tiles_y;
	for (uint32_t t = 0; t < tiles; t++) {
		const uint32_t *rows = bits + (size_t)t * VOLUME_TILE;
		if (c->lit_tables)
			mask_tile_lit(c, k, t, rows, rgb, p, fn);
		else
			mask_tile_bytes(c, t, rows, rgb);
	}
}
