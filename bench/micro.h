/* Single-thread microbenchmarks that put the renderer's figures in context:
 * the machine's memcpy bandwidth and the throughput of each halftone+pack
 * variant (daemon/render/halftone.h). */
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

#endif
