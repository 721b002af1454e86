/* Renderers: take a scene snapshot, produce a packed tile-sparse volume.
 *
 * Every renderer lights, for each image k of the volume, the voxels of
 * docs/design.md section 3: both lobes of image k's bow tie, colours combined per
 * channel by MAX, then ordered-dithered to 1 bit per channel with a threshold
 * phase that depends on k only (halftone.h), and packed. Image k + N/2 of a
 * mirrored device is never rendered: the hardware mirrors image k.
 *
 * This header is the renderers' whole interface: the base and its calls
 * (renderer.h), the CPU (render_cpu.h) and GL (render_gl.h) renderers, and
 * render_create(), which picks one of them by name. */
#ifndef SPINDLE_RENDER_H
#define SPINDLE_RENDER_H

#include "render_cpu.h"
#include "render_gl.h"
#include "renderer.h"

/* Picks a renderer by name ("cpu", "egl", "osmesa", "auto"), with up to threads worker
 * threads (0 = one per core). NULL + errno (ENOENT: unknown or not built)
 * on failure. */
struct renderer *render_create(const char *name, const struct geometry *geom, unsigned threads);

#endif
