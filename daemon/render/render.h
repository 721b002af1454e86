/* Renderers: take a scene snapshot, produce a packed tile-sparse volume.
 *
 * Every renderer lights, for each image k of the volume, the voxels of
 * DESIGN.md section 3: both lobes of image k's bow tie, colours combined per
 * channel by MAX, then ordered-dithered to 1 bit per channel with a threshold
 * phase that depends on k only, and packed. Image k + N/2 of a mirrored device
 * is never rendered: the hardware mirrors image k. */
#ifndef SPINDLE_RENDER_H
#define SPINDLE_RENDER_H

#include <stdbool.h>

#include "geometry.h"
#include "scene.h"
#include "volume.h"

struct renderer;

/* What the last render cost and produced. Times in ns; the per-stage times
 * are summed over the threads that ran them (divide by threads for a wall
 * share), total_ns is wall time. */
struct render_stats {
	uint64_t total_ns;     /* wall: the whole render_volume() call */
	uint64_t bin_ns;       /* transform + outcodes + binning + sort */
	uint64_t raster_ns;    /* sectioning and conservative raster */
	uint64_t pack_ns;      /* halftone + pack + canvas clear */
	uint64_t prims;        /* primitives after transform (finite) */
	uint64_t prim_images;  /* (primitive, image) pairs sectioned */
	uint64_t canvas_tiles; /* tiles halftoned (something touched them) */
	uint64_t tiles;        /* non-empty tiles packed */
	unsigned threads;      /* threads that rendered images */
};

/* CPU renderer variants, for tests and benchmarks: every variant gives
 * bit-identical output. */
struct render_cpu_options {
	unsigned threads;    /* worker threads; 0 = one per core */
	const char *simd;    /* halftone+pack variant: NULL or "auto" (best this
			      * CPU runs), "scalar", "sse2", "avx2", "avx512" */
};

/* GL renderer options (render_gl.c). */
struct render_gl_options {
	const char *backend; /* "egl" (default when NULL) or "osmesa" */
	unsigned threads;    /* binning threads; 0 = one per core */
	unsigned batch;      /* images per batch; 0 = as many as fit, at most 16 */
	bool naive;          /* the unoptimised baseline the benchmark measures
			      * against: every primitive in every image, RGBA
			      * read back whole, halftone and pack on the CPU */
	bool no_fallback;    /* a GL failure fails the render instead of
			      * handing over to the CPU renderer (tests) */
	bool hardware_only;  /* fail (ENODEV) on a software rasterizer, before
			      * building shaders: what "auto" asks for */
	uint32_t max_prims;  /* binned primitives a volume may have on GL; more
			      * render that volume on the CPU. 0 = as many as
			      * the primitive texture holds (tests set less) */
};

struct renderer_impl {
	const char *name;
	/* Renders scene into out (same geometry as the renderer; out is
	 * cleared first). Returns 0 or negative errno; out is then unusable. */
	int (*render)(struct renderer *r, const struct scene *scene, struct volume *out);
	void (*destroy)(struct renderer *r);
};

/* Base struct, embedded first in each implementation. */
struct renderer {
	const struct renderer_impl *impl;
	struct geometry geom;
	struct render_stats stats; /* of the last render */
};

/* The exact CPU sectioning renderer, using up to threads worker threads
 * (0 = one per core). NULL + errno on failure. */
struct renderer *render_cpu_create(const struct geometry *geom, unsigned threads);
/* The same with explicit options (ENOENT: simd variant unknown or not
 * runnable on this CPU). */
struct renderer *render_cpu_create_opts(const struct geometry *geom,
					const struct render_cpu_options *opts);

/* The GL pipeline of DESIGN.md section 5 on an EGL (surfaceless or device)
 * or OSMesa context. NULL + errno when there is no usable context or a
 * shader does not build (ENOENT: backend not built in), with a log line
 * saying why. After a failure while rendering (context lost, GL error, a
 * fence that never signals) it logs why and renders on the CPU from then
 * on, unless opts->no_fallback. */
struct renderer *render_gl_create(const struct geometry *geom, const struct render_gl_options *opts);
/* GL_RENDERER and GL_VERSION of a GL renderer's context ("" otherwise). */
const char *render_gl_describe(const struct renderer *r);

/* Picks a renderer by name ("cpu", "egl", "osmesa", "auto"), with up to threads worker
 * threads (0 = one per core). NULL + errno (ENOENT: unknown or not built)
 * on failure. */
struct renderer *render_create(const char *name, const struct geometry *geom, unsigned threads);

static inline int render_volume(struct renderer *r, const struct scene *s, struct volume *out)
{
	return r->impl->render(r, s, out);
}

/* Accepts NULL. */
static inline void render_destroy(struct renderer *r)
{
	if (r)
		r->impl->destroy(r);
}

/* The ordered-dither threshold (0..254) of pixel (u, v) in image k: a pixel
 * of channel value c is lit iff c > threshold. 0 is never lit, 255 always. */
uint8_t render_dither_threshold(uint32_t k, uint32_t u, uint32_t v);

#endif
