/* The .svol capture format (docs/design.md section 3, binding): a 64-byte
 * little-endian header, then for each image, planes R, G, B of H rows of
 * ceil(W/8) bytes, MSB = leftmost pixel. */
#ifndef SPINDLE_SVOL_H
#define SPINDLE_SVOL_H

#include <stdint.h>
#include <stdio.h>

#include "volume.h"

#define SVOL_HEADER_SIZE 64
#define SVOL_VERSION 1
#define SVOL_FLAG_MIRRORED 0x01

struct svol_header {
	uint32_t width, height;
	uint32_t image_count;    /* images in this file */
	uint32_t images_per_rev; /* N */
	uint8_t planes;          /* 3 */
	uint8_t flags;
	float half_height;
	uint64_t seq;
	uint64_t shown_ns;
};

/* Encodes/decodes the 64-byte header. Decode returns 0, or -EINVAL for a
 * header that is not a valid version 1 .svol header. */
void svol_header_encode(const struct svol_header *h, uint8_t out[SVOL_HEADER_SIZE]);
int svol_header_decode(const uint8_t in[SVOL_HEADER_SIZE], struct svol_header *h);

/* Size of the whole file described by h. */
uint64_t svol_file_size(const struct svol_header *h);

/* Bytes of vol as an .svol file, and the file written into out (which has
 * that many). */
uint64_t svol_size(const struct volume *vol);
void svol_encode(const struct volume *vol, uint8_t *out);

/* Writes vol as an .svol stream. Returns 0 or negative errno. */
int svol_write(FILE *f, const struct volume *vol);

/* Reads an .svol stream into a new volume (sequence and time kept).
 * NULL + errno (EINVAL for a malformed file) on failure. */
struct volume *svol_read(FILE *f);

#endif
