/* The ordered dither of docs/design.md section 3 (the threshold of a pixel in an
 * image), and halftone + pack of one canvas tile: 8-bit RGB in, 1 bit per
 * channel out, in several bit-identical variants chosen at run time by what
 * the CPU supports.
 *
 * Canvas tile layout: planes R, G, B, each 32 rows of 32 bytes. Pixel x
 * (0..31) of a row is stored at byte halftone_pos(x) = x ^ 7, i.e. reversed
 * inside each group of 8, so that one SIMD byte-compare and one byte-mask
 * movement give the packed row (4 bytes, MSB = leftmost pixel) directly.
 * Output: the packed tile of volume.h (planes R, G, B of 32 rows of 4
 * bytes). */
#ifndef SPINDLE_HALFTONE_H
#define SPINDLE_HALFTONE_H

#include <stdint.h>

#define HALFTONE_ROW_BYTES 32
#define HALFTONE_PLANE_BYTES (32 * HALFTONE_ROW_BYTES) /* 1024 */
#define HALFTONE_TILE_BYTES (3 * HALFTONE_PLANE_BYTES) /* 3072 */

static inline uint32_t halftone_pos(uint32_t x)
{
	return x ^ 7u;
}

/* The ordered-dither threshold (0..254) of pixel (u, v) in image k: a pixel
 * of channel value c is lit iff c > threshold. 0 is never lit, 255 always. */
uint8_t halftone_threshold(uint32_t k, uint32_t u, uint32_t v);

/* Image k's thresholds for tile rows y % 16, in canvas byte order (the
 * 16-periodic matrix repeated to 32 columns). A pixel of value c is lit
 * iff c > threshold. */
struct halftone_table {
	uint8_t thr[16][HALFTONE_ROW_BYTES];
};

void halftone_table_init(struct halftone_table *t, uint32_t k);

/* Halftones the rows of canvas (a tile in the layout above) whose bit is set
 * in rows (bit y = row y, in every plane); rows not set are zero in the
 * canvas and come out zero. Writes all VOLUME_TILE_BYTES of out. Returns
 * nonzero iff some output bit is set. */
typedef int (*halftone_fn)(const uint8_t *canvas, uint32_t rows, const struct halftone_table *t, uint8_t *out);

struct halftone_variant {
	const char *name;
	halftone_fn fn;
};

/* The halftone of one colour under the last few tables asked for: what a
 * tile of that colour in every row packs to, rows y % 16 (a table's
 * period), each plane's rows as in volume.h. A thread's own. */
#define HALFTONE_PATTERNS 4
struct halftone_patterns {
	unsigned next;
	struct halftone_pattern {
		const struct halftone_table *thr; /* NULL: unused */
		uint8_t rgb[3];
		uint32_t bits[3][16];
	} pattern[HALFTONE_PATTERNS];
};

/* rgb's pattern under thr, halftoned by fn the first time it is asked
 * for (the oldest of p's patterns then gives way). */
const struct halftone_pattern *halftone_pattern(struct halftone_patterns *p, const uint8_t rgb[3],
						const struct halftone_table *thr, halftone_fn fn);

/* The variants this CPU can run, best first, ending with "scalar" and then
 * an entry whose name is NULL. */
const struct halftone_variant *halftone_variants(void);

/* The variant called name (NULL or "auto": the best), or NULL if unknown or
 * not runnable here. */
halftone_fn halftone_pick(const char *name);

/* The slow, obvious way, for the naive GL pipeline: halftones and packs a
 * whole W x H RGBA8 image (row 0 first, 4 bytes a pixel, alpha ignored)
 * into image k of vol, pixel by pixel, appending its non-empty tiles.
 * Returns 0 or -ENOMEM. */
struct volume;
int halftone_rgba_image(struct volume *vol, uint32_t k, const uint8_t *rgba);

/* The same against another threshold (a brightness model's, brightness.h):
 * threshold(ctx, k, u, v). */
typedef uint8_t (*halftone_threshold_fn)(const void *ctx, uint32_t k, uint32_t u, uint32_t v);
int halftone_rgba_with(struct volume *vol, uint32_t k, const uint8_t *rgba, halftone_threshold_fn threshold,
		       const void *ctx);

#endif
