#include "testvol.h"

#include <math.h>
#include <string.h>

struct testvol *testvol_create(const struct geometry *geom)
{
	struct testvol *tv = calloc(1, sizeof(*tv));
	CHECK(tv);
	tv->geom = *geom;
	tv->images = geometry_images_per_volume(geom);
	tv->bits = calloc((size_t)tv->images * geom->width * geom->height, 1);
	CHECK(tv->bits);
	return tv;
}

void testvol_destroy(struct testvol *tv)
{
	if (!tv)
		return;
	free(tv->bits);
	free(tv);
}

void testvol_set(struct testvol *tv, uint32_t k, uint32_t u, uint32_t v, unsigned rgb_bits)
{
	CHECK(k < tv->images && u < tv->geom.width && v < tv->geom.height);
	tv->bits[((size_t)k * tv->geom.height + v) * tv->geom.width + u] |= (uint8_t)rgb_bits;
}

void testvol_light_point(struct testvol *tv, const double p[3], unsigned rgb_bits)
{
	uint32_t k = geometry_image_of_azimuth(&tv->geom, atan2(p[2], p[0])) % tv->images;
	double theta = geometry_image_angle(&tv->geom, k);
	double s = p[0] * cos(theta) + p[2] * sin(theta);
	testvol_set(tv, k, geometry_column(&tv->geom, s), geometry_row(&tv->geom, p[1]), rgb_bits);
}

/* Packs the 32x32 tile (tx, ty) of image k; returns whether any bit is set. */
static int pack_tile(const struct testvol *tv, uint32_t k, uint32_t tx, uint32_t ty, uint8_t *tile)
{
	int any = 0;
	memset(tile, 0, VOLUME_TILE_BYTES);
	for (uint32_t r = 0; r < VOLUME_TILE; r++) {
		uint32_t v = ty * VOLUME_TILE + r;
		for (uint32_t x = 0; x < VOLUME_TILE && v < tv->geom.height; x++) {
			uint32_t u = tx * VOLUME_TILE + x;
			if (u >= tv->geom.width)
				break;
			uint8_t b = tv->bits[((size_t)k * tv->geom.height + v) * tv->geom.width + u];
			for (int c = 0; c < 3; c++) {
				if (b & (1u << c)) {
					tile[c * VOLUME_TILE_PLANE_BYTES + r * 4 + x / 8] |= (uint8_t)(0x80 >> (x % 8));
					any = 1;
				}
			}
		}
	}
	return any;
}

struct volume *testvol_to_volume(const struct testvol *tv)
{
	struct volume *vol = volume_create(&tv->geom);
	uint8_t tile[VOLUME_TILE_BYTES];
	CHECK(vol);
	for (uint32_t k = 0; k < tv->images; k++) {
		for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
			if (pack_tile(tv, k, t % vol->tiles_x, t / vol->tiles_x, tile))
				CHECK(volume_image_append(vol, k, t, tile) == 0);
		}
	}
	return vol;
}
