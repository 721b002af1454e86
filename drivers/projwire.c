/* The projector wire codec: errors, CRC, control requests, replies, event
 * records and the host-side record encoders. The device-side bulk decoder
 * is in projwire_decoder.c. */
#include "projwire.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "le.h"

static const struct {
	uint32_t code;
	int err;
} error_table[] = {
	{ PROJWIRE_ERR_NONE, 0 },
	{ PROJWIRE_ERR_REQUEST, -EINVAL },
	{ PROJWIRE_ERR_FRAMING, -EPROTO },
	{ PROJWIRE_ERR_IMAGE, -EBADMSG },
	{ PROJWIRE_ERR_CRC, -EILSEQ },
	{ PROJWIRE_ERR_BUSY, -EBUSY },
	{ PROJWIRE_ERR_NOT_READY, -ENODATA },
	{ PROJWIRE_ERR_UNSUPPORTED, -EOPNOTSUPP },
	{ PROJWIRE_ERR_NO_MEMORY, -ENOMEM },
	{ PROJWIRE_ERR_ABORTED, -ECANCELED },
};

#define ERROR_COUNT (sizeof(error_table) / sizeof(error_table[0]))

uint32_t projwire_error_from_errno(int err)
{
	for (size_t i = 0; i < ERROR_COUNT; i++)
		if (error_table[i].err == err)
			return error_table[i].code;
	return PROJWIRE_ERR_REQUEST;
}

int projwire_error_to_errno(uint32_t code)
{
	for (size_t i = 0; i < ERROR_COUNT; i++)
		if (error_table[i].code == code)
			return error_table[i].err;
	return -EIO; /* a code from a newer device */
}

uint32_t projwire_crc32(uint32_t crc, const void *buf, size_t len)
{
	/* zlib's: the same CRC, some ten times faster than a table made here
	 * (it is computed over every byte uploaded, on the event loop). */
	return (uint32_t)crc32_z(crc, buf, len);
}

/* ---- Control requests ---- */

void projwire_setup_encode(const struct projwire_setup *s, uint8_t out[PROJWIRE_SETUP_SIZE])
{
	out[0] = s->request_type;
	out[1] = s->request;
	le_put16(out + 2, s->value);
	le_put16(out + 4, s->index);
	le_put16(out + 6, s->length);
}

void projwire_setup_decode(const uint8_t in[PROJWIRE_SETUP_SIZE], struct projwire_setup *s)
{
	s->request_type = in[0];
	s->request = in[1];
	s->value = le_get16(in + 2);
	s->index = le_get16(in + 4);
	s->length = le_get16(in + 6);
}

size_t projwire_ctrl_encode(const struct projwire_ctrl *c, uint16_t iface, uint8_t setup[PROJWIRE_SETUP_SIZE],
			    uint8_t data[PROJWIRE_CTRL_DATA_MAX])
{
	struct projwire_setup s = { .request_type = PROJWIRE_RT_OUT, .request = (uint8_t)c->request, .index = iface };
	size_t len = 0;
	switch (c->request) {
	case PROJWIRE_REQ_GET_INFO:
	case PROJWIRE_REQ_GET_STATUS:
		s.request_type = PROJWIRE_RT_IN;
		s.length = PROJWIRE_INFO_SIZE; /* == PROJWIRE_STATUS_SIZE */
		break;
	case PROJWIRE_REQ_SET_BLANK:
		s.value = c->blank ? 1 : 0;
		break;
	case PROJWIRE_REQ_SET_TIMING:
		le_put64(data, c->timing.period_ns);
		le_put64(data + 8, (uint64_t)c->timing.index_ns);
		le_put64(data + 16, (uint64_t)c->timing.host_now_ns);
		len = PROJWIRE_TIMING_SIZE;
		break;
	case PROJWIRE_REQ_SWAP:
	case PROJWIRE_REQ_SWAP_HALF:
		s.value = (uint16_t)c->buffer;
		break;
	case PROJWIRE_REQ_RESET_STREAM:
		break;
	}
	s.length = len ? (uint16_t)len : s.length;
	projwire_setup_encode(&s, setup);
	return len;
}

/* The fixed shape of each request: direction, data stage length. */
static int ctrl_shape(const struct projwire_setup *s, size_t len)
{
	bool in = s->request == PROJWIRE_REQ_GET_INFO || s->request == PROJWIRE_REQ_GET_STATUS;
	if (s->request_type != (in ? PROJWIRE_RT_IN : PROJWIRE_RT_OUT))
		return -EINVAL;
	if (in)
		return s->value == 0 && s->length == PROJWIRE_INFO_SIZE && len == 0 ? 0 : -EINVAL;
	size_t want = s->request == PROJWIRE_REQ_SET_TIMING ? PROJWIRE_TIMING_SIZE : 0;
	return s->length == want && len == want ? 0 : -EINVAL;
}

/* Whether request is one of the protocol's requests. */
static bool ctrl_known(uint8_t request)
{
	switch (request) {
	case PROJWIRE_REQ_GET_INFO:
	case PROJWIRE_REQ_GET_STATUS:
	case PROJWIRE_REQ_SET_BLANK:
	case PROJWIRE_REQ_SET_TIMING:
	case PROJWIRE_REQ_SWAP:
	case PROJWIRE_REQ_RESET_STREAM:
	case PROJWIRE_REQ_SWAP_HALF:
		return true;
	default:
		return false;
	}
}

int projwire_ctrl_decode(const uint8_t setup[PROJWIRE_SETUP_SIZE], const uint8_t *data, size_t len,
			 struct projwire_ctrl *out)
{
	struct projwire_setup s;
	projwire_setup_decode(setup, &s);
	if (!ctrl_known(s.request))
		return -EOPNOTSUPP;
	if (ctrl_shape(&s, len) < 0)
		return -EINVAL;
	memset(out, 0, sizeof(*out));
	out->request = s.request;
	switch (s.request) {
	case PROJWIRE_REQ_SET_BLANK:
		if (s.value > 1)
			return -EINVAL;
		out->blank = s.value == 1;
		return 0;
	case PROJWIRE_REQ_SET_TIMING:
		out->timing.period_ns = le_get64(data);
		out->timing.index_ns = (int64_t)le_get64(data + 8);
		out->timing.host_now_ns = (int64_t)le_get64(data + 16);
		/* 1 to 600,000 rpm: anything else is not a rotor. */
		if (out->timing.period_ns < 100000 || out->timing.period_ns > 60000000000ull)
			return -EINVAL;
		return 0;
	case PROJWIRE_REQ_SWAP:
	case PROJWIRE_REQ_SWAP_HALF:
		if (s.value >= PROJWIRE_MAX_BUFFERS)
			return -EINVAL;
		out->buffer = s.value;
		return 0;
	default:
		return s.value == 0 ? 0 : -EINVAL;
	}
}

/* ---- GET_INFO ---- */

void projwire_info_encode(const struct projwire_info *info, uint8_t out[PROJWIRE_INFO_SIZE])
{
	memset(out, 0, PROJWIRE_INFO_SIZE);
	out[0] = info->version_major;
	out[1] = info->version_minor;
	le_put16(out + 2, PROJWIRE_INFO_SIZE);
	le_put32(out + 4, info->width);
	le_put32(out + 8, info->height);
	le_put32(out + 12, info->images_per_rev);
	le_put32(out + 16, info->flags);
	le_putf(out + 20, info->half_height);
	le_putf(out + 24, info->nominal_rpm);
	le_put32(out + 28, info->buffers);
	le_put32(out + 32, info->tile_size);
	le_put32(out + 36, info->max_record);
	le_put64(out + 40, info->link_bytes_per_sec);
	le_put32(out + 48, info->images_per_volume);
}

void projwire_info_to_geometry(const struct projwire_info *info, struct geometry *g)
{
	*g = (struct geometry){
		.width = info->width,
		.height = info->height,
		.images_per_rev = info->images_per_rev,
		.mirrored = (info->flags & PROJWIRE_INFO_MIRRORED) != 0,
		.half_height = info->half_height,
		.rpm = info->nominal_rpm,
	};
}

bool projwire_info_half_turn_swaps(const struct projwire_info *info)
{
	return info->version_minor >= 2 && (info->flags & PROJWIRE_INFO_MIRRORED);
}

void projwire_info_from_geometry(struct projwire_info *info, const struct geometry *g, uint32_t buffers,
				 uint64_t link_bytes_per_sec)
{
	*info = (struct projwire_info){
		.version_major = PROJWIRE_VERSION_MAJOR,
		.version_minor = PROJWIRE_VERSION_MINOR,
		.width = g->width,
		.height = g->height,
		.images_per_rev = g->images_per_rev,
		.flags = g->mirrored ? PROJWIRE_INFO_MIRRORED : 0,
		.half_height = g->half_height,
		.nominal_rpm = g->rpm,
		.buffers = buffers,
		.tile_size = VOLUME_TILE,
		.max_record = projwire_max_image_payload(g),
		.images_per_volume = geometry_images_per_volume(g),
		.link_bytes_per_sec = link_bytes_per_sec,
	};
}

int projwire_info_decode(const uint8_t *in, size_t len, struct projwire_info *out)
{
	if (len < PROJWIRE_INFO_SIZE || in[0] != PROJWIRE_VERSION_MAJOR || le_get16(in + 2) < PROJWIRE_INFO_SIZE)
		return -EPROTO;
	*out = (struct projwire_info){
		.version_major = in[0],
		.version_minor = in[1],
		.width = le_get32(in + 4),
		.height = le_get32(in + 8),
		.images_per_rev = le_get32(in + 12),
		.flags = le_get32(in + 16),
		.half_height = le_getf(in + 20),
		.nominal_rpm = le_getf(in + 24),
		.buffers = le_get32(in + 28),
		.tile_size = le_get32(in + 32),
		.max_record = le_get32(in + 36),
		.link_bytes_per_sec = le_get64(in + 40),
		.images_per_volume = le_get32(in + 48),
	};
	struct geometry g;
	projwire_info_to_geometry(out, &g);
	if (geometry_validate(&g) < 0 || out->tile_size != VOLUME_TILE)
		return -EINVAL;
	if (out->buffers < 2 || out->buffers > PROJWIRE_MAX_BUFFERS)
		return -EINVAL;
	if (out->images_per_volume != geometry_images_per_volume(&g))
		return -EINVAL;
	/* A device must take at least one whole tile. */
	uint32_t tiles = volume_geometry_tiles(&g);
	if (out->max_record < PROJWIRE_IMAGE_HEAD + (tiles + 7) / 8 + VOLUME_TILE_BYTES ||
	    out->max_record > PROJWIRE_MAX_PAYLOAD)
		return -EINVAL;
	return 0;
}

/* ---- GET_STATUS ---- */

void projwire_status_encode(const struct projwire_status *st, uint8_t out[PROJWIRE_STATUS_SIZE])
{
	memset(out, 0, PROJWIRE_STATUS_SIZE);
	le_put16(out, PROJWIRE_STATUS_SIZE);
	le_put32(out + 4, st->flags);
	le_put32(out + 8, st->shown);
	le_put32(out + 12, st->pending);
	le_put64(out + 16, st->revolutions);
	le_put64(out + 24, st->swaps);
	le_put64(out + 32, st->underruns);
	le_put64(out + 40, st->bytes);
	le_put32(out + 48, st->last_error);
	le_put32(out + 52, st->decode_errors);
	memcpy(out + 56, st->buffer_state, PROJWIRE_MAX_BUFFERS);
}

static bool buffer_field_valid(uint32_t b)
{
	return b == PROJWIRE_NO_BUFFER || b < PROJWIRE_MAX_BUFFERS;
}

int projwire_status_decode(const uint8_t *in, size_t len, struct projwire_status *out)
{
	if (len < PROJWIRE_STATUS_SIZE || le_get16(in) < PROJWIRE_STATUS_SIZE)
		return -EPROTO;
	*out = (struct projwire_status){
		.flags = le_get32(in + 4),
		.shown = le_get32(in + 8),
		.pending = le_get32(in + 12),
		.revolutions = le_get64(in + 16),
		.swaps = le_get64(in + 24),
		.underruns = le_get64(in + 32),
		.bytes = le_get64(in + 40),
		.last_error = le_get32(in + 48),
		.decode_errors = le_get32(in + 52),
	};
	memcpy(out->buffer_state, in + 56, PROJWIRE_MAX_BUFFERS);
	if (!buffer_field_valid(out->shown) || !buffer_field_valid(out->pending))
		return -EINVAL;
	for (int i = 0; i < PROJWIRE_MAX_BUFFERS; i++)
		if (out->buffer_state[i] > PROJWIRE_BUF_INVALID)
			return -EINVAL;
	return 0;
}

/* ---- Records ---- */

static void header_encode(uint8_t *out, uint8_t type, uint32_t payload)
{
	out[0] = PROJWIRE_MAGIC0;
	out[1] = PROJWIRE_MAGIC1;
	out[2] = type;
	out[3] = 0; /* flags: none defined in 1.0 */
	le_put32(out + 4, payload);
}

uint32_t projwire_max_image_payload(const struct geometry *geom)
{
	uint32_t tiles = volume_geometry_tiles(geom);
	return PROJWIRE_IMAGE_HEAD + (tiles + 7) / 8 + tiles * VOLUME_TILE_BYTES;
}

size_t projwire_image_size(const struct volume *vol, uint32_t k)
{
	return PROJWIRE_HEADER_SIZE + PROJWIRE_IMAGE_HEAD + vol->mask_bytes +
	       (size_t)vol->images[k].tile_count * VOLUME_TILE_BYTES;
}

size_t projwire_volume_size(const struct volume *vol)
{
	size_t n = PROJWIRE_BEGIN_SIZE + PROJWIRE_END_SIZE;
	for (uint32_t k = 0; k < vol->image_count; k++)
		if (vol->images[k].tile_count)
			n += projwire_image_size(vol, k);
	return n;
}

void projwire_begin_encode(uint8_t out[PROJWIRE_BEGIN_SIZE], uint32_t buffer, uint32_t image_count, uint64_t seq)
{
	header_encode(out, PROJWIRE_VOLUME_BEGIN, PROJWIRE_BEGIN_SIZE - PROJWIRE_HEADER_SIZE);
	le_put32(out + 8, buffer);
	le_put32(out + 12, image_count);
	le_put64(out + 16, seq);
}

size_t projwire_image_encode(const struct volume *vol, uint32_t k, uint8_t *out)
{
	const struct volume_image *img = &vol->images[k];
	size_t size = projwire_image_size(vol, k);
	header_encode(out, PROJWIRE_IMAGE, (uint32_t)(size - PROJWIRE_HEADER_SIZE));
	le_put32(out + 8, k);
	le_put32(out + 12, img->tile_count);
	memcpy(out + 16, img->mask, vol->mask_bytes);
	/* Stored tiles are already in increasing t, the wire order. */
	if (img->tile_count)
		memcpy(out + 16 + vol->mask_bytes, img->tiles, (size_t)img->tile_count * VOLUME_TILE_BYTES);
	return size;
}

void projwire_end_encode(uint8_t out[PROJWIRE_END_SIZE], uint32_t image_records, uint32_t crc)
{
	header_encode(out, PROJWIRE_VOLUME_END, PROJWIRE_END_SIZE - PROJWIRE_HEADER_SIZE);
	le_put32(out + 8, image_records);
	le_put32(out + 12, crc);
}

size_t projwire_volume_encode(const struct volume *vol, uint32_t buffer, uint8_t *out)
{
	size_t n = PROJWIRE_BEGIN_SIZE;
	uint32_t images = 0;
	projwire_begin_encode(out, buffer, vol->image_count, vol->seq);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		if (!vol->images[k].tile_count)
			continue; /* absent images are empty */
		n += projwire_image_encode(vol, k, out + n);
		images++;
	}
	projwire_end_encode(out + n, images, projwire_crc32(0, out, n));
	return n + PROJWIRE_END_SIZE;
}

/* ---- Events ---- */

size_t projwire_event_encode(const struct projwire_event *ev, uint8_t out[PROJWIRE_EVENT_MAX])
{
	if (ev->type == PROJWIRE_EV_SWAPPED) {
		header_encode(out, ev->type, 24);
		le_put32(out + 8, ev->buffer);
		le_put32(out + 12, ev->boundary); /* reserved (0) before 1.2 */
		le_put64(out + 16, (uint64_t)ev->time_ns);
		le_put64(out + 24, ev->seq);
		return PROJWIRE_HEADER_SIZE + 24;
	}
	header_encode(out, PROJWIRE_EV_ERROR, 16);
	le_put32(out + 8, ev->error);
	le_put32(out + 12, ev->buffer);
	le_put64(out + 16, ev->seq);
	return PROJWIRE_HEADER_SIZE + 16;
}

int projwire_event_decode(const uint8_t *in, size_t len, struct projwire_event *out)
{
	if (len < PROJWIRE_HEADER_SIZE)
		return -EAGAIN;
	if (in[0] != PROJWIRE_MAGIC0 || in[1] != PROJWIRE_MAGIC1 || in[3] != 0)
		return -EPROTO;
	uint32_t payload = le_get32(in + 4);
	if ((in[2] == PROJWIRE_EV_SWAPPED && payload != 24) || (in[2] == PROJWIRE_EV_ERROR && payload != 16) ||
	    (in[2] != PROJWIRE_EV_SWAPPED && in[2] != PROJWIRE_EV_ERROR))
		return -EPROTO;
	if (len < PROJWIRE_HEADER_SIZE + payload)
		return -EAGAIN;
	memset(out, 0, sizeof(*out));
	out->type = in[2];
	if (out->type == PROJWIRE_EV_SWAPPED) {
		out->buffer = le_get32(in + 8);
		/* Bits a later minor version may define are ignored. */
		out->boundary = le_get32(in + 12) & PROJWIRE_SWAPPED_HALF_TURN;
		out->time_ns = (int64_t)le_get64(in + 16);
		out->seq = le_get64(in + 24);
	} else {
		out->error = le_get32(in + 8);
		out->buffer = le_get32(in + 12);
		out->seq = le_get64(in + 16);
	}
	if (!buffer_field_valid(out->buffer) || (out->type == PROJWIRE_EV_SWAPPED && out->buffer == PROJWIRE_NO_BUFFER))
		return -EPROTO;
	return (int)(PROJWIRE_HEADER_SIZE + payload);
}

/* ---- Delta volumes (1.1) ---- */

void projwire_delta_begin_encode(uint8_t out[PROJWIRE_DELTA_BEGIN_SIZE], uint32_t buffer, uint32_t image_count,
				 uint64_t seq, uint64_t base_seq)
{
	header_encode(out, PROJWIRE_DELTA_BEGIN, PROJWIRE_DELTA_BEGIN_SIZE - PROJWIRE_HEADER_SIZE);
	le_put32(out + 8, buffer);
	le_put32(out + 12, image_count);
	le_put64(out + 16, seq);
	le_put64(out + 24, base_seq);
}

/* Marks in mask (mask_bytes, cleared first) the tiles of image k that
 * differ between vol and base, a tile that only one of them has among
 * them; returns how many. The one comparison of the two volumes; none
 * where the two images carry the same stamp (volume.h): the object
 * cache's compositions stamp what they change, so an image that no
 * object touched since base is not read at all; and, with differ (image
 * k's mask of the tiles that may differ, or NULL), no tile it leaves out:
 * the cache knows which tiles its compositions changed. */
static uint32_t delta_tiles(const struct volume *vol, const struct volume *base, uint32_t k, const uint8_t *differ,
			    uint8_t *mask)
{
	const struct volume_image *a = &vol->images[k], *b = &base->images[k];
	const uint8_t *pa = a->tiles, *pb = b->tiles;
	uint32_t n = 0;
	memset(mask, 0, vol->mask_bytes);
	if (a->stamp && a->stamp == b->stamp)
		return 0;
	for (uint32_t byte = 0; byte < vol->mask_bytes; byte++) {
		uint8_t ma = a->mask[byte], mb = b->mask[byte], may = differ ? differ[byte] : 0xff;
		for (uint32_t bits = ma | mb; bits; bits &= bits - 1) {
			uint32_t bit = (uint32_t)__builtin_ctz(bits);
			bool ia = (ma >> bit) & 1, ib = (mb >> bit) & 1;
			if (ia != ib || (((may >> bit) & 1) && memcmp(pa, pb, VOLUME_TILE_BYTES))) {
				mask[byte] |= (uint8_t)(1u << bit);
				n++;
			}
			pa += ia ? VOLUME_TILE_BYTES : 0;
			pb += ib ? VOLUME_TILE_BYTES : 0;
		}
	}
	return n;
}

/* The tiles of image k of vol that mask marks, in order into out: a
 * tile vol no longer has goes as zeros. */
static void delta_copy(const struct volume *vol, uint32_t k, const uint8_t *mask, uint8_t *out)
{
	const struct volume_image *a = &vol->images[k];
	const uint8_t *pa = a->tiles;
	for (uint32_t byte = 0; byte < vol->mask_bytes; byte++) {
		uint8_t ma = a->mask[byte], m = mask[byte];
		for (uint32_t bits = ma | m; bits; bits &= bits - 1) {
			uint32_t bit = (uint32_t)__builtin_ctz(bits);
			bool ia = (ma >> bit) & 1;
			if ((m >> bit) & 1) {
				if (ia)
					memcpy(out, pa, VOLUME_TILE_BYTES);
				else
					memset(out, 0, VOLUME_TILE_BYTES);
				out += VOLUME_TILE_BYTES;
			}
			pa += ia ? VOLUME_TILE_BYTES : 0;
		}
	}
}

static size_t delta_image_size(const struct volume *vol, uint32_t tiles)
{
	return PROJWIRE_HEADER_SIZE + PROJWIRE_IMAGE_HEAD + vol->mask_bytes + (size_t)tiles * VOLUME_TILE_BYTES;
}

static bool delta_fits(const struct volume *vol, const struct volume *base)
{
	return base && base->image_count == vol->image_count && base->mask_bytes == vol->mask_bytes &&
	       base->tiles_x == vol->tiles_x;
}

/* Room in d for vol's images. 0 or -ENOMEM. */
static int delta_reserve(struct projwire_delta *d, const struct volume *vol)
{
	size_t bytes = (size_t)vol->image_count * vol->mask_bytes;
	if (vol->image_count > d->images_cap) {
		uint32_t *t = realloc(d->tiles, vol->image_count * sizeof(*t));
		if (!t)
			return -ENOMEM;
		d->tiles = t;
		d->images_cap = vol->image_count;
	}
	if (bytes > d->masks_cap) {
		uint8_t *m = realloc(d->masks, bytes);
		if (!m)
			return -ENOMEM;
		d->masks = m;
		d->masks_cap = bytes;
	}
	return 0;
}

void projwire_delta_free(struct projwire_delta *d)
{
	free(d->tiles);
	free(d->masks);
	*d = (struct projwire_delta){ 0 };
}

/* A delta when there is a base and it is the smaller form: a delta sends
 * removed tiles as zeros, so a volume unlike its base is cheaper whole. */
int projwire_upload_plan(const struct volume *vol, const struct volume *base, const uint8_t *differ,
			 struct projwire_delta *d, size_t *size)
{
	*size = projwire_volume_size(vol);
	d->delta = false;
	if (!delta_fits(vol, base))
		return 0;
	int r = delta_reserve(d, vol);
	if (r < 0)
		return r;
	size_t n = PROJWIRE_DELTA_BEGIN_SIZE + PROJWIRE_END_SIZE;
	for (uint32_t k = 0; k < vol->image_count; k++) {
		const uint8_t *may = differ ? differ + (size_t)k * vol->mask_bytes : NULL;
		d->tiles[k] = delta_tiles(vol, base, k, may, d->masks + (size_t)k * vol->mask_bytes);
		n += d->tiles[k] ? delta_image_size(vol, d->tiles[k]) : 0;
	}
	d->delta = n < *size;
	if (d->delta)
		*size = n;
	return 0;
}

/* A delta volume: an IMAGE_DELTA record for each image with a changed
 * tile; images not sent keep what the buffer holds. */
static size_t delta_encode(const struct volume *vol, const struct volume *base, const struct projwire_delta *d,
			   uint32_t buffer, uint8_t *out)
{
	size_t n = PROJWIRE_DELTA_BEGIN_SIZE;
	uint32_t images = 0;
	projwire_delta_begin_encode(out, buffer, vol->image_count, vol->seq, base->seq);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		uint32_t t = d->tiles[k];
		if (!t)
			continue;
		const uint8_t *mask = d->masks + (size_t)k * vol->mask_bytes;
		uint8_t *rec = out + n, *head = rec + PROJWIRE_HEADER_SIZE + PROJWIRE_IMAGE_HEAD;
		size_t size = delta_image_size(vol, t);
		header_encode(rec, PROJWIRE_IMAGE_DELTA, (uint32_t)(size - PROJWIRE_HEADER_SIZE));
		le_put32(rec + 8, k);
		le_put32(rec + 12, t);
		memcpy(head, mask, vol->mask_bytes);
		delta_copy(vol, k, mask, head + vol->mask_bytes);
		n += size;
		images++;
	}
	projwire_end_encode(out + n, images, projwire_crc32(0, out, n));
	return n + PROJWIRE_END_SIZE;
}

size_t projwire_upload_encode(const struct volume *vol, const struct volume *base, const struct projwire_delta *d,
			      uint32_t buffer, uint8_t *out)
{
	if (!d->delta)
		return projwire_volume_encode(vol, buffer, out);
	return delta_encode(vol, base, d, buffer, out);
}
