#include "svol.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "le.h"

void svol_header_encode(const struct svol_header *h, uint8_t out[SVOL_HEADER_SIZE])
{
	uint32_t hh;
	memset(out, 0, SVOL_HEADER_SIZE);
	memcpy(out, "SVOL", 4);
	out[4] = SVOL_VERSION;
	out[6] = SVOL_HEADER_SIZE;
	le_put32(out + 8, h->width);
	le_put32(out + 12, h->height);
	le_put32(out + 16, h->image_count);
	le_put32(out + 20, h->images_per_rev);
	out[24] = 3;
	out[25] = h->flags;
	memcpy(&hh, &h->half_height, 4);
	le_put32(out + 28, hh);
	le_put64(out + 32, h->seq);
	le_put64(out + 40, h->shown_ns);
}

int svol_header_decode(const uint8_t in[SVOL_HEADER_SIZE], struct svol_header *h)
{
	if (memcmp(in, "SVOL", 4) != 0 || in[4] != SVOL_VERSION || in[5] != 0 || in[6] != SVOL_HEADER_SIZE ||
	    in[7] != 0 || in[24] != 3)
		return -EINVAL;
	uint32_t hh = le_get32(in + 28);
	h->width = le_get32(in + 8);
	h->height = le_get32(in + 12);
	h->image_count = le_get32(in + 16);
	h->images_per_rev = le_get32(in + 20);
	h->planes = in[24];
	h->flags = in[25];
	memcpy(&h->half_height, &hh, 4);
	h->seq = le_get64(in + 32);
	h->shown_ns = le_get64(in + 40);
	uint32_t expect = (h->flags & SVOL_FLAG_MIRRORED) ? h->images_per_rev / 2 : h->images_per_rev;
	if (h->image_count != expect)
		return -EINVAL;
	return 0;
}

uint64_t svol_file_size(const struct svol_header *h)
{
	return SVOL_HEADER_SIZE + (uint64_t)h->image_count * 3 * h->height * ((h->width + 7) / 8);
}

static struct svol_header header_of(const struct volume *vol)
{
	return (struct svol_header){
		.width = vol->geom.width,
		.height = vol->geom.height,
		.image_count = vol->image_count,
		.images_per_rev = vol->geom.images_per_rev,
		.planes = 3,
		.flags = vol->geom.mirrored ? SVOL_FLAG_MIRRORED : 0,
		.half_height = vol->geom.half_height,
		.seq = vol->seq,
		.shown_ns = vol->shown_ns,
	};
}

uint64_t svol_size(const struct volume *vol)
{
	struct svol_header h = header_of(vol);
	return svol_file_size(&h);
}

void svol_encode(const struct volume *vol, uint8_t *out)
{
	struct svol_header h = header_of(vol);
	svol_header_encode(&h, out);
	out += SVOL_HEADER_SIZE;
	for (uint32_t k = 0; k < vol->image_count; k++, out += volume_dense_image_bytes(vol))
		volume_image_to_dense(vol, k, out);
}

int svol_write(FILE *f, const struct volume *vol)
{
	struct svol_header h = header_of(vol);
	uint8_t hdr[SVOL_HEADER_SIZE];
	svol_header_encode(&h, hdr);
	if (fwrite(hdr, 1, sizeof(hdr), f) != sizeof(hdr))
		return -EIO;
	size_t n = volume_dense_image_bytes(vol);
	uint8_t *buf = malloc(n);
	if (!buf)
		return -ENOMEM;
	int r = 0;
	for (uint32_t k = 0; k < vol->image_count && r == 0; k++) {
		volume_image_to_dense(vol, k, buf);
		if (fwrite(buf, 1, n, f) != n)
			r = -EIO;
	}
	free(buf);
	return r;
}

/* Cuts dense image data back into tiles. */
static int image_from_dense(struct volume *vol, uint32_t k, const uint8_t *dense)
{
	uint32_t rb = geometry_row_bytes(&vol->geom), h = vol->geom.height;
	size_t plane = (size_t)h * rb;
	uint8_t tile[VOLUME_TILE_BYTES];
	for (uint32_t t = 0; t < volume_tiles_per_image(vol); t++) {
		uint32_t x0 = (t % vol->tiles_x) * VOLUME_TILE, y0 = (t / vol->tiles_x) * VOLUME_TILE;
		uint32_t n = rb - x0 / 8 < 4 ? rb - x0 / 8 : 4;
		memset(tile, 0, sizeof(tile));
		for (int c = 0; c < 3; c++)
			for (uint32_t r = 0; r < VOLUME_TILE && y0 + r < h; r++)
				memcpy(tile + c * VOLUME_TILE_PLANE_BYTES + r * 4,
				       dense + c * plane + (size_t)(y0 + r) * rb + x0 / 8, n);
		int ret = volume_image_append(vol, k, t, tile);
		if (ret < 0)
			return ret;
	}
	return 0;
}

struct volume *svol_read(FILE *f)
{
	uint8_t hdr[SVOL_HEADER_SIZE];
	struct svol_header h;
	if (fread(hdr, 1, sizeof(hdr), f) != sizeof(hdr) || svol_header_decode(hdr, &h) < 0) {
		errno = EINVAL;
		return NULL;
	}
	struct geometry g = {
		.width = h.width,
		.height = h.height,
		.images_per_rev = h.images_per_rev,
		.mirrored = (h.flags & SVOL_FLAG_MIRRORED) != 0,
		.half_height = h.half_height,
		.rpm = 60.0f, /* not stored in the file */
	};
	struct volume *vol = volume_create(&g);
	if (!vol)
		return NULL;
	vol->seq = h.seq;
	vol->shown_ns = h.shown_ns;
	size_t n = volume_dense_image_bytes(vol);
	uint8_t *buf = malloc(n);
	int r = buf ? 0 : -ENOMEM;
	for (uint32_t k = 0; k < vol->image_count && r == 0; k++) {
		if (fread(buf, 1, n, f) != n)
			r = -EINVAL;
		else
			r = image_from_dense(vol, k, buf);
	}
	free(buf);
	if (r < 0) {
		volume_destroy(vol);
		errno = -r;
		return NULL;
	}
	return vol;
}
