/* The renderer base every implementation embeds (render_cpu.c, render_gl.c)
 * and the calls on it: what render.h's callers use on a renderer, whichever
 * one render_create() picked; and each renderer's options. */
#ifndef SPINDLE_RENDERER_H
#define SPINDLE_RENDERER_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry.h"
#include "scene.h"
#include "volume.h"

struct renderer;
struct rle_volume;

/* What the last render cost and produced. Times in ns; the per-stage times
 * are summed over the threads that ran them (divide by threads for a wall
 * share), total_ns is wall time. */
/* What produced a volume. Renderers of one engine give bit-identical
 * volumes; of different engines, not (a GL renderer that hands a scene to
 * its CPU fallback gives the CPU renderer's volume). */
enum render_engine {
	RENDER_ENGINE_CPU = 1,
	RENDER_ENGINE_GL = 2,
};

struct render_stats {
	enum render_engine engine; /* of the last volume */
	uint64_t total_ns;         /* wall: the whole render_volume() call */
	uint64_t bin_ns;           /* transform + outcodes + binning + sort */
	uint64_t raster_ns;        /* sectioning and conservative raster */
	uint64_t pack_ns;          /* halftone + pack + canvas clear */
	uint64_t prims;            /* primitives after transform (finite) */
	uint64_t prim_images;      /* (primitive, image) pairs sectioned */
	uint64_t bins_kept;        /* passes that found their binning kept
				    * from the last (render_cpu_options.keep) */
	uint64_t canvas_tiles;     /* tiles halftoned (something touched them) */
	uint64_t tiles;            /* non-empty tiles packed */
	unsigned threads;          /* threads that rendered images */
};

/* CPU renderer variants, for tests and benchmarks: every variant gives
 * bit-identical output. */
struct render_cpu_options {
	unsigned threads; /* worker threads; 0 = one per core */
	const char *simd; /* halftone+pack variant: NULL or "auto" (best this
			      * CPU runs), "scalar", "sse2", "avx2", "avx512" */
	bool keep;        /* keep the binning of a scene whose draws are the
			      * same as the last render's, data ids included
			      * (scene_draw.data_id): render_cpu_create() does */
};

/* GL renderer options (render_gl.c). */
struct render_gl_options {
	const char *backend;     /* "egl" (default when NULL) or "osmesa" */
	unsigned threads;        /* binning threads; 0 = one per core */
	unsigned batch;          /* images per batch; 0 = as many as fit, at most 16 */
	bool naive;              /* the unoptimised baseline the benchmark measures
			      * against: every primitive in every image, RGBA
			      * read back whole, halftone and pack on the CPU */
	bool no_fallback;        /* a GL failure fails the render instead of
			      * handing over to the CPU renderer (tests) */
	bool hardware_only;      /* fail (ENODEV) on a software rasterizer, before
			      * building shaders: what "auto" asks for */
	uint32_t max_prims;      /* binned primitives a volume may have on GL; more
			      * render that volume on the CPU. 0 = as many as
			      * the primitive texture holds (tests set less) */
	bool keep;               /* keep the binning while the scene's draws stay
			      * the same (render_cpu_options.keep) */
	uint64_t max_grid_bytes; /* bytes of grid textures a volume may need on
				  * GL; more render that volume on the CPU. 0 =
				  * GL_GRID_BUDGET, 1 GiB (tests set less) */
};

struct renderer_impl {
	const char *name;
	/* Renders scene into out (same geometry as the renderer; out is
	 * cleared first). Returns 0 or negative errno; out is then unusable. */
	int (*render)(struct renderer *r, const struct scene *scene, struct volume *out);
	/* Optional (the CPU renderer): renders scene up to the halftone, into
	 * out's images (a coded volume of CANVAS_TILE_BYTES tiles, compose.h,
	 * of the renderer's geometry; its images are replaced, then summed):
	 * what the object cache turns (compose_turned()). Halftoned at image
	 * k's phase, image k of out is image k of render(). 0 or negative
	 * errno. */
	int (*render_canvas)(struct renderer *r, const struct scene *scene, struct rle_volume *out);
	/* Optional (the CPU renderer): a new renderer of r's engine and
	 * geometry that renders on the calling thread alone, bit for bit as
	 * r does: several render small scenes side by side (batch.h). NULL +
	 * errno on failure. */
	struct renderer *(*serial)(const struct renderer *r);
	void (*destroy)(struct renderer *r);
};

/* Base struct, embedded first in each implementation. */
struct renderer {
	const struct renderer_impl *impl;
	struct geometry geom;
	/* Scenes of more segments and triangles than this are rendered by
	 * another engine (a GL renderer's CPU fallback); 0: no limit. */
	uint64_t native_prims;
	struct render_stats stats; /* of the last render */
	/* Its workers, or NULL: its caller may run jobs of its own on them
	 * between renders (they are still looking for work right after one:
	 * pool.h). */
	struct pool *pool;
};

static inline int render_volume(struct renderer *r, const struct scene *s, struct volume *out)
{
	return r->impl->render(r, s, out);
}

/* s rendered into out moved by (du, dv) whole pixels (volume_shift(), the
 * calibration's axis offset): straight into out without one, else into
 * scratch first. */
static inline int render_volume_moved(struct renderer *r, const struct scene *s, struct volume *scratch,
				      struct volume *out, int32_t du, int32_t dv)
{
	if (!du && !dv)
		return render_volume(r, s, out);
	int err = render_volume(r, s, scratch);
	return err < 0 ? err : volume_shift(out, scratch, du, dv);
}

/* Accepts NULL. */
static inline void render_destroy(struct renderer *r)
{
	if (r)
		r->impl->destroy(r);
}

#endif
