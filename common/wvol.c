#include "wvol.h"

#include <errno.h>
#include <string.h>

#include "le.h"

static uint32_t padded_mask(uint32_t mask_bytes)
{
	return (mask_bytes + 3) & ~3u;
}

uint64_t wvol_size(const struct volume *vol)
{
	uint64_t per_image = 4 + padded_mask(vol->mask_bytes);
	return WVOL_HEADER_SIZE + vol->image_count * per_image + volume_tile_count(vol) * VOLUME_TILE_BYTES;
}

void wvol_encode(const struct volume *vol, uint8_t *out)
{
	uint32_t hh;
	memset(out, 0, WVOL_HEADER_SIZE);
	memcpy(out, "SPWV", 4);
	out[4] = WVOL_VERSION;
	out[6] = WVOL_HEADER_SIZE;
	le_put32(out + 8, vol->geom.width);
	le_put32(out + 12, vol->geom.height);
	le_put32(out + 16, vol->image_count);
	le_put32(out + 20, vol->geom.images_per_rev);
	out[24] = 3;
	out[25] = vol->geom.mirrored ? WVOL_FLAG_MIRRORED : 0;
	memcpy(&hh, &vol->geom.half_height, 4);
	le_put32(out + 28, hh);
	le_put64(out + 32, vol->seq);
	le_put64(out + 40, vol->shown_ns);
	le_put32(out + 48, vol->tiles_x);
	le_put32(out + 52, vol->tiles_y);
	le_put32(out + 56, vol->mask_bytes);
	le_put32(out + 60, (uint32_t)volume_tile_count(vol));
	uint8_t *p = out + WVOL_HEADER_SIZE;
	uint32_t mask = padded_mask(vol->mask_bytes);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const struct volume_image *img = &vol->images[k];
		le_put32(p, img->tile_count);
		memset(p + 4, 0, mask);
		memcpy(p + 4, img->mask, vol->mask_bytes);
		p += 4 + mask;
		size_t n = (size_t)img->tile_count * VOLUME_TILE_BYTES;
		if (n)
			memcpy(p, img->tiles, n);
		p += n;
	}
}

int wvol_is(const uint8_t *buf, size_t size)
{
	return size >= WVOL_HEADER_SIZE && memcmp(buf, "SPWV", 4) == 0;
}

/* Image k from *p (before end): its tile count, mask and tiles, checked
 * against each other; *p moves past them. 0, -EINVAL or -ENOMEM. */
static int decode_image(struct volume *vol, uint32_t k, const uint8_t **pp, const uint8_t *end)
{
	uint32_t per_image = volume_tiles_per_image(vol), mask = padded_mask(vol->mask_bytes);
	const uint8_t *p = *pp;
	if ((size_t)(end - p) < 4 + (size_t)mask)
		return -EINVAL;
	uint32_t count = le_get32(p);
	const uint8_t *m = p + 4;
	if (volume_mask_count(m, vol->mask_bytes) != count || (size_t)(end - p - 4 - mask) / VOLUME_TILE_BYTES < count)
		return -EINVAL;
	p += 4 + mask;
	if (count && volume_image_reserve(vol, k, count) < 0)
		return -ENOMEM;
	for (uint32_t t = 0; t < vol->mask_bytes * 8 && count; t++) {
		if (!((m[t / 8] >> (t % 8)) & 1))
			continue;
		if (t >= per_image || volume_image_append(vol, k, t, p) < 0)
			return -EINVAL;
		p += VOLUME_TILE_BYTES;
	}
	*pp = p;
	return 0;
}

/* The geometry a watch volume's header gives, where the header is one
 * this version reads and the geometry valid. */
static bool header_geometry(const uint8_t *buf, size_t size, struct geometry *g)
{
	if (!wvol_is(buf, size) || buf[4] != WVOL_VERSION || buf[5] || buf[6] != WVOL_HEADER_SIZE || buf[7] ||
	    buf[24] != 3)
		return false;
	*g = (struct geometry){
		.width = le_get32(buf + 8),
		.height = le_get32(buf + 12),
		.images_per_rev = le_get32(buf + 20),
		.mirrored = buf[25] & WVOL_FLAG_MIRRORED,
		.rpm = 60.0f, /* not stored */
	};
	uint32_t hh = le_get32(buf + 28);
	memcpy(&g->half_height, &hh, 4);
	return geometry_validate(g) == 0 && le_get32(buf + 16) == geometry_images_per_volume(g);
}

struct volume *wvol_decode(const uint8_t *buf, size_t size)
{
	struct geometry g;
	if (!header_geometry(buf, size, &g)) {
		errno = EINVAL;
		return NULL;
	}
	struct volume *vol = volume_create(&g);
	if (!vol)
		return NULL;
	if (le_get32(buf + 48) != vol->tiles_x || le_get32(buf + 52) != vol->tiles_y ||
	    le_get32(buf + 56) != vol->mask_bytes)
		goto invalid;
	vol->seq = le_get64(buf + 32);
	vol->shown_ns = le_get64(buf + 40);
	const uint8_t *p = buf + WVOL_HEADER_SIZE, *end = buf + size;
	uint64_t total = 0;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		int r = decode_image(vol, k, &p, end);
		if (r == -ENOMEM) {
			volume_destroy(vol);
			errno = ENOMEM;
			return NULL;
		}
		if (r < 0)
			goto invalid;
		total += vol->images[k].tile_count;
	}
	if (p != end || total != le_get32(buf + 60))
		goto invalid;
	return vol;
invalid:
	volume_destroy(vol);
	errno = EINVAL;
	return NULL;
}
