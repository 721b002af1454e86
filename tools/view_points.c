#include "view_points.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

/* Row r of a tile: the pixels lit in any channel (bit 31 the leftmost),
 * and each channel's. */
static inline uint32_t row_bits(const uint8_t *tile, int c, int r)
{
	const uint8_t *p = tile + c * VOLUME_TILE_PLANE_BYTES + r * 4;
	return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

static uint64_t count_lit(const struct volume *vol)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const struct volume_image *img = &vol->images[k];
		for (uint32_t i = 0; i < img->tile_count; i++) {
			const uint8_t *tile = img->tiles + (size_t)i * VOLUME_TILE_BYTES;
			for (int r = 0; r < VOLUME_TILE; r++)
				n += (uint64_t)__builtin_popcount(
					row_bits(tile, 0, r) | row_bits(tile, 1, r) | row_bits(tile, 2, r));
		}
	}
	return n;
}

/* Room in pts for want points. 0 or -ENOMEM. */
static int reserve_points(struct view_points *pts, size_t want)
{
	if (want > pts->cap) {
		struct view_point *p = realloc(pts->p, want * sizeof(*p));
		if (!p)
			return -ENOMEM;
		pts->p = p;
		pts->cap = want;
	}
	return 0;
}

/* Adds the points of image k: every stride-th lit voxel, counting on from
 * seen (the lit voxels of the images before). Returns seen, counted on. */
static uint64_t image_points(struct view_points *pts, const struct volume *vol, uint32_t k, uint32_t stride,
			     uint64_t seen)
{
	const struct geometry *g = &vol->geom;
	const float h = g->half_height, W = (float)g->width, H = (float)g->height;
	const struct volume_image *img = &vol->images[k];
	double theta = 2.0 * M_PI * k / g->images_per_rev;
	float ck = (float)cos(theta), sk = (float)sin(theta);
	uint32_t i = 0;
	for (uint32_t t = 0; t < vol->mask_bytes * 8 && i < img->tile_count; t++) {
		if (!volume_tile_present(img, t))
			continue;
		const uint8_t *tile = img->tiles + (size_t)i++ * VOLUME_TILE_BYTES;
		uint32_t x0 = (t % vol->tiles_x) * VOLUME_TILE, y0 = (t / vol->tiles_x) * VOLUME_TILE;
		for (int r = 0; r < VOLUME_TILE; r++) {
			uint32_t rb = row_bits(tile, 0, r), gb = row_bits(tile, 1, r), bb = row_bits(tile, 2, r);
			uint32_t any = rb | gb | bb;
			float y = h - ((float)(y0 + r) + 0.5f) / H * 2.0f * h;
			while (any) {
				int b = __builtin_clz(any);
				uint32_t bit = 0x80000000u >> b;
				any &= ~bit;
				if (seen++ % stride)
					continue;
				float s = ((float)(x0 + (uint32_t)b) + 0.5f) / W * 2.0f - 1.0f;
				struct view_point *p = &pts->p[pts->count++];
				p->x = s * ck;
				p->y = y;
				p->z = s * sk;
				p->rgba[0] = rb & bit ? 255 : 0;
				p->rgba[1] = gb & bit ? 255 : 0;
				p->rgba[2] = bb & bit ? 255 : 0;
				p->rgba[3] = 255;
			}
		}
	}
	return seen;
}

int view_points_from_volume(struct view_points *pts, const struct volume *vol, size_t max_points)
{
	const struct geometry *g = &vol->geom;
	uint64_t lit = count_lit(vol);
	uint32_t stride = 1;
	if (max_points && lit > max_points)
		stride = (uint32_t)((lit + max_points - 1) / max_points);
	size_t want = (size_t)((lit + stride - 1) / stride);
	if (reserve_points(pts, want) < 0)
		return -ENOMEM;
	pts->count = 0;
	pts->lit = lit;
	pts->stride = stride;
	pts->half_height = g->half_height;
	pts->seq = vol->seq;
	uint64_t seen = 0;
	for (uint32_t k = 0; k < vol->image_count; k++)
		seen = image_points(pts, vol, k, stride, seen);
	return 0;
}

void view_points_free(struct view_points *pts)
{
	free(pts->p);
	*pts = (struct view_points){ 0 };
}
