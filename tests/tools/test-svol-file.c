/* .svol round trip through a real file: svol_write -> svol_read gives the
 * same geometry, sequence, time and voxels; the header decodes and the file
 * has the size the format says. argv[1]: scratch file path. */
#include <string.h>

#include "svol.h"
#include "testvol.h"

static struct volume *make_volume(const char *profile)
{
	struct geometry g;
	CHECK(geometry_from_profile(profile, &g) == 0);
	struct testvol *tv = testvol_create(&g);
	uint32_t seed = 12345;
	for (int i = 0; i < 5000; i++) {
		seed = seed * 1103515245u + 12345u;
		uint32_t k = (seed >> 8) % tv->images;
		seed = seed * 1103515245u + 12345u;
		uint32_t u = (seed >> 8) % g.width;
		seed = seed * 1103515245u + 12345u;
		uint32_t v = (seed >> 8) % g.height;
		testvol_set(tv, k, u, v, 1u + (seed >> 4) % 7u);
	}
	struct volume *vol = testvol_to_volume(tv);
	testvol_destroy(tv);
	vol->seq = 0x0123456789abcdefull;
	vol->shown_ns = 987654321012345ull;
	return vol;
}

static void check_same(const struct volume *a, const struct volume *b)
{
	CHECK(memcmp(&a->geom.width, &b->geom.width, sizeof(uint32_t) * 3) == 0);
	CHECK(a->geom.mirrored == b->geom.mirrored);
	CHECK(a->geom.half_height == b->geom.half_height);
	CHECK(a->image_count == b->image_count && a->seq == b->seq && a->shown_ns == b->shown_ns);
	size_t n = volume_dense_image_bytes(a);
	uint8_t *da = malloc(n), *db = malloc(n);
	CHECK(da && db);
	for (uint32_t k = 0; k < a->image_count; k++) {
		volume_image_to_dense(a, k, da);
		volume_image_to_dense(b, k, db);
		CHECK(memcmp(da, db, n) == 0);
	}
	free(da);
	free(db);
}

static void round_trip(const char *profile, const char *path)
{
	struct volume *vol = make_volume(profile);
	FILE *f = fopen(path, "wb");
	CHECK(f);
	CHECK(svol_write(f, vol) == 0);
	CHECK(fclose(f) == 0);

	f = fopen(path, "rb");
	CHECK(f);
	uint8_t raw[SVOL_HEADER_SIZE];
	struct svol_header hdr;
	CHECK(fread(raw, 1, sizeof(raw), f) == sizeof(raw));
	CHECK(memcmp(raw, "SVOL", 4) == 0);
	CHECK(svol_header_decode(raw, &hdr) == 0);
	CHECK(fseek(f, 0, SEEK_END) == 0);
	CHECK((uint64_t)ftell(f) == svol_file_size(&hdr));
	rewind(f);
	struct volume *back = svol_read(f);
	CHECK(back);
	fclose(f);
	check_same(vol, back);
	printf("%s: %u images, %llu bytes, identical\n", profile, hdr.image_count,
	       (unsigned long long)svol_file_size(&hdr));
	volume_destroy(back);
	volume_destroy(vol);
	remove(path);
}

int main(int argc, char **argv)
{
	CHECK(argc == 2);
	round_trip("small", argv[1]);
	round_trip("perspecta", argv[1]);
	return 0;
}
