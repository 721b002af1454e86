/* The watch volume layout (docs/formats.md, "Watch volumes"): a volume as
 * display.watch sends it, sparse, in the daemon's own packed tile form
 * (volume.h). A 64-byte little-endian header, then for each image a u32
 * tile count, its occupancy mask (mask_bytes, zero-padded to a multiple of
 * 4) and its stored tiles (tile count x 384 bytes: planes R, G, B of 32
 * rows of 4 bytes, MSB = leftmost pixel), in increasing tile number. */
#ifndef SPINDLE_WVOL_H
#define SPINDLE_WVOL_H

#include <stddef.h>
#include <stdint.h>

#include "volume.h"

#define WVOL_HEADER_SIZE 64
#define WVOL_VERSION 1
#define WVOL_FLAG_MIRRORED 0x01

/* Bytes wvol_encode() writes for vol. */
uint64_t wvol_size(const struct volume *vol);
/* Writes vol into out, which has wvol_size(vol) bytes. */
void wvol_encode(const struct volume *vol, uint8_t *out);
/* Whether buf starts like a watch volume (its magic). */
int wvol_is(const uint8_t *buf, size_t size);
/* Decodes a watch volume of exactly size bytes into a new volume (seq and
 * shown_ns kept). NULL + errno (EINVAL: malformed, ENOMEM). */
struct volume *wvol_decode(const uint8_t *buf, size_t size);

#endif
