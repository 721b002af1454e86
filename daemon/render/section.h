/* Exact sectioning by one image's bow tie, and conservative rasterisation of
 * the sections into an 8-bit RGB canvas (docs/design.md section 3).
 *
 * Image k's bow tie is two closed wedges meeting at the y axis, bounded by
 * the planes through the axis at azimuths theta_k - D/2 and theta_k + D/2:
 * lobe s >= 0 around theta_k and lobe s < 0 around theta_k + pi. A primitive
 * is clipped to each lobe, the convex piece projected to (s, y) with
 * s = p . d_k, and every pixel whose cell that piece touches is lit. */
#ifndef SPINDLE_SECTION_H
#define SPINDLE_SECTION_H

#include <stdbool.h>
#include <stdint.h>

#include "brightness.h"
#include "geometry.h"
#include "halftone.h"
#include "volume.h"

#define SECTION_LIT_TILE (3 * VOLUME_TILE) /* uint32_t words of a tile's lit bits */

/* An 8-bit RGB accumulation buffer for one image, stored tile by tile in
 * the canvas tile layout of halftone.h (planes R, G, B of 32 rows of 32
 * bytes, pixel x at byte x ^ 7), so that halftoning and clearing a tile
 * touch one contiguous block. rows[t] has bit y set when row y of tile t
 * may hold non-zero bytes; all other rows are zero. */
struct section_canvas {
	struct geometry geom;
	uint32_t tiles_x, tiles_y;
	uint8_t *rgb;   /* tiles_x * tiles_y * HALFTONE_TILE_BYTES */
	uint32_t *rows; /* tiles_x * tiles_y row masks */
	/* The brightness model primitives are weighted by (brightness.h);
	 * NULL, or one that is not active: every touched voxel at full
	 * colour (EXACT). Points are never weighted. */
	const struct brightness_map *bright;
	uint8_t *weighted;       /* 3 planes of weighted_plane bytes: a polygon's */
	uint32_t weighted_plane; /* weighted colour per column, in canvas order */
	float *scratch;          /* NULL, or scratch_floats floats: grid.c's, */
	size_t scratch_floats;   /* grown as needed, freed with the canvas */
	double row_scale;        /* 1 / (2h) where 2h is a power of two, else 0 */
	/* The plain colour (section_canvas_plain()): spans of exactly that
	 * colour are kept as bits, not bytes: plain_bits[32 t + y] holds tile
	 * t's row y in the packed order of volume.h (bit x ^ 7 for pixel x),
	 * plain_rows[t] flags the rows with any (rows[t] does not: it stays
	 * the rows with bytes; a tile is touched where either is set). The
	 * canvas means the MAX of its bytes and its plain bits, which
	 * section_canvas_fold() makes bytes again; the halftone of that MAX
	 * is that of the bytes ORed with that of the bits, so a pack may take
	 * the bits straight. A dense mesh of one colour lights millions of
	 * spans of a pixel or two: a bit OR each, where bytes cost three
	 * planes. All zero outside the flagged rows. */
	bool plain;
	uint8_t plain_rgb[3];
	uint32_t *plain_bits; /* tiles_x * tiles_y * VOLUME_TILE */
	uint32_t *plain_rows; /* tiles_x * tiles_y */
	/* Points lit as bits, halftoned already (section_lit_pixel()): tile
	 * t as a packed tile of volume.h (planes R, G, B of 32 rows; bit
	 * x ^ 7 of a row's word for pixel x), lit_bits[96 t + 32 i + y]
	 * plane i's row y; lit_rows[t] flags the rows with a bit set. The
	 * pack takes them as they are or ORs them in
	 * (section_canvas_pack_lit()): exact, as the halftone of a MAX
	 * under one table is the OR of the halftones. Only for a canvas
	 * packed as it stands, never one kept as bytes: lit_tables (the
	 * volume's, section_canvas_lit()) says which it is, NULL for bytes.
	 * All zero outside the flagged rows. */
	uint32_t *lit_bits; /* tiles_x * tiles_y * SECTION_LIT_TILE */
	uint32_t *lit_rows; /* tiles_x * tiles_y */
	const struct brightness_tables *lit_tables;
	/* Tests: none of section.c's shortcuts, which light the same voxels
	 * (lobes the clip cannot reach, planes every vertex is inside, rows
	 * by a product, spans by half rows): both lobes, both planes,
	 * geometry_row(), spans byte by byte. */
	bool general;
};

/* The two half-spaces of image k's s >= 0 lobe, as inward normals in the xz
 * plane; the s < 0 lobe is their negation. */
struct section_wedge {
	uint32_t image;  /* k, in volume images */
	double dx, dz;   /* d_k */
	double n1x, n1z; /* plane at theta_k - D/2 */
	double n2x, n2z; /* plane at theta_k + D/2 */
};

/* Allocates a zeroed canvas. Returns 0 or -ENOMEM. */
int section_canvas_init(struct section_canvas *c, const struct geometry *g);
void section_canvas_finish(struct section_canvas *c);

/* Per-channel MAX of a canvas tile (compose.h, CANVAS_TILE_BYTES: its row
 * mask, then the planes) into tile t of c. */
void section_canvas_max_tile(struct section_canvas *c, uint32_t t, const uint8_t *src);

/* Zeroes the rows of tile t that rows[t] flags, its plain and lit bits,
 * and the flags. */
void section_canvas_clear_tile(struct section_canvas *c, uint32_t t);

/* From now on spans of colour rgb are kept as bits (rgb NULL: none are).
 * The canvas must hold no plain bits (every tile folded). Not with
 * c->general, whose byte loops the tests compare. */
void section_canvas_plain(struct section_canvas *c, const uint8_t *rgb);

/* From now on one-pixel points are lit as bits under tables (a canvas
 * packed as it stands: section_lit_pixel() under image k's table for the
 * point's tile column), or, tables NULL, as bytes (a canvas read as
 * bytes: section_pixel()). The canvas must hold no lit bits. */
void section_canvas_lit(struct section_canvas *c, const struct brightness_tables *tables);

/* The first tile from t on that something touched (bytes, plain or lit
 * bits), or the tile count. */
uint32_t section_canvas_next(const struct section_canvas *c, uint32_t t);

/* Tile t's plain bits halftoned, ORed into out (a packed tile: the halftone
 * of its bytes, or zeros): ANDed with pattern, the halftone of the plain
 * colour under the tile's thresholds (rows y % 16, packed), in the rows
 * plain_rows[t] flags. Whether those rows of out have a bit set (the
 * caller knows whether its bytes lit any). The bits stay
 * (section_canvas_clear_tile()). */
bool section_canvas_pack_plain(const struct section_canvas *c, uint32_t t, const uint32_t pattern[3][16], uint8_t *out);

/* Tile t's lit bits into out (a packed tile): copied where fresh (out
 * not written yet), else ORed in. They stay
 * (section_canvas_clear_tile()). */
void section_canvas_pack_lit(const struct section_canvas *c, uint32_t t, uint8_t *out, bool fresh);

/* Tile t's plain bits MAXed into its bytes (rows[t] gains their rows), and
 * cleared: its bytes are then what section_span() would have written.
 * Before tile t's bytes are read (section_canvas_fold_tile() where it has
 * any). */
void section_canvas_fold(struct section_canvas *c, uint32_t t);
static inline void section_canvas_fold_tile(struct section_canvas *c, uint32_t t)
{
	if (c->plain_rows[t])
		section_canvas_fold(c, t);
}

/* Lights pixel (u, v) by per-channel MAX with rgb, without branches (a
 * compare-and-store mispredicts on points of random colours). */
static inline void section_pixel(struct section_canvas *c, uint32_t u, uint32_t v, const uint8_t rgb[3])
{
	uint32_t t = (v / VOLUME_TILE) * c->tiles_x + u / VOLUME_TILE;
	uint8_t *px = c->rgb + (size_t)t * HALFTONE_TILE_BYTES + (v % VOLUME_TILE) * HALFTONE_ROW_BYTES +
		      halftone_pos(u % VOLUME_TILE);
	for (int i = 0; i < 3; i++) {
		uint8_t was = px[i * HALFTONE_PLANE_BYTES];
		px[i * HALFTONE_PLANE_BYTES] = was > rgb[i] ? was : rgb[i];
	}
	c->rows[t] |= 1u << (v % VOLUME_TILE);
}

/* section_pixel() halftoned at once: pixel (u, v) of colour rgb as the
 * bits it lights under thr, its tile's thresholds, in the lit bits. */
static inline void section_lit_pixel(struct section_canvas *c, uint32_t u, uint32_t v, const uint8_t rgb[3],
				     const struct halftone_table *thr)
{
	uint32_t t = (v / VOLUME_TILE) * c->tiles_x + u / VOLUME_TILE, x = u % VOLUME_TILE, y = v % VOLUME_TILE;
	uint8_t level = thr->thr[y % 16][halftone_pos(x)];
	uint32_t bit = 1u << (x ^ 7);
	uint32_t r = -(uint32_t)(rgb[0] > level) & bit, g = -(uint32_t)(rgb[1] > level) & bit;
	uint32_t b = -(uint32_t)(rgb[2] > level) & bit;
	uint32_t *row = c->lit_bits + (size_t)t * SECTION_LIT_TILE + y;
	row[0] |= r;
	row[VOLUME_TILE] |= g;
	row[2 * VOLUME_TILE] |= b;
	c->lit_rows[t] |= (uint32_t)((r | g | b) != 0) << y;
}

/* Image k's tiles of a point mask (bits: bin.h's struct bin_point_mask
 * layout, tile t's rows at bits + VOLUME_TILE t) lit in colour rgb: what
 * section_lit_pixel() (or, on a canvas kept as bytes, section_pixel())
 * lights for each set bit, the lit bits through rgb's pattern under each
 * tile's table (halftone_pattern(), halftoned by fn, cached in p). */
void section_canvas_mask(struct section_canvas *c, uint32_t k, const uint32_t *bits, const uint8_t rgb[3],
			 struct halftone_patterns *p, halftone_fn fn);

/* A segment or triangle for section_lanes(): its vertices (x, y, z each,
 * in float as binned) and its colour. */
struct section_lane {
	const float *v;
	const uint8_t *rgb;
};

#define SECTION_BATCH 8

/* section_prim() of each of n (at most SECTION_BATCH) primitives of verts
 * vertices (2 or 3) in w's image, unmirrored, bit for bit the same canvas:
 * the common cases eight at a time where the CPU has AVX-512
 * (section_batch.c), the rest one by one. */
void section_lanes(struct section_canvas *c, const struct section_wedge *w, const struct section_lane *t, unsigned n,
		   int verts);
/* Whether section_lanes() has its eight-lane path on this CPU. */
bool section_batch_supported(void);

void section_wedge_init(struct section_wedge *w, const struct geometry *g, uint32_t k);

/* Lights columns u0..u1 of row v by per-channel MAX with rgb. */
void section_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1, const uint8_t rgb[3]);

/* Whether section_span() keeps spans of colour rgb as plain bits. */
static inline bool section_is_plain(const struct section_canvas *c, const uint8_t rgb[3])
{
	return c->plain && rgb[0] == c->plain_rgb[0] && rgb[1] == c->plain_rgb[1] && rgb[2] == c->plain_rgb[2];
}

/* section_span() of the plain colour: columns u0..u1 of row v as bits. */
static inline void section_plain_span(struct section_canvas *c, uint32_t v, uint32_t u0, uint32_t u1)
{
	uint32_t row = (v / VOLUME_TILE) * c->tiles_x, y = v % VOLUME_TILE;
	for (uint32_t u = u0; u <= u1;) {
		uint32_t t = row + u / VOLUME_TILE;
		uint32_t a = u % VOLUME_TILE, b = (u | 31) < u1 ? 31 : u1 % VOLUME_TILE;
		/* Pixels a..b at bits 31 - b .. 31 - a, bytes swapped: at
		 * bits x ^ 7. */
		uint32_t bits = (uint32_t)((2ull << (31 - a)) - (1ull << (31 - b)));
		c->plain_bits[(size_t)t * VOLUME_TILE + y] |= __builtin_bswap32(bits);
		c->plain_rows[t] |= 1u << y;
		u += b - a + 1;
	}
}

/* A span for section_weighted_runs(): columns u0..u1 of row v. */
struct section_run {
	uint32_t v, u0, u1;
};

/* The spans of one unmirrored piece of triangle or segment v (n vertices)
 * in w's image, whose s range is [lo, hi], lit as section_prim() lights
 * them where c's brightness model is active and v reaches its band
 * (brightness.h): the columns in the band weighted by v's weights, the
 * others plain (section_lanes()' lanes, section_batch.c). */
void section_weighted_runs(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			   const uint8_t rgb[3], double lo, double hi, const struct section_run *runs, unsigned count);

/* Sections a segment (n = 2) or triangle (n = 3), vertices in volume space
 * and finite, by both lobes of the wedge's image and lights what it touches,
 * clamped to the image. Degenerate primitives light their section too.
 * mirror: lights the mirror image of that instead (columns u0..u1 of a row
 * become W-1-u1..W-1-u0): a turned primitive (scene.h) shown mirrored. */
void section_prim_mirror(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
			 const uint8_t rgb[3], bool mirror);
/* section_prim_mirror(c, w, v, n, rgb, false). */
void section_prim(struct section_canvas *c, const struct section_wedge *w, const double (*v)[3], int n,
		  const uint8_t rgb[3]);

#endif
