/* The projector wire codec's delta volumes (1.1): a buffer edited into
 * the next volume is bit for bit that volume; images with equal stamps,
 * and tiles the caller vouches for, are not compared. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "projwire.h"
#include "projwire_rig.h"
#include "volume_diff.h"
#include "volume_util.h"

/* Encodes r->src as a delta against base for buffer, told where tiles
 * may differ (differ, or NULL: anywhere). */
static uint8_t *encode_delta(struct rig *r, const struct volume *base, const uint8_t *differ, uint32_t buffer,
			     size_t *len)
{
	struct projwire_delta plan = { 0 };
	size_t size;
	CHECK(projwire_upload_plan(r->src, base, differ, &plan, &size) == 0);
	uint8_t *out = malloc(size);
	CHECK(out);
	*len = projwire_upload_encode(r->src, base, &plan, buffer, out);
	CHECK_EQ(*len, size);
	projwire_delta_free(&plan);
	return out;
}

/* The start of each delta test: the rig, and base (returned) a random
 * volume (seed) that r->src copies, in buffer already; with stamped, each
 * of base's images stamped first (volume_copy() gives r->src the same). */
static struct volume *delta_start(struct rig *r, uint64_t seed, uint32_t buffer, bool stamped)
{
	rig_init(r);
	struct volume *base = volume_create(&geom);
	CHECK(base);
	random_volume(base, 5, seed);
	CHECK_EQ(base->images[0].stamp, 0u); /* as a writer leaves it */
	for (uint32_t k = 0; stamped && k < base->image_count; k++)
		base->images[k].stamp = volume_new_stamp();
	CHECK_EQ(volume_copy(r->src, base), 0);
	CHECK_EQ(r->src->images[3].stamp, base->images[3].stamp);
	size_t len;
	uint8_t *wire = encode(r, buffer, &len);
	CHECK_EQ(feed_chunked(r->dec, wire, len, 500), 0);
	free(wire);
	return base;
}

/* Delta volumes (1.1): a buffer edited into the next volume is bit for bit
 * that volume, whatever the change; the bytes scale with the change. */
static void test_delta(void)
{
	struct rig r;
	struct volume *base = delta_start(&r, 100, 2, false);
	size_t len, full = projwire_volume_size(base);
	uint8_t *wire;
	for (int i = 0; i < 40; i++) {
		uint32_t permille = i == 0 ? 0 : i < 20 ? 100 : 1 + rnd_below(1000);
		mutate_volume(r.src, base, permille, 101 + (uint64_t)i);
		wire = encode_delta(&r, base, NULL, 2, &len);
		if (permille == 0)
			CHECK_EQ(len, PROJWIRE_DELTA_BEGIN_SIZE + PROJWIRE_END_SIZE);
		if (permille == 100)
			CHECK_MSG(len < full / 4, "10%% change: %zu of %zu bytes", len, full);
		CHECK_EQ(feed_chunked(r.dec, wire, len, i % 2 ? 7 : 4000), 0);
		CHECK_EQ(r.sink.result[2], 0);
		CHECK(volumes_equal(r.sink.vols[2], r.src));
		free(wire);
		CHECK_EQ(volume_copy(base, r.src), 0);
	}
	/* On a base the buffer does not hold: refused, the buffer untouched. */
	mutate_volume(r.src, base, 100, 500);
	base->seq = 77;
	wire = encode_delta(&r, base, NULL, 2, &len);
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), -ENODATA);
	CHECK(r.sink.vols[2]->seq == 140);
	/* A corrupt delta leaves the buffer invalid, never half-edited. */
	base->seq = 140;
	free(wire);
	wire = encode_delta(&r, base, NULL, 2, &len);
	wire[len - 1] ^= 1;
	CHECK_EQ(projwire_decoder_feed(r.dec, wire, len), -EILSEQ);
	CHECK_EQ(r.sink.result[2], -EILSEQ);
	free(wire);
	volume_destroy(base);
	rig_finish(&r);
}

/* The tiles planned for image k of src against base. */
static uint32_t planned_tiles(const struct volume *src, const struct volume *base, uint32_t k)
{
	struct projwire_delta plan = { 0 };
	size_t size;
	CHECK(projwire_upload_plan(src, base, NULL, &plan, &size) == 0);
	CHECK(plan.delta);
	uint32_t n = plan.tiles[k];
	projwire_delta_free(&plan);
	return n;
}

/* Images that carry the same stamp (volume.h) are not compared: the delta
 * of a copy whose one image was redrawn reads that image alone, and is
 * still exact. */
static void test_delta_stamps(void)
{
	struct rig r;
	struct volume *base = delta_start(&r, 200, 1, true);
	CHECK(base->images[1].stamp > base->images[0].stamp);
	size_t len;
	uint8_t *wire;
	/* Image 3 redrawn: its stamp goes, the others' stay. */
	uint8_t tile[VOLUME_TILE_BYTES];
	volume_image_clear(r.src, 3);
	CHECK_EQ(r.src->images[3].stamp, 0u);
	random_tile(r.src, 5, tile);
	CHECK_EQ(volume_image_append(r.src, 3, 5, tile), 0);
	r.src->seq = 201;
	struct projwire_delta plan = { 0 };
	size_t size;
	CHECK(projwire_upload_plan(r.src, base, NULL, &plan, &size) == 0);
	CHECK(plan.delta);
	for (uint32_t k = 0; k < r.src->image_count; k++)
		CHECK_MSG(k == 3 ? plan.tiles[k] > 0 : plan.tiles[k] == 0, "image %u: %u tiles", k, plan.tiles[k]);
	projwire_delta_free(&plan);
	wire = encode_delta(&r, base, NULL, 1, &len);
	CHECK_EQ(feed_chunked(r.dec, wire, len, 300), 0);
	CHECK_EQ(r.sink.result[1], 0);
	CHECK(volumes_equal(r.sink.vols[1], r.src));
	free(wire);
	/* The stamp is trusted, not checked: image 4 changed in place with
	 * its stamp kept is not compared (which is why every writer that
	 * changes tiles in place sets it to 0 first); with the stamp gone it
	 * is. */
	uint32_t k4 = 4;
	while (k4 < r.src->image_count && !r.src->images[k4].tile_count)
		k4++;
	CHECK(k4 < r.src->image_count);
	r.src->images[k4].tiles[0] ^= 0x80;
	CHECK_EQ(planned_tiles(r.src, base, k4), 0u);
	r.src->images[k4].stamp = 0;
	CHECK_EQ(planned_tiles(r.src, base, k4), 1u);
	volume_destroy(base);
	rig_finish(&r);
}

/* Told which tiles may differ (differ), the plan compares no other tile
 * both volumes hold: told every difference it plans the same delta, and
 * the buffer edited is the volume; told none it sends only the tiles one
 * of them lacks. */
static void test_delta_differ(void)
{
	struct rig r;
	struct volume *base = delta_start(&r, 300, 0, false);
	size_t len, size[3], bytes = (size_t)base->image_count * base->mask_bytes;
	uint8_t *wire;
	mutate_volume(r.src, base, 100, 301);
	uint8_t *differ = calloc(bytes, 1), *none = calloc(bytes, 1);
	CHECK(differ && none);
	uint64_t in_place, sums[3] = { 0, 0, 0 };
	volume_differences(r.src, base, NULL, differ, &in_place);
	CHECK(in_place > 0);
	struct projwire_delta plans[3] = { { 0 } };
	const uint8_t *told[3] = { NULL, differ, none };
	for (int i = 0; i < 3; i++) {
		CHECK(projwire_upload_plan(r.src, base, told[i], &plans[i], &size[i]) == 0);
		for (uint32_t k = 0; k < base->image_count; k++)
			sums[i] += plans[i].tiles[k];
	}
	CHECK_EQ(size[1], size[0]);
	CHECK_EQ(sums[1], sums[0]);
	CHECK_EQ(sums[2], sums[0] - in_place);
	wire = encode_delta(&r, base, differ, 0, &len);
	CHECK_EQ(feed_chunked(r.dec, wire, len, 700), 0);
	CHECK_EQ(r.sink.result[0], 0);
	CHECK(volumes_equal(r.sink.vols[0], r.src));
	free(wire);
	for (int i = 0; i < 3; i++)
		projwire_delta_free(&plans[i]);
	free(differ);
	free(none);
	volume_destroy(base);
	rig_finish(&r);
}

int main(void)
{
	test_delta();
	test_delta_stamps();
	test_delta_differ();
	return check_done();
}
