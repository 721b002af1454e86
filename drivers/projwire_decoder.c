/* The device side of the bulk OUT stream: an incremental, strict decoder.
 *
 * Bytes arrive split anywhere (USB bulk transfers). Each record is checked
 * as soon as enough of it is in: the header before any payload is taken,
 * the image head and mask before any tile. Tiles stream straight into the
 * buffer's volume, which stays invalid until VOLUME_END's CRC matches, so a
 * volume is never shown half-written or corrupted. After any error the
 * decoder drops bytes until it sees a VOLUME_BEGIN or DELTA_BEGIN header
 * again.
 *
 * A delta volume (1.1) edits the buffer's volume in place, one image at a
 * time: the image's old tiles and the record's changed ones are merged, in
 * tile order, into a scratch image that is then exchanged with it. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "le.h"
#include "projwire.h"

enum dec_state {
	DEC_HEADER, /* collecting a record header */
	DEC_HEAD,   /* collecting a fixed payload, or an image head + mask */
	DEC_TILES,  /* collecting an image's tiles */
	DEC_SYNC,   /* after an error: looking for a VOLUME_BEGIN header */
};

struct projwire_decoder {
	const struct projwire_sink *sink;
	void *data;
	struct geometry geom;
	uint32_t buffers, max_record;
	uint32_t image_count, tiles_x, tiles_per_image, mask_bytes;

	enum dec_state state;
	uint8_t hdr[PROJWIRE_HEADER_SIZE];
	size_t hdr_fill;
	uint8_t type;
	uint32_t length;
	uint8_t *head; /* fixed payloads and image head + mask */
	size_t head_need, head_fill;
	uint8_t tile[VOLUME_TILE_BYTES];
	size_t tile_fill;

	/* The volume being written. */
	struct volume *vol;
	bool delta;
	struct volume *scratch;        /* a delta's merged image (image 0), made on first use */
	uint32_t base_next, base_tile; /* merge cursors: tile number, stored index */
	uint32_t buffer;
	uint32_t crc, images;
	int64_t image; /* index of the current or last image, -1 before any */
	uint32_t next_bit, tiles_left;

	struct projwire_decoder_stats stats;
	int first_err;
};

struct projwire_decoder *projwire_decoder_create(const struct geometry *geom, uint32_t buffers, uint32_t max_record,
						 const struct projwire_sink *sink, void *data)
{
	if (geometry_validate(geom) < 0 || buffers < 1 || buffers > PROJWIRE_MAX_BUFFERS) {
		errno = EINVAL;
		return NULL;
	}
	struct projwire_decoder *d = calloc(1, sizeof(*d));
	if (!d)
		return NULL;
	d->sink = sink;
	d->data = data;
	d->geom = *geom;
	d->buffers = buffers;
	d->image_count = geometry_images_per_volume(geom);
	d->tiles_x = volume_tiles_across(geom->width);
	d->tiles_per_image = d->tiles_x * volume_tiles_across(geom->height);
	d->mask_bytes = (d->tiles_per_image + 7) / 8;
	uint32_t need = projwire_max_image_payload(geom);
	d->max_record = max_record && max_record < need ? max_record : need;
	d->head = malloc(PROJWIRE_IMAGE_HEAD + d->mask_bytes + 16);
	if (!d->head) {
		free(d);
		errno = ENOMEM;
		return NULL;
	}
	d->image = -1;
	return d;
}

void projwire_decoder_destroy(struct projwire_decoder *d)
{
	if (!d)
		return;
	free(d->head);
	volume_destroy(d->scratch);
	free(d);
}

void projwire_decoder_get_stats(const struct projwire_decoder *d, struct projwire_decoder_stats *out)
{
	*out = d->stats;
}

static void close_volume(struct projwire_decoder *d, int err)
{
	if (!d->vol)
		return;
	d->vol = NULL;
	if (!err)
		d->stats.volumes++;
	d->sink->end(d->data, d->buffer, err);
}

/* Rejects what came so far. notify: tell the sink (a refused BEGIN was
 * already answered by the sink itself). */
static void fail(struct projwire_decoder *d, int err, bool notify)
{
	d->stats.errors++;
	if (!d->first_err)
		d->first_err = err;
	if (d->vol)
		close_volume(d, err);
	else if (notify)
		d->sink->end(d->data, PROJWIRE_NO_BUFFER, err);
	d->state = DEC_SYNC;
	d->hdr_fill = 0;
}

static void expect_header(struct projwire_decoder *d)
{
	d->state = DEC_HEADER;
	d->hdr_fill = 0;
	d->stats.records++;
}

/* Checks a complete header; returns 0 or the error that rejects it. */
static int header_check(struct projwire_decoder *d)
{
	const uint8_t *h = d->hdr;
	if (h[0] != PROJWIRE_MAGIC0 || h[1] != PROJWIRE_MAGIC1 || h[3] != 0)
		return -EPROTO;
	d->type = h[2];
	d->length = le_get32(h + 4);
	uint32_t fixed = PROJWIRE_IMAGE_HEAD + d->mask_bytes;
	switch (d->type) {
	case PROJWIRE_VOLUME_BEGIN:
		return d->length == PROJWIRE_BEGIN_SIZE - PROJWIRE_HEADER_SIZE ? 0 : -EPROTO;
	case PROJWIRE_DELTA_BEGIN:
		return d->length == PROJWIRE_DELTA_BEGIN_SIZE - PROJWIRE_HEADER_SIZE ? 0 : -EPROTO;
	case PROJWIRE_VOLUME_END:
		if (!d->vol)
			return -EPROTO;
		return d->length == PROJWIRE_END_SIZE - PROJWIRE_HEADER_SIZE ? 0 : -EPROTO;
	case PROJWIRE_IMAGE:
	case PROJWIRE_IMAGE_DELTA:
		/* Each kind of image only in its kind of volume. */
		if (!d->vol || d->delta != (d->type == PROJWIRE_IMAGE_DELTA) || d->length < fixed ||
		    d->length > d->max_record || (d->length - fixed) % VOLUME_TILE_BYTES)
			return -EPROTO;
		return 0;
	default:
		return -EPROTO;
	}
}

static void header_done(struct projwire_decoder *d)
{
	int err = header_check(d);
	if (err < 0) {
		/* Keep scanning from the byte after this header's first. */
		fail(d, err, true);
		d->hdr_fill = PROJWIRE_HEADER_SIZE;
		return;
	}
	if (d->type == PROJWIRE_VOLUME_BEGIN || d->type == PROJWIRE_DELTA_BEGIN) {
		if (d->vol)
			fail(d, -ECANCELED, true); /* abandon the open volume */
		d->crc = 0;
	}
	if (d->type != PROJWIRE_VOLUME_END)
		d->crc = projwire_crc32(d->crc, d->hdr, PROJWIRE_HEADER_SIZE);
	bool image = d->type == PROJWIRE_IMAGE || d->type == PROJWIRE_IMAGE_DELTA;
	d->head_need = image ? PROJWIRE_IMAGE_HEAD + d->mask_bytes : d->length;
	d->head_fill = 0;
	d->state = DEC_HEAD;
}

static int begin_done(struct projwire_decoder *d)
{
	uint32_t buffer = le_get32(d->head);
	uint32_t count = le_get32(d->head + 4);
	uint64_t seq = le_get64(d->head + 8);
	bool delta = d->type == PROJWIRE_DELTA_BEGIN;
	uint64_t base_seq = delta ? le_get64(d->head + 16) : 0;
	if (buffer >= d->buffers || count != d->image_count)
		return -EBADMSG;
	if (delta && !d->scratch && !(d->scratch = volume_create(&d->geom)))
		return -ENOMEM;
	int err = -EBUSY;
	struct volume *vol = d->sink->begin(d->data, buffer, seq, delta ? &base_seq : NULL, &err);
	if (!vol) {
		fail(d, err < 0 ? err : -EBUSY, false); /* the sink knows already */
		return 0;
	}
	if (!delta)
		volume_clear(vol);
	vol->seq = seq;
	d->vol = vol;
	d->delta = delta;
	d->buffer = buffer;
	d->images = 0;
	d->image = -1;
	expect_header(d);
	return 0;
}

static int mask_popcount(const struct projwire_decoder *d, const uint8_t *mask)
{
	int n = 0;
	for (uint32_t b = 0; b < d->mask_bytes; b++)
		n += __builtin_popcount(mask[b]);
	return n;
}

/* Delta merge: copies the buffer's own tiles numbered below t into the
 * scratch image, and steps over tile t itself (the record replaces it). */
static int merge_base(struct projwire_decoder *d, uint32_t t)
{
	const struct volume_image *img = &d->vol->images[d->image];
	for (; d->base_next < t && d->base_next < img->next_tile; d->base_next++) {
		if (!volume_tile_present(img, d->base_next))
			continue;
		const uint8_t *src = img->tiles + (size_t)d->base_tile++ * VOLUME_TILE_BYTES;
		int r = volume_image_append(d->scratch, 0, d->base_next, src);
		if (r < 0)
			return r;
	}
	if (t < img->next_tile && volume_tile_present(img, t))
		d->base_tile++;
	d->base_next = t + 1;
	return 0;
}

/* The last tile of an image record is in. */
static int image_done(struct projwire_decoder *d)
{
	expect_header(d);
	if (!d->delta)
		return 0;
	int r = merge_base(d, d->tiles_per_image);
	if (r < 0)
		return r;
	volume_image_exchange(d->vol, (uint32_t)d->image, d->scratch, 0);
	return 0;
}

static int image_head_done(struct projwire_decoder *d)
{
	uint32_t k = le_get32(d->head);
	uint32_t count = le_get32(d->head + 4);
	const uint8_t *mask = d->head + PROJWIRE_IMAGE_HEAD;
	if (k >= d->image_count || (int64_t)k <= d->image)
		return -EBADMSG; /* out of range, repeated or out of order */
	uint32_t spare = d->mask_bytes * 8 - d->tiles_per_image;
	if (spare && (mask[d->mask_bytes - 1] >> (8 - spare)))
		return -EBADMSG; /* bits for tiles that do not exist */
	if ((uint32_t)mask_popcount(d, mask) != count ||
	    d->length != PROJWIRE_IMAGE_HEAD + d->mask_bytes + count * VOLUME_TILE_BYTES)
		return -EBADMSG;
	struct volume *into = d->delta ? d->scratch : d->vol;
	uint32_t into_k = d->delta ? 0 : k;
	if (d->delta)
		volume_image_clear(d->scratch, 0);
	if (volume_image_reserve(into, into_k, count) < 0)
		return -ENOMEM;
	d->image = k;
	d->images++;
	d->next_bit = 0;
	d->base_next = d->base_tile = 0;
	d->tiles_left = count;
	d->tile_fill = 0;
	if (!count)
		return image_done(d);
	d->state = DEC_TILES;
	return 0;
}

static int end_done(struct projwire_decoder *d)
{
	uint32_t images = le_get32(d->head);
	uint32_t crc = le_get32(d->head + 4);
	if (images != d->images || crc != d->crc)
		return -EILSEQ;
	expect_header(d);
	close_volume(d, 0);
	return 0;
}

static int head_done(struct projwire_decoder *d)
{
	switch (d->type) {
	case PROJWIRE_VOLUME_BEGIN:
	case PROJWIRE_DELTA_BEGIN:
		return begin_done(d);
	case PROJWIRE_IMAGE:
	case PROJWIRE_IMAGE_DELTA:
		return image_head_done(d);
	default:
		return end_done(d);
	}
}

/* Pixels past W and H in edge tiles are always 0 (volume.h); an all-zero
 * tile must not be sent, except in a delta, where it empties the tile.
 * Either would make the device's buffer differ from the volume the host
 * meant. */
static bool tile_valid(const struct projwire_decoder *d, uint32_t t, const uint8_t *tile)
{
	uint32_t x0 = (t % d->tiles_x) * VOLUME_TILE, y0 = (t / d->tiles_x) * VOLUME_TILE;
	uint32_t cols = d->geom.width - x0, rows = d->geom.height - y0;
	uint32_t keep = cols >= VOLUME_TILE ? 0xffffffffu : ~(0xffffffffu >> cols);
	bool any = false;
	for (int c = 0; c < 3; c++) {
		for (uint32_t r = 0; r < VOLUME_TILE; r++) {
			const uint8_t *p = tile + c * VOLUME_TILE_PLANE_BYTES + r * 4;
			uint32_t bits = (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
			if (bits & (r < rows ? ~keep : 0xffffffffu))
				return false;
			any |= bits != 0;
		}
	}
	return any || d->delta;
}

static int tile_done(struct projwire_decoder *d)
{
	const uint8_t *mask = d->head + PROJWIRE_IMAGE_HEAD;
	uint32_t t = d->next_bit;
	while (!((mask[t / 8] >> (t % 8)) & 1))
		t++; /* the mask's popcount matched, so a bit is ahead */
	d->next_bit = t + 1;
	if (!tile_valid(d, t, d->tile))
		return -EBADMSG;
	int r = d->delta ? merge_base(d, t) : 0;
	if (r == 0)
		r = volume_image_append(d->delta ? d->scratch : d->vol, d->delta ? 0 : (uint32_t)d->image, t, d->tile);
	if (r < 0)
		return r;
	d->tile_fill = 0;
	if (--d->tiles_left == 0)
		return image_done(d);
	return 0;
}

/* Takes up to len bytes into dst (filled so far: *fill, wanted: need). */
static size_t take(uint8_t *dst, size_t *fill, size_t need, const uint8_t *src, size_t len)
{
	size_t n = need - *fill < len ? need - *fill : len;
	memcpy(dst + *fill, src, n);
	*fill += n;
	return n;
}

/* One step of the sync scan: slide the header window by one byte. */
static size_t sync_step(struct projwire_decoder *d, const uint8_t *buf)
{
	static const uint8_t begin_hdr[PROJWIRE_HEADER_SIZE] = {
		PROJWIRE_MAGIC0,
		PROJWIRE_MAGIC1,
		PROJWIRE_VOLUME_BEGIN,
		0,
		PROJWIRE_BEGIN_SIZE - PROJWIRE_HEADER_SIZE,
		0,
		0,
		0,
	};
	static const uint8_t delta_hdr[PROJWIRE_HEADER_SIZE] = {
		PROJWIRE_MAGIC0,
		PROJWIRE_MAGIC1,
		PROJWIRE_DELTA_BEGIN,
		0,
		PROJWIRE_DELTA_BEGIN_SIZE - PROJWIRE_HEADER_SIZE,
		0,
		0,
		0,
	};
	if (d->hdr_fill == PROJWIRE_HEADER_SIZE) {
		memmove(d->hdr, d->hdr + 1, PROJWIRE_HEADER_SIZE - 1);
		d->hdr_fill--;
		d->stats.skipped++;
	}
	size_t used = 0;
	if (buf)
		d->hdr[d->hdr_fill++] = buf[used++];
	if (d->hdr_fill == PROJWIRE_HEADER_SIZE &&
	    (!memcmp(d->hdr, begin_hdr, PROJWIRE_HEADER_SIZE) || !memcmp(d->hdr, delta_hdr, PROJWIRE_HEADER_SIZE)))
		header_done(d);
	return used;
}

static size_t step(struct projwire_decoder *d, const uint8_t *buf, size_t len)
{
	size_t n = 0;
	int err = 0;
	switch (d->state) {
	case DEC_HEADER:
		n = take(d->hdr, &d->hdr_fill, PROJWIRE_HEADER_SIZE, buf, len);
		if (d->hdr_fill == PROJWIRE_HEADER_SIZE)
			header_done(d);
		return n;
	case DEC_SYNC:
		return sync_step(d, buf);
	case DEC_HEAD:
		n = take(d->head, &d->head_fill, d->head_need, buf, len);
		if (d->type != PROJWIRE_VOLUME_END)
			d->crc = projwire_crc32(d->crc, buf, n);
		if (d->head_fill == d->head_need)
			err = head_done(d);
		break;
	case DEC_TILES:
		n = take(d->tile, &d->tile_fill, VOLUME_TILE_BYTES, buf, len);
		d->crc = projwire_crc32(d->crc, buf, n);
		if (d->tile_fill == VOLUME_TILE_BYTES)
			err = tile_done(d);
		break;
	}
	if (err < 0)
		fail(d, err, true);
	return n;
}

int projwire_decoder_feed(struct projwire_decoder *d, const uint8_t *buf, size_t len)
{
	d->first_err = 0;
	d->stats.bytes += len;
	while (len) {
		size_t n = step(d, buf, len);
		buf += n;
		len -= n;
		/* A header rejected in the scan leaves a full window to slide. */
		while (d->state == DEC_SYNC && d->hdr_fill == PROJWIRE_HEADER_SIZE)
			sync_step(d, NULL);
	}
	return d->first_err;
}

void projwire_decoder_reset(struct projwire_decoder *d)
{
	close_volume(d, -ECANCELED);
	d->state = DEC_HEADER;
	d->hdr_fill = 0;
}
