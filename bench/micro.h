/* Single-thread microbenchmarks that put the renderer's figures in context:
 * the machine's memcpy bandwidth, the throughput of each halftone+pack
 * variant (daemon/render/halftone.h), and the calibration's shift of a
 * volume (volume_shift()). */
#ifndef SPINDLE_BENCH_MICRO_H
#define SPINDLE_BENCH_MICRO_H

#include <stddef.h>
#include <stdint.h>

#include "halftone.h"

/* memcpy of bytes between two buffers touched beforehand, median of runs
 * runs, in GB/s (1e9 bytes copied per second; each byte counted once).
 * Negative when the buffers can't be allocated. */
double micro_memcpy_gbps(size_t bytes, int runs);

/* fn over tiles random canvas tiles with all 32 rows set, median of runs
 * passes, in GB/s of canvas (HALFTONE_TILE_BYTES = 3072 bytes per tile).
 * Negative when the buffers can't be allocated. */
double micro_halftone_gbps(halftone_fn fn, uint32_t tiles, int runs);

/* volume_shift() (the calibration's axis offset) of a volume of geometry g
 * whose images each hold every tile with probability fill (random bits),
 * by (du, dv); median of runs, in ms per volume, and the volume's stored
 * tiles in *tiles. Negative when out of memory. */
struct geometry;
double micro_shift_ms(const struct geometry *g, double fill, int32_t du, int32_t dv, int runs, uint64_t *tiles);

#endif
