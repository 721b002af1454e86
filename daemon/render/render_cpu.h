/* The exact CPU sectioning renderer (render_cpu.c). */
#ifndef SPINDLE_RENDER_CPU_H
#define SPINDLE_RENDER_CPU_H

#include "renderer.h"

/* The exact CPU sectioning renderer, using up to threads worker threads
 * (0 = one per core). NULL + errno on failure. */
struct renderer *render_cpu_create(const struct geometry *geom, unsigned threads);
/* The same with explicit options (ENOENT: simd variant unknown or not
 * runnable on this CPU). */
struct renderer *render_cpu_create_opts(const struct geometry *geom, const struct render_cpu_options *opts);

#endif
