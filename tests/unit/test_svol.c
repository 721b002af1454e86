/* common/svol: the 64-byte header at exactly docs/design.md's byte offsets
 * (little-endian), rejection of malformed headers, and file round trips. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "svol.h"

static uint32_t le32(const uint8_t *p)
{
	return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t le64(const uint8_t *p)
{
	return le32(p) | (uint64_t)le32(p + 4) << 32;
}

static bool zero(const uint8_t *p, size_t n)
{
	for (size_t i = 0; i < n; i++)
		if (p[i])
			return false;
	return true;
}

static void check_header_layout(void)
{
	struct svol_header h = {
		.width = 0x01020304,
		.height = 0x0a0b0c0d,
		.image_count = 198,
		.images_per_rev = 396,
		.planes = 3,
		.flags = SVOL_FLAG_MIRRORED,
		.half_height = 0.75f,
		.seq = 0x1122334455667788ull,
		.shown_ns = 0x99aabbccddeeff00ull
	};
	uint8_t b[SVOL_HEADER_SIZE];
	memset(b, 0xff, sizeof(b));
	svol_header_encode(&h, b);
	CHECK(memcmp(b, "SVOL", 4) == 0);
	CHECK(b[4] == 1 && b[5] == 0);  /* version, u16 */
	CHECK(b[6] == 64 && b[7] == 0); /* header size, u16 */
	CHECK(b[8] == 0x04 && b[9] == 0x03 && b[10] == 0x02 && b[11] == 0x01);
	CHECK(le32(b + 12) == 0x0a0b0c0d);
	CHECK(le32(b + 16) == 198);
	CHECK(le32(b + 20) == 396);
	CHECK(b[24] == 3);
	CHECK(b[25] == 1);
	CHECK(zero(b + 26, 2));
	CHECK(le32(b + 28) == 0x3f400000u); /* 0.75f */
	CHECK(le64(b + 32) == 0x1122334455667788ull);
	CHECK(le64(b + 40) == 0x99aabbccddeeff00ull);
	CHECK(zero(b + 48, 16));
	struct svol_header d;
	CHECK(svol_header_decode(b, &d) == 0);
	CHECK(d.width == h.width && d.height == h.height && d.image_count == 198 && d.images_per_rev == 396 &&
	      d.planes == 3 && d.flags == 1 && d.half_height == 0.75f && d.seq == h.seq && d.shown_ns == h.shown_ns);
	CHECK(svol_file_size(&h) == 64 + 198ull * 3 * 0x0a0b0c0d * ((0x01020304ull + 7) / 8));
	const int bad_at[] = { 0, 3, 4, 5, 6, 7, 24, 16, 25 };
	for (size_t i = 0; i < sizeof(bad_at) / sizeof(bad_at[0]); i++) {
		uint8_t c[SVOL_HEADER_SIZE];
		memcpy(c, b, sizeof(c));
		c[bad_at[i]] ^= 0x01; /* byte 25: unmirrored then wants 396 images */
		CHECK_MSG(svol_header_decode(c, &d) == -EINVAL, "corrupt byte %d accepted", bad_at[i]);
	}
}

static void fill(struct volume *v, uint32_t seed)
{
	for (uint32_t k = 0; k < v->image_count; k += 3)
		for (uint32_t t = k % 2; t < volume_tiles_per_image(v); t += 2) {
			uint8_t tile[VOLUME_TILE_BYTES] = { 0 };
			uint32_t x0 = (t % v->tiles_x) * 32, y0 = (t / v->tiles_x) * 32;
			for (uint32_t i = 0; i < 40; i++) {
				seed = seed * 1664525u + 1013904223u;
				uint32_t x = (seed >> 8) % 32, y = (seed >> 16) % 32, c = (seed >> 28) % 3;
				if (x0 + x < v->geom.width && y0 + y < v->geom.height)
					tile[c * 128 + y * 4 + x / 8] |= (uint8_t)(0x80 >> (x % 8));
			}
			volume_image_append(v, k, t, tile);
		}
}

static void check_round_trip(const struct geometry *g)
{
	struct volume *v = volume_create(g);
	fill(v, 5);
	v->seq = 42;
	v->shown_ns = 123456789;
	FILE *f = tmpfile();
	CHECK(svol_write(f, v) == 0);
	long size = ftell(f);
	uint8_t hdr[SVOL_HEADER_SIZE];
	rewind(f);
	CHECK(fread(hdr, 1, sizeof(hdr), f) == sizeof(hdr));
	struct svol_header h;
	CHECK(svol_header_decode(hdr, &h) == 0);
	CHECK(size >= 0 && (uint64_t)size == svol_file_size(&h));
	CHECK(h.image_count == v->image_count && h.flags == (g->mirrored ? 1 : 0));
	/* Image 0's dense planes start right after the header. */
	size_t n = volume_dense_image_bytes(v);
	uint8_t *want = malloc(n), *got = malloc(n);
	volume_image_to_dense(v, 0, want);
	CHECK(fread(got, 1, n, f) == n && memcmp(want, got, n) == 0);
	rewind(f);
	struct volume *r = svol_read(f);
	CHECK(r && r->seq == 42 && r->shown_ns == 123456789 && r->image_count == v->image_count);
	CHECK(r && r->geom.width == g->width && r->geom.height == g->height && r->geom.mirrored == g->mirrored &&
	      r->geom.half_height == g->half_height);
	for (uint32_t k = 0; r && k < v->image_count; k++) {
		volume_image_to_dense(v, k, want);
		volume_image_to_dense(r, k, got);
		CHECK_MSG(memcmp(want, got, n) == 0, "image %u differs", k);
		CHECK(r->images[k].tile_count == v->images[k].tile_count);
	}
	volume_destroy(r);
	fclose(f);
	/* Truncated: rejected. */
	f = tmpfile();
	CHECK(svol_write(f, v) == 0);
	CHECK(fflush(f) == 0);
	CHECK(ftruncate(fileno(f), (off_t)(svol_file_size(&h) - 1)) == 0);
	rewind(f);
	errno = 0;
	CHECK(svol_read(f) == NULL && errno == EINVAL);
	fclose(f);
	free(want);
	free(got);
	volume_destroy(v);
}

int main(void)
{
	struct geometry small, odd = { 100, 72, 50, false, 0.75f, 600.0f, GEOMETRY_BRIGHTNESS_EXACT };
	geometry_from_profile("small", &small);
	check_header_layout();
	check_round_trip(&small);
	check_round_trip(&odd);
	return check_done();
}
