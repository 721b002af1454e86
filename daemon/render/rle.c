/* The run-length coded form of volumes and canvases (rle.h). */
#include "rle.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "volume.h"

#define MAX_LITERAL 128
#define MAX_ZEROS 128

/* Codes one tile of size bytes into out (room for size + size /
 * MAX_LITERAL + 1); returns the bytes written. */
static size_t encode_tile(const uint8_t *tile, size_t size, uint8_t *out)
{
	size_t o = 0, i = 0;
	while (i < size) {
		size_t n = 0;
		/* Zeros 8 at a time first: most of a tile is zero. */
		for (uint64_t word; i + n + 8 <= size && n + 8 <= MAX_ZEROS; n += 8) {
			memcpy(&word, tile + i + n, sizeof(word));
			if (word)
				break;
		}
		while (i + n < size && tile[i + n] == 0 && n < MAX_ZEROS)
			n++;
		if (n > 0) {
			out[o++] = (uint8_t)(127 + n);
			i += n;
			continue;
		}
		/* Literals up to the next pair of zeros (a lone zero is cheaper
		 * kept literal than coded). */
		while (i + n < size && n < MAX_LITERAL &&
		       !(tile[i + n] == 0 && (i + n + 1 == size || tile[i + n + 1] == 0)))
			n++;
		out[o++] = (uint8_t)(n - 1);
		memcpy(out + o, tile + i, n);
		o += n;
		i += n;
	}
	return o;
}

size_t rle_or_coded(const uint8_t *in, size_t avail, uint8_t *dst, size_t size)
{
	size_t o = 0, i = 0;
	while (o < size) {
		if (i >= avail)
			return 0;
		uint8_t c = in[i++];
		if (c >= 128) {
			o += (size_t)c - 127;
			continue;
		}
		size_t n = (size_t)c + 1;
		if (i + n > avail || o + n > size)
			return 0;
		for (size_t j = 0; j < n; j++)
			dst[o + j] |= in[i + j];
		i += n;
		o += n;
	}
	return o == size ? i : 0;
}

struct rle_volume *rle_volume_new(uint32_t image_count, uint32_t mask_bytes, uint32_t tiles_per_image,
				  uint32_t tile_bytes)
{
	struct rle_volume *r = calloc(1, sizeof(*r));
	if (!r)
		return NULL;
	r->image_count = image_count;
	r->mask_bytes = mask_bytes;
	r->tiles_per_image = tiles_per_image;
	r->tile_bytes = tile_bytes;
	r->images = calloc(image_count, sizeof(*r->images));
	if (!r->images) {
		free(r);
		return NULL;
	}
	return r;
}

/* The bytes of a non-empty mask between which its set bits lie. */
static struct rle_span mask_span(const uint8_t *mask, uint32_t bytes)
{
	uint32_t first = 0, last = bytes - 1;
	while (first < last && !mask[first])
		first++;
	while (last > first && !mask[last])
		last--;
	return (struct rle_span){ first, last };
}

int rle_volume_set_image(struct rle_volume *r, uint32_t k, const uint8_t *mask, const uint8_t *tiles, uint32_t count,
			 struct rle_scratch *s)
{
	struct rle_image *img = &r->images[k];
	free(img->data);
	*img = (struct rle_image){ 0 };
	if (!count)
		return 0;
	size_t head = r->mask_bytes + (size_t)count * sizeof(uint32_t);
	size_t need = head + (size_t)count * (r->tile_bytes + r->tile_bytes / MAX_LITERAL + 1);
	if (need > s->cap) {
		uint8_t *t = realloc(s->buf, need);
		if (!t)
			return -ENOMEM;
		s->buf = t;
		s->cap = need;
	}
	memcpy(s->buf, mask, r->mask_bytes);
	size_t len = head;
	for (uint32_t i = 0; i < count; i++) {
		uint32_t off = (uint32_t)(len - head);
		memcpy(s->buf + r->mask_bytes + i * sizeof(uint32_t), &off, sizeof(off));
		len += encode_tile(tiles + (size_t)i * r->tile_bytes, r->tile_bytes, s->buf + len);
	}
	uint8_t *data = malloc(len);
	if (!data)
		return -ENOMEM;
	memcpy(data, s->buf, len);
	*img = (struct rle_image){ .tile_count = count,
				   .len = (uint32_t)len,
				   .data = data,
				   .span = mask_span(mask, r->mask_bytes) };
	return 0;
}

void rle_volume_sum(struct rle_volume *r)
{
	r->tiles = 0;
	r->bytes = sizeof(*r) + r->image_count * sizeof(*r->images);
	r->lit_count = 0;
	for (uint32_t k = 0; k < r->image_count; k++) {
		r->tiles += r->images[k].tile_count;
		r->bytes += r->images[k].len;
		r->lit_count += r->images[k].tile_count > 0;
	}
	r->packed_bytes = r->tiles * r->tile_bytes;
	free(r->lit);
	r->lit = malloc((r->lit_count ? r->lit_count : 1) * sizeof(*r->lit));
	if (!r->lit) /* patching then looks at every image */
		return;
	uint32_t n = 0;
	for (uint32_t k = 0; k < r->image_count; k++)
		if (r->images[k].tile_count)
			r->lit[n++] = k;
	r->bytes += r->lit_count * sizeof(*r->lit);
}

struct rle_volume *rle_volume_encode(const struct volume *vol)
{
	struct rle_volume *r =
		rle_volume_new(vol->image_count, vol->mask_bytes, volume_tiles_per_image(vol), VOLUME_TILE_BYTES);
	if (!r)
		return NULL;
	struct rle_scratch s = { 0 };
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const struct volume_image *img = &vol->images[k];
		if (rle_volume_set_image(r, k, img->mask, img->tiles, img->tile_count, &s) < 0) {
			free(s.buf);
			rle_volume_free(r);
			errno = ENOMEM;
			return NULL;
		}
	}
	free(s.buf);
	rle_volume_sum(r);
	return r;
}

void rle_volume_free(struct rle_volume *r)
{
	if (!r)
		return;
	for (uint32_t k = 0; r->images && k < r->image_count; k++)
		free(r->images[k].data);
	free(r->images);
	free(r->lit);
	free(r);
}

int rle_canvas_each(const struct rle_volume *r, uint32_t k, canvas_tile_fn fn, void *arg)
{
	const struct rle_image *img = &r->images[k];
	if (!img->tile_count)
		return 0;
	size_t head = r->mask_bytes + (size_t)img->tile_count * sizeof(uint32_t);
	size_t avail = img->len - head;
	const uint8_t *code = img->data + head;
	uint8_t buf[CANVAS_TILE_BYTES];
	for (uint32_t t = 0; t < r->tiles_per_image; t++) {
		if (!((img->data[t / 8] >> (t % 8)) & 1))
			continue;
		memset(buf, 0, sizeof(buf));
		size_t used = rle_or_coded(code, avail, buf, CANVAS_TILE_BYTES);
		if (!used)
			return -EINVAL;
		fn(arg, t, buf);
		code += used;
		avail -= used;
	}
	return 0;
}
