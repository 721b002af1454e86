/* A decoder over a test sink of BUFFERS buffers at a small geometry,
 * and what feeds it: shared by the projector wire codec's tests. */
#ifndef SPINDLE_TEST_PROJWIRE_RIG_H
#define SPINDLE_TEST_PROJWIRE_RIG_H

#include <errno.h>
#include <stdlib.h>

#include "check.h"
#include "projwire.h"
#include "volume_util.h"

#define BUFFERS 3

/* W and H not multiples of 32: edge tiles and spare mask bits get tested. */
static const struct geometry geom = {
	.width = 100,
	.height = 70,
	.images_per_rev = 16,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
};

struct test_sink {
	struct volume *vols[BUFFERS];
	bool busy[BUFFERS];
	int result[BUFFERS]; /* 1 = nothing yet, else the err of end() */
	int begins, ends, stray_errors, last_err;
};

static inline struct volume *sink_begin(void *data, uint32_t buffer, uint64_t seq, const uint64_t *base_seq, int *err)
{
	struct test_sink *s = data;
	CHECK(buffer < BUFFERS);
	if (s->busy[buffer]) {
		*err = -EBUSY;
		return NULL;
	}
	if (base_seq && (s->result[buffer] != 0 || s->vols[buffer]->seq != *base_seq)) {
		*err = -ENODATA;
		return NULL;
	}
	s->begins++;
	s->result[buffer] = 1;
	return s->vols[buffer];
}

static inline void sink_end(void *data, uint32_t buffer, int err)
{
	struct test_sink *s = data;
	s->last_err = err;
	if (buffer == PROJWIRE_NO_BUFFER) {
		CHECK(err < 0);
		s->stray_errors++;
		return;
	}
	CHECK(buffer < BUFFERS);
	s->ends++;
	s->result[buffer] = err;
}

static const struct projwire_sink sink_impl = { .begin = sink_begin, .end = sink_end };

struct rig {
	struct test_sink sink;
	struct projwire_decoder *dec;
	struct volume *src;
};

static inline void rig_init(struct rig *r)
{
	memset(r, 0, sizeof(*r));
	for (int i = 0; i < BUFFERS; i++) {
		r->sink.vols[i] = volume_create(&geom);
		CHECK(r->sink.vols[i]);
		r->sink.result[i] = 1;
	}
	r->src = volume_create(&geom);
	CHECK(r->src);
	r->dec = projwire_decoder_create(&geom, BUFFERS, 0, &sink_impl, &r->sink);
	CHECK(r->dec);
}

static inline void rig_finish(struct rig *r)
{
	projwire_decoder_destroy(r->dec);
	for (int i = 0; i < BUFFERS; i++)
		volume_destroy(r->sink.vols[i]);
	volume_destroy(r->src);
}

/* Encodes r->src for buffer into a new allocation. */
static inline uint8_t *encode(struct rig *r, uint32_t buffer, size_t *len)
{
	size_t size = projwire_volume_size(r->src);
	uint8_t *out = malloc(size);
	CHECK(out);
	*len = projwire_volume_encode(r->src, buffer, out);
	CHECK_EQ(*len, size);
	return out;
}

/* Feeds in random chunks (1 to max bytes); returns the first error. */
static inline int feed_chunked(struct projwire_decoder *d, const uint8_t *buf, size_t len, size_t max)
{
	int first = 0;
	while (len) {
		size_t n = 1 + rnd_below((uint32_t)max);
		if (n > len)
			n = len;
		int r = projwire_decoder_feed(d, buf, n);
		if (r < 0 && !first)
			first = r;
		buf += n;
		len -= n;
	}
	return first;
}

#endif
