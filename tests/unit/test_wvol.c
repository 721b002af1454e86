/* common/wvol: the watch volume layout of docs/formats.md (header offsets,
 * per image count, padded mask and tiles), round trips bit for bit, and
 * rejection of malformed or truncated input. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "wvol.h"

static uint32_t le32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* A volume of the small profile with some tiles lit in some images. */
static struct volume *sample(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	struct volume *vol = volume_create(&g);
	CHECK(vol != NULL);
	vol->seq = 42;
	uint8_t tile[VOLUME_TILE_BYTES];
	uint32_t seed = 1;
	for (uint32_t k = 0; k < vol->image_count; k += 3) {
		for (uint32_t t = k % 5; t < volume_tiles_per_image(vol); t += 7) {
			for (size_t i = 0; i < sizeof(tile); i++) {
				seed = seed * 1103515245u + 12345u;
				tile[i] = (uint8_t)(seed >> 16) & (uint8_t)(seed >> 8);
			}
			CHECK(volume_image_append(vol, k, t, tile) == 0);
		}
	}
	return vol;
}

static void check_round_trip(void)
{
	struct volume *vol = sample();
	uint64_t n = wvol_size(vol);
	uint8_t *buf = malloc(n);
	CHECK(buf != NULL);
	wvol_encode(vol, buf);
	CHECK(memcmp(buf, "SPWV", 4) == 0 && buf[4] == WVOL_VERSION && buf[6] == WVOL_HEADER_SIZE);
	CHECK_EQ(le32(buf + 8), vol->geom.width);
	CHECK_EQ(le32(buf + 16), vol->image_count);
	CHECK_EQ(le32(buf + 48), vol->tiles_x);
	CHECK_EQ(le32(buf + 56), vol->mask_bytes);
	CHECK_EQ(le32(buf + 60), (uint32_t)volume_tile_count(vol));
	CHECK_EQ(le32(buf + 64), vol->images[0].tile_count); /* image 0's count comes first */
	CHECK_EQ(n, WVOL_HEADER_SIZE + vol->image_count * (4 + ((vol->mask_bytes + 3) & ~3u)) +
			    volume_tile_count(vol) * VOLUME_TILE_BYTES);
	struct volume *back = wvol_decode(buf, n);
	CHECK(back != NULL);
	CHECK_EQ(back->seq, 42u);
	CHECK_EQ(volume_tile_count(back), volume_tile_count(vol));
	size_t dense = volume_dense_image_bytes(vol);
	uint8_t *a = malloc(dense), *b = malloc(dense);
	for (uint32_t k = 0; k < vol->image_count; k++) {
		volume_image_to_dense(vol, k, a);
		volume_image_to_dense(back, k, b);
		CHECK_MSG(memcmp(a, b, dense) == 0, "image %u differs", k);
	}
	volume_destroy(back);
	/* Truncated, grown, a wrong count or magic: refused. */
	errno = 0;
	CHECK(wvol_decode(buf, n - 1) == NULL && errno == EINVAL);
	CHECK(wvol_decode(buf, 40) == NULL && errno == EINVAL);
	buf[64] ^= 1;
	CHECK(wvol_decode(buf, n) == NULL && errno == EINVAL);
	buf[64] ^= 1;
	buf[0] = 'X';
	CHECK(wvol_decode(buf, n) == NULL && errno == EINVAL);
	free(a);
	free(b);
	free(buf);
	volume_destroy(vol);
}

static void check_empty(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("perspecta", &g) == 0);
	struct volume *vol = volume_create(&g);
	uint64_t n = wvol_size(vol);
	CHECK_EQ(n, 64u + 198u * (4u + 72u)); /* docs/formats.md: some 15 KiB */
	uint8_t *buf = malloc(n);
	wvol_encode(vol, buf);
	struct volume *back = wvol_decode(buf, n);
	CHECK(back != NULL && volume_tile_count(back) == 0);
	volume_destroy(back);
	volume_destroy(vol);
	free(buf);
}

int main(void)
{
	check_round_trip();
	check_empty();
	return check_done();
}
