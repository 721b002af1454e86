/* The projector wire codec: round trips in arbitrary chunks, strict
 * rejection of every malformed record, recovery, and garbage streams. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "le.h"
#include "projwire.h"
#include "projwire_rig.h"
#include "volume_util.h"

static void test_round_trip(void)
{
	struct rig r;
	rig_init(&r);
	for (int i = 0; i < 60; i++) {
		uint32_t buffer = (uint32_t)i % BUFFERS;
		random_volume(r.src, 1 + rnd_below(8), 1000 + (uint64_t)i);
		size_t len;
		uint8_t *wire = encode(&r, buffer, &len);
		size_t max = (i % 3 == 0) ? 1 : (i % 3 == 1) ? 17 : 5000;
		CHECK_EQ(feed_chunked(r.dec, wire, len, max), 0);
		CHECK_EQ(r.sink.result[buffer], 0);
		CHECK(volumes_equal(r.sink.vols[buffer], r.src));
		free(wire);
	}
	struct projwire_decoder_stats st;
	projwire_decoder_get_stats(r.dec, &st);
	CHECK_EQ(st.volumes, 60);
	CHECK_EQ(st.errors, 0);
	CHECK_EQ(st.skipped, 0);
	/* An empty volume is BEGIN + END only. */
	volume_clear(r.src);
	size_t len;
	uint8_t *wire = encode(&r, 1, &len);
	CHECK_EQ(len, PROJWIRE_BEGIN_SIZE + PROJWIRE_END_SIZE);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), 0);
	CHECK(volumes_equal(r.sink.vols[1], r.src));
	free(wire);
	rig_finish(&r);
}

/* Offset of the first IMAGE record of an encoded volume. */
#define FIRST_IMAGE PROJWIRE_BEGIN_SIZE

/* Mutates a fresh encoding with fn, feeds it, and expects err for buffer 0,
 * then checks that a good volume right after still decodes. */
static void expect_reject(void (*fn)(uint8_t *wire, size_t len), int err, bool in_volume)
{
	struct rig r;
	rig_init(&r);
	do
		random_volume(r.src, 4, 7);
	while (!r.src->images[0].tile_count || r.src->images[0].tile_count < 2);
	size_t len;
	uint8_t *wire = encode(&r, 0, &len);
	fn(wire, len);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), err);
	CHECK(r.sink.result[0] != 0); /* never valid */
	if (in_volume)
		CHECK_EQ(r.sink.result[0], err);
	else
		CHECK(r.sink.stray_errors >= 1);
	free(wire);
	/* Recovery: the next volume is taken whole. */
	random_volume(r.src, 3, 8);
	wire = encode(&r, 1, &len);
	CHECK_EQ(feed_chunked(r.dec, wire, len, 100), 0);
	CHECK_EQ(r.sink.result[1], 0);
	CHECK(volumes_equal(r.sink.vols[1], r.src));
	free(wire);
	rig_finish(&r);
}

static void bad_magic(uint8_t *w, size_t len)
{
	w[0] = 'X';
}

static void begin_too_long(uint8_t *w, size_t len)
{
	le_put32(w + 4, 17);
}

static void image_oversized(uint8_t *w, size_t len)
{
	le_put32(w + FIRST_IMAGE + 4, PROJWIRE_MAX_PAYLOAD + 8);
}

static void image_out_of_range(uint8_t *w, size_t len)
{
	le_put32(w + FIRST_IMAGE + 8, geom.images_per_rev / 2);
}

static void count_mismatch(uint8_t *w, size_t len)
{
	le_put32(w + FIRST_IMAGE + 12, le_get32(w + FIRST_IMAGE + 12) - 1);
}

static void spare_mask_bit(uint8_t *w, size_t len)
{
	/* 12 tiles in 2 mask bytes: bit 15 names no tile. */
	w[FIRST_IMAGE + 16 + 1] |= 0x80;
}

static void padding_pixel(uint8_t *w, size_t len)
{
	/* Find image 0's tile 3 (x 96..127, only 4 columns real) if present,
	 * else any tile of the last row (rows 64..95, 6 real): set a dead bit. */
	const uint8_t *mask = w + FIRST_IMAGE + 16;
	uint8_t *tile = w + FIRST_IMAGE + 16 + 2;
	for (uint32_t t = 0; t < 12; t++) {
		if (!((mask[t / 8] >> (t % 8)) & 1))
			continue;
		if (t % 4 == 3) {
			tile[0 * 4 + 3] |= 0x01; /* column 127 */
			return;
		}
		if (t >= 8) {
			tile[31 * 4] |= 0x80; /* row 95 */
			return;
		}
		tile += VOLUME_TILE_BYTES;
	}
	/* No edge tile in image 0: an all-zero tile is just as bad. */
	memset(w + FIRST_IMAGE + 16 + 2, 0, VOLUME_TILE_BYTES);
}

static void crc_field(uint8_t *w, size_t len)
{
	w[len - 1] ^= 0x10;
}

static void seq_bit(uint8_t *w, size_t len)
{
	w[16] ^= 0x01; /* a field no check but the CRC covers */
}

static void delta_record(uint8_t *w, size_t len)
{
	w[FIRST_IMAGE + 2] = PROJWIRE_IMAGE_DELTA;
}

static void image_before_begin(uint8_t *w, size_t len)
{
	w[0] ^= 0xff; /* the BEGIN is lost, so the IMAGE is out of place */
	w[FIRST_IMAGE] = PROJWIRE_MAGIC0;
}

static void truncate_tail(uint8_t *w, size_t len)
{
	/* Replace the END record with bytes of an unknown type. */
	w[len - PROJWIRE_END_SIZE + 2] = 0x7f;
}

static void test_rejects(void)
{
	expect_reject(bad_magic, -EPROTO, false);
	expect_reject(begin_too_long, -EPROTO, false);
	expect_reject(image_oversized, -EPROTO, true);
	expect_reject(image_out_of_range, -EBADMSG, true);
	expect_reject(count_mismatch, -EBADMSG, true);
	expect_reject(spare_mask_bit, -EBADMSG, true);
	expect_reject(padding_pixel, -EBADMSG, true);
	expect_reject(crc_field, -EILSEQ, true);
	expect_reject(seq_bit, -EILSEQ, true);
	expect_reject(delta_record, -EPROTO, true); /* a delta image in a whole volume */
	expect_reject(image_before_begin, -EPROTO, false);
	expect_reject(truncate_tail, -EPROTO, true);
}

static void test_image_order(void)
{
	struct rig r;
	rig_init(&r);
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_clear(r.src);
	random_tile(r.src, 0, tile);
	CHECK_EQ(volume_image_append(r.src, 2, 0, tile), 0);
	/* BEGIN, image 2, image 2 again: a repeated index is refused. */
	size_t img = projwire_image_size(r.src, 2);
	uint8_t *w = malloc(PROJWIRE_BEGIN_SIZE + 2 * img);
	CHECK(w);
	projwire_begin_encode(w, 2, r.src->image_count, 1);
	projwire_image_encode(r.src, 2, w + PROJWIRE_BEGIN_SIZE);
	projwire_image_encode(r.src, 2, w + PROJWIRE_BEGIN_SIZE + img);
	CHECK_EQ(projwire_decoder_feed(r.dec, w, PROJWIRE_BEGIN_SIZE + 2 * img), -EBADMSG);
	CHECK_EQ(r.sink.result[2], -EBADMSG);
	/* An IMAGE with no volume open is out of place (once in step: while
	 * resynchronising, anything but a BEGIN is skipped silently). */
	r.sink.stray_errors = 0;
	projwire_decoder_reset(r.dec);
	CHECK_EQ(projwire_decoder_feed(r.dec, w + PROJWIRE_BEGIN_SIZE, img), -EPROTO);
	CHECK_EQ(r.sink.stray_errors, 1);
	/* Wrong image count in BEGIN. */
	projwire_begin_encode(w, 2, r.src->image_count + 1, 1);
	CHECK_EQ(projwire_decoder_feed(r.dec, w, PROJWIRE_BEGIN_SIZE), -EBADMSG);
	free(w);
	rig_finish(&r);
}

static void test_busy_and_abandon(void)
{
	struct rig r;
	rig_init(&r);
	random_volume(r.src, 3, 5);
	size_t len;
	uint8_t *wire = encode(&r, 0, &len);
	r.sink.busy[0] = true;
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), -EBUSY);
	CHECK_EQ(r.sink.result[0], 1); /* the busy buffer was never touched */
	CHECK_EQ(r.sink.begins, 0);
	free(wire);
	/* A BEGIN in the middle of a volume abandons it. */
	wire = encode(&r, 1, &len);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len - PROJWIRE_END_SIZE), 0);
	CHECK_EQ(r.sink.result[1], 1);
	free(wire);
	wire = encode(&r, 2, &len);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), -ECANCELED);
	CHECK_EQ(r.sink.result[1], -ECANCELED);
	CHECK_EQ(r.sink.result[2], 0);
	CHECK(volumes_equal(r.sink.vols[2], r.src));
	/* RESET_STREAM drops a partial record and the open volume. */
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len / 2), 0);
	projwire_decoder_reset(r.dec);
	CHECK_EQ(r.sink.result[2], -ECANCELED);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), 0);
	CHECK_EQ(r.sink.result[2], 0);
	free(wire);
	rig_finish(&r);
}

static void test_truncated_then_more(void)
{
	struct rig r;
	rig_init(&r);
	for (int i = 0; i < 200; i++) {
		random_volume(r.src, 3, (uint64_t)i);
		size_t len;
		uint8_t *wire = encode(&r, 0, &len);
		r.sink.result[0] = 1;
		feed_chunked(r.dec, wire, rnd_below((uint32_t)len), 300);
		free(wire);
		/* The cut volume is never valid, whatever follows it; the
		 * decoder is back in step within one more volume. */
		for (uint32_t b = 1; b < BUFFERS; b++) {
			random_volume(r.src, 3, 100 + b);
			wire = encode(&r, b, &len);
			r.sink.result[b] = 1;
			feed_chunked(r.dec, wire, len, 300);
			free(wire);
		}
		CHECK(r.sink.result[0] != 0);
		CHECK_EQ(r.sink.result[2], 0);
		CHECK(volumes_equal(r.sink.vols[2], r.src));
	}
	rig_finish(&r);
}

static void test_garbage(void)
{
	struct rig r;
	rig_init(&r);
	uint8_t junk[3000];
	for (int i = 0; i < 4000; i++) {
		size_t n = rnd_below(sizeof(junk));
		for (size_t j = 0; j < n; j++)
			junk[j] = (uint8_t)rnd();
		/* Sometimes plausible headers, to get past the first checks. */
		if (n >= 16 && i % 2) {
			size_t at = rnd_below((uint32_t)n - 15);
			uint8_t types[] = { 1, 2, 3, 4, 0x81 };
			junk[at] = PROJWIRE_MAGIC0;
			junk[at + 1] = PROJWIRE_MAGIC1;
			junk[at + 2] = types[rnd_below(5)];
			junk[at + 3] = 0;
			le_put32(junk + at + 4, rnd_below(4) ? rnd_below(2000) : 16);
		}
		/* In step, garbage meets the header checks, not just the scan. */
		if (i % 3 == 0)
			projwire_decoder_reset(r.dec);
		feed_chunked(r.dec, junk, n, 64);
	}
	struct projwire_decoder_stats st;
	projwire_decoder_get_stats(r.dec, &st);
	fprintf(stderr, "garbage: %llu errors, %llu bytes skipped\n", (unsigned long long)st.errors,
		(unsigned long long)st.skipped);
	CHECK(st.errors > 1000 && st.skipped > 1000000);
	/* Bit flips in real volumes are always caught. */
	for (int i = 0; i < 1000; i++) {
		random_volume(r.src, 2, (uint64_t)i);
		size_t len;
		uint8_t *wire = encode(&r, 1, &len);
		int flips = 1 + (int)rnd_below(2);
		for (int f = 0; f < flips; f++)
			wire[rnd_below((uint32_t)len)] ^= (uint8_t)(1u << rnd_below(8));
		r.sink.result[1] = 1;
		feed_chunked(r.dec, wire, len, 500);
		CHECK(r.sink.result[1] != 0);
		free(wire);
		projwire_decoder_reset(r.dec);
	}
	/* And after all that, a clean volume still goes through. */
	random_volume(r.src, 5, 99);
	size_t len;
	uint8_t *wire = encode(&r, 2, &len);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), 0);
	CHECK(volumes_equal(r.sink.vols[2], r.src));
	free(wire);
	rig_finish(&r);
}

static void ctrl_round_trip(const struct projwire_ctrl *c)
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX];
	size_t len = projwire_ctrl_encode(c, 0, setup, data);
	struct projwire_ctrl out;
	CHECK_EQ(projwire_ctrl_decode(setup, data, len, &out), 0);
	CHECK_EQ(out.request, c->request);
	CHECK(memcmp(&out, c, sizeof(out)) == 0);
}

static void test_control(void)
{
	struct projwire_ctrl c;
	memset(&c, 0, sizeof(c));
	c.request = PROJWIRE_REQ_GET_INFO;
	ctrl_round_trip(&c);
	c.request = PROJWIRE_REQ_GET_STATUS;
	ctrl_round_trip(&c);
	c.request = PROJWIRE_REQ_RESET_STREAM;
	ctrl_round_trip(&c);
	c.request = PROJWIRE_REQ_SET_BLANK;
	c.blank = true;
	ctrl_round_trip(&c);
	memset(&c, 0, sizeof(c));
	c.request = PROJWIRE_REQ_SWAP;
	c.buffer = 2;
	ctrl_round_trip(&c);
	c.request = PROJWIRE_REQ_SWAP_HALF;
	c.buffer = 3;
	ctrl_round_trip(&c);
	memset(&c, 0, sizeof(c));
	c.request = PROJWIRE_REQ_SET_TIMING;
	c.timing = (struct projwire_timing){ 33333333, 123456789012345, 123456789099999 };
	ctrl_round_trip(&c);

	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl out;
	size_t len = projwire_ctrl_encode(&c, 0, setup, data);
	CHECK_EQ(projwire_ctrl_decode(setup, data, len - 1, &out), -EINVAL); /* short data */
	setup[0] = PROJWIRE_RT_IN;
	CHECK_EQ(projwire_ctrl_decode(setup, data, len, &out), -EINVAL); /* wrong direction */
	c.timing.period_ns = 0;
	len = projwire_ctrl_encode(&c, 0, setup, data);
	CHECK_EQ(projwire_ctrl_decode(setup, data, len, &out), -EINVAL);
	struct projwire_setup s = { PROJWIRE_RT_OUT, PROJWIRE_REQ_SET_BLANK, 2, 0, 0 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EINVAL);
	s = (struct projwire_setup){ PROJWIRE_RT_OUT, PROJWIRE_REQ_SWAP, PROJWIRE_MAX_BUFFERS, 0, 0 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EINVAL);
	s = (struct projwire_setup){ PROJWIRE_RT_OUT, PROJWIRE_REQ_SWAP_HALF, PROJWIRE_MAX_BUFFERS, 0, 0 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EINVAL);
	s = (struct projwire_setup){ PROJWIRE_RT_IN, PROJWIRE_REQ_SWAP_HALF, 1, 0, 0 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EINVAL); /* wrong direction */
	s = (struct projwire_setup){ PROJWIRE_RT_OUT, PROJWIRE_REQ_SWAP_HALF, 1, 0, 4 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, data, 4, &out), -EINVAL); /* no data stage */

	/* SWAP_HALF (1.2) byte for byte: 41 14 bb 00 ii 00 00 00. */
	c = (struct projwire_ctrl){ .request = PROJWIRE_REQ_SWAP_HALF, .buffer = 2 };
	CHECK_EQ(projwire_ctrl_encode(&c, 3, setup, data), 0);
	static const uint8_t swap_half[PROJWIRE_SETUP_SIZE] = { 0x41, 0x14, 0x02, 0x00, 0x03, 0x00, 0x00, 0x00 };
	CHECK(!memcmp(setup, swap_half, sizeof(swap_half)));
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), 0);
	CHECK_EQ(out.request, PROJWIRE_REQ_SWAP_HALF);
	CHECK_EQ(out.buffer, 2);
	s = (struct projwire_setup){ PROJWIRE_RT_IN, PROJWIRE_REQ_GET_INFO, 0, 0, 8 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EINVAL);
	s = (struct projwire_setup){ PROJWIRE_RT_OUT, 0x77, 0, 0, 0 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(projwire_ctrl_decode(setup, NULL, 0, &out), -EOPNOTSUPP);
	struct projwire_setup back;
	s = (struct projwire_setup){ 0xc1, 0x02, 0x1234, 0x0003, 0x0040 };
	projwire_setup_encode(&s, setup);
	CHECK_EQ(setup[2], 0x34);
	projwire_setup_decode(setup, &back);
	CHECK(memcmp(&s, &back, sizeof(s)) == 0);
}

/* Field by field: struct padding is not part of the value. */
static bool info_equal(const struct projwire_info *a, const struct projwire_info *b)
{
	return a->version_major == b->version_major && a->version_minor == b->version_minor && a->width == b->width &&
	       a->height == b->height && a->images_per_rev == b->images_per_rev && a->flags == b->flags &&
	       a->half_height == b->half_height && a->nominal_rpm == b->nominal_rpm && a->buffers == b->buffers &&
	       a->tile_size == b->tile_size && a->max_record == b->max_record &&
	       a->images_per_volume == b->images_per_volume && a->link_bytes_per_sec == b->link_bytes_per_sec;
}

static bool status_equal(const struct projwire_status *a, const struct projwire_status *b)
{
	return a->flags == b->flags && a->shown == b->shown && a->pending == b->pending &&
	       a->revolutions == b->revolutions && a->swaps == b->swaps && a->underruns == b->underruns &&
	       a->bytes == b->bytes && a->last_error == b->last_error && a->decode_errors == b->decode_errors &&
	       !memcmp(a->buffer_state, b->buffer_state, sizeof(a->buffer_state));
}

static bool event_equal(const struct projwire_event *a, const struct projwire_event *b)
{
	return a->type == b->type && a->buffer == b->buffer && a->time_ns == b->time_ns && a->seq == b->seq &&
	       a->error == b->error && a->boundary == b->boundary;
}

/* 1.2: SWAPPED's boundary field, the status flag, who gets SWAP_HALF. */
static void test_half_turn_wire(void)
{
	struct projwire_event ev = {
		.type = PROJWIRE_EV_SWAPPED,
		.buffer = 1,
		.time_ns = 0x0102030405060708,
		.seq = 77,
		.boundary = PROJWIRE_SWAPPED_HALF_TURN,
	}, ev2;
	uint8_t eb[PROJWIRE_EVENT_MAX];
	CHECK_EQ(projwire_event_encode(&ev, eb), 32);
	static const uint8_t want[32] = {
		0x53, 0x50, 0x81, 0x00, 0x18, 0x00, 0x00, 0x00, /* header: SWAPPED, 24 bytes */
		0x01, 0x00, 0x00, 0x00,                         /* buffer */
		0x01, 0x00, 0x00, 0x00,                         /* boundary: half turn */
		0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01, /* time */
		77,   0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, /* sequence number */
	};
	CHECK(!memcmp(eb, want, sizeof(want)));
	CHECK_EQ(projwire_event_decode(eb, sizeof(eb), &ev2), 32);
	CHECK(event_equal(&ev, &ev2));
	/* A revolution start, and what a 1.1 device sends (the field was
	 * reserved): 0. */
	eb[12] = 0;
	CHECK_EQ(projwire_event_decode(eb, sizeof(eb), &ev2), 32);
	CHECK_EQ(ev2.boundary, 0);
	ev.boundary = 0;
	CHECK(event_equal(&ev, &ev2));
	/* Bits a later version may define are ignored, not an error. */
	le_put32(eb + 12, 0x80000003u);
	CHECK_EQ(projwire_event_decode(eb, sizeof(eb), &ev2), 32);
	CHECK_EQ(ev2.boundary, PROJWIRE_SWAPPED_HALF_TURN);
	/* ERROR events have no boundary. */
	struct projwire_event err = { .type = PROJWIRE_EV_ERROR, .buffer = 2, .error = PROJWIRE_ERR_NOT_READY };
	CHECK_EQ(projwire_event_decode(eb, projwire_event_encode(&err, eb), &ev2), 24);
	CHECK_EQ(ev2.boundary, 0);

	struct projwire_status st = { .flags = PROJWIRE_STATUS_PENDING | PROJWIRE_STATUS_PENDING_HALF,
				      .shown = 0,
				      .pending = 1 },
			       st2;
	uint8_t sb[PROJWIRE_STATUS_SIZE];
	projwire_status_encode(&st, sb);
	CHECK_EQ(sb[4], 0x0c);
	CHECK_EQ(projwire_status_decode(sb, sizeof(sb), &st2), 0);
	CHECK_EQ(st2.flags, PROJWIRE_STATUS_PENDING | PROJWIRE_STATUS_PENDING_HALF);

	/* Half-turn swaps: 1.2 or later, and mirrored. */
	struct projwire_info info;
	projwire_info_from_geometry(&info, &geom, 3, 0);
	CHECK_EQ(info.version_minor, 2);
	CHECK(projwire_info_half_turn_swaps(&info));
	uint8_t ib[PROJWIRE_INFO_SIZE];
	projwire_info_encode(&info, ib);
	CHECK_EQ(ib[1], 2);
	info.version_minor = 1;
	CHECK(!projwire_info_half_turn_swaps(&info));
	info.version_minor = 3;
	CHECK(projwire_info_half_turn_swaps(&info));
	struct geometry flat = geom;
	flat.mirrored = false;
	projwire_info_from_geometry(&info, &flat, 3, 0);
	CHECK(!projwire_info_half_turn_swaps(&info));
}

static void test_info_status_events(void)
{
	struct projwire_info info, info2;
	projwire_info_from_geometry(&info, &geom, 3, 400000000);
	uint8_t buf[PROJWIRE_INFO_SIZE];
	projwire_info_encode(&info, buf);
	CHECK_EQ(projwire_info_decode(buf, sizeof(buf), &info2), 0);
	CHECK(info_equal(&info, &info2));
	struct geometry g;
	projwire_info_to_geometry(&info2, &g);
	CHECK(g.width == geom.width && g.height == geom.height && g.images_per_rev == geom.images_per_rev &&
	      g.mirrored == geom.mirrored && g.half_height == geom.half_height && g.rpm == geom.rpm);
	CHECK_EQ(info2.images_per_volume, 8);
	CHECK_EQ(projwire_info_decode(buf, sizeof(buf) - 1, &info2), -EPROTO);
	buf[0] = 2;
	CHECK_EQ(projwire_info_decode(buf, sizeof(buf), &info2), -EPROTO);
	info.buffers = 9;
	projwire_info_encode(&info, buf);
	CHECK_EQ(projwire_info_decode(buf, sizeof(buf), &info2), -EINVAL);

	struct projwire_status st = {
		.flags = PROJWIRE_STATUS_BLANKED, .shown = 1, .pending = PROJWIRE_NO_BUFFER, .revolutions = 1ull << 40,
		.swaps = 7, .underruns = 2, .bytes = 123456789, .last_error = PROJWIRE_ERR_CRC,
		.decode_errors = 3, .buffer_state = { 2, 2, 3, 0 },
	}, st2;
	uint8_t sb[PROJWIRE_STATUS_SIZE];
	projwire_status_encode(&st, sb);
	CHECK_EQ(projwire_status_decode(sb, sizeof(sb), &st2), 0);
	CHECK(status_equal(&st, &st2));
	sb[56] = 9;
	CHECK_EQ(projwire_status_decode(sb, sizeof(sb), &st2), -EINVAL);

	struct projwire_event ev = { .type = PROJWIRE_EV_SWAPPED, .buffer = 2, .time_ns = 987654321, .seq = 42 }, ev2;
	uint8_t eb[PROJWIRE_EVENT_MAX * 2];
	size_t n = projwire_event_encode(&ev, eb);
	struct projwire_event err = { .type = PROJWIRE_EV_ERROR,
				      .buffer = PROJWIRE_NO_BUFFER,
				      .error = PROJWIRE_ERR_CRC };
	size_t m = projwire_event_encode(&err, eb + n);
	CHECK_EQ(projwire_event_decode(eb, n - 1, &ev2), -EAGAIN);
	CHECK_EQ(projwire_event_decode(eb, n + m, &ev2), (int)n);
	CHECK(event_equal(&ev, &ev2));
	CHECK_EQ(projwire_event_decode(eb + n, m, &ev2), (int)m);
	CHECK(event_equal(&err, &ev2));
	eb[0] = 0;
	CHECK_EQ(projwire_event_decode(eb, n, &ev2), -EPROTO);
	test_half_turn_wire();
}

static void test_crc_and_errors(void)
{
	CHECK_EQ(projwire_crc32(0, "123456789", 9), 0xcbf43926u);
	uint32_t part = projwire_crc32(0, "1234", 4);
	CHECK_EQ(projwire_crc32(part, "56789", 5), 0xcbf43926u);
	for (uint32_t c = 0; c <= PROJWIRE_ERR_ABORTED; c++)
		CHECK_EQ(projwire_error_from_errno(projwire_error_to_errno(c)), c);
	CHECK_EQ(projwire_error_to_errno(1000), -EIO);
}

int main(void)
{
	test_crc_and_errors();
	test_control();
	test_info_status_events();
	test_round_trip();
	test_rejects();
	test_image_order();
	test_busy_and_abandon();
	test_truncated_then_more();
	test_garbage();
	return 0;
}
