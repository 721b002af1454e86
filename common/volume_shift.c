/* volume_shift(): a volume moved by whole pixels (calibration.h's axis
 * offset), tile by tile: each tile of the result takes its rows from at
 * most four tiles of the source, two across and two down. */
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>

#include "volume.h"

static inline uint32_t be32_load(const uint8_t *p)
{
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static inline void be32_store(uint8_t *p, uint32_t v)
{
	p[0] = (uint8_t)(v >> 24);
	p[1] = (uint8_t)(v >> 16);
	p[2] = (uint8_t)(v >> 8);
	p[3] = (uint8_t)v;
}

/* floor(a / VOLUME_TILE) for negative a too. */
static inline int64_t tile_of(int64_t a)
{
	return a >= 0 ? a / VOLUME_TILE : -((-a + VOLUME_TILE - 1) / VOLUME_TILE);
}

struct shift_image {
	const struct volume *src;
	const uint8_t **tile; /* per tile number: its bytes in the source, or NULL */
	int64_t du, dv;
};

/* The source tile at (tx, ty), or NULL: outside the image or not stored. */
static const uint8_t *source_tile(const struct shift_image *s, int64_t tx, int64_t ty)
{
	if (tx < 0 || ty < 0 || tx >= s->src->tiles_x || ty >= s->src->tiles_y)
		return NULL;
	return s->tile[ty * s->src->tiles_x + tx];
}

/* Fills out with tile (tx, ty) of the shifted image. Returns whether any
 * bit is set; false without writing when no source tile reaches it. */
static bool shift_tile(const struct shift_image *s, uint32_t tx, uint32_t ty, uint8_t *out)
{
	const struct geometry *g = &s->src->geom;
	int64_t sx = (int64_t)tx * VOLUME_TILE - s->du, sy = (int64_t)ty * VOLUME_TILE - s->dv;
	int64_t stx = tile_of(sx), sty = tile_of(sy);
	unsigned r = (unsigned)(sx - stx * VOLUME_TILE), ry = (unsigned)(sy - sty * VOLUME_TILE);
	/* [row][column]: the tiles the rows come from, top then bottom. */
	const uint8_t *src[2][2] = {
		{ source_tile(s, stx, sty), r ? source_tile(s, stx + 1, sty) : NULL },
		{ ry ? source_tile(s, stx, sty + 1) : NULL, r && ry ? source_tile(s, stx + 1, sty + 1) : NULL },
	};
	if (!src[0][0] && !src[0][1] && !src[1][0] && !src[1][1])
		return false;
	uint32_t x_end = g->width - tx * VOLUME_TILE, y_end = g->height - ty * VOLUME_TILE;
	uint32_t col_mask = x_end >= VOLUME_TILE ? UINT32_MAX : ~(UINT32_MAX >> x_end);
	uint32_t any = 0;
	for (unsigned c = 0; c < 3; c++)
		for (unsigned j = 0; j < VOLUME_TILE; j++) {
			unsigned row = ry + j, half = row >= VOLUME_TILE;
			size_t at = c * VOLUME_TILE_PLANE_BYTES + (row - half * VOLUME_TILE) * 4;
			const uint8_t *a = src[half][0], *b = src[half][1];
			uint32_t wa = a ? be32_load(a + at) : 0, wb = b ? be32_load(b + at) : 0;
			uint32_t w = r ? wa << r | wb >> (VOLUME_TILE - r) : wa;
			w = j < y_end ? w & col_mask : 0;
			be32_store(out + c * VOLUME_TILE_PLANE_BYTES + j * 4, w);
			any |= w;
		}
	return any != 0;
}

int volume_shift(struct volume *dst, const struct volume *src, int32_t du, int32_t dv)
{
	if (dst == src || dst->image_count != src->image_count || dst->tiles_x != src->tiles_x ||
	    dst->tiles_y != src->tiles_y || dst->geom.width != src->geom.width || dst->geom.height != src->geom.height)
		return -EINVAL;
	volume_clear(dst);
	uint32_t tiles = volume_tiles_per_image(src);
	struct shift_image s = { .src = src, .tile = malloc(tiles * sizeof(*s.tile)), .du = du, .dv = dv };
	if (!s.tile)
		return -ENOMEM;
	int r = 0;
	for (uint32_t k = 0; k < src->image_count && !r; k++) {
		const struct volume_image *img = &src->images[k];
		const uint8_t *next = img->tiles;
		for (uint32_t t = 0; t < tiles; t++) {
			s.tile[t] = volume_tile_present(img, t) ? next : NULL;
			next += s.tile[t] ? VOLUME_TILE_BYTES : 0;
		}
		for (uint32_t ty = 0; ty < src->tiles_y && !r; ty++)
			for (uint32_t tx = 0; tx < src->tiles_x && !r; tx++) {
				uint8_t *out = volume_image_next(dst, k);
				if (!out)
					r = -ENOMEM;
				else if (shift_tile(&s, tx, ty, out))
					r = volume_image_push(dst, k, ty * src->tiles_x + tx);
			}
	}
	free(s.tile);
	dst->seq = src->seq;
	dst->shown_ns = src->shown_ns;
	return r;
}
