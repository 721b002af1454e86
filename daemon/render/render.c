#include "render.h"

#include <errno.h>
#include <string.h>

#include "log.h"

struct renderer *render_create(const char *name, const struct geometry *geom, unsigned threads)
{
	struct render_gl_options gl = { .backend = name, .threads = threads, .keep = true };
	if (name && (!strcmp(name, "egl") || !strcmp(name, "osmesa")))
		return render_gl_create(geom, &gl);
	if (name && strcmp(name, "auto") != 0 && strcmp(name, "cpu") != 0) {
		errno = ENOENT;
		return NULL;
	}
	if (!name || !strcmp(name, "auto")) {
		/* EGL on a hardware GPU. Without one, EGL and OSMesa run on
		 * llvmpipe, which docs/performance.md measures slower than
		 * the CPU renderer on every scene: take the CPU renderer. */
		gl.backend = "egl";
		gl.hardware_only = true;
		struct renderer *r = render_gl_create(geom, &gl);
		if (r)
			return r;
		log_info("renderer auto: no hardware GPU for EGL: the CPU renderer (faster than a "
			 "software rasterizer, docs/performance.md)");
	}
	return render_cpu_create(geom, threads);
}
