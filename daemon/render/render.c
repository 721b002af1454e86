#include "render.h"

#include <errno.h>
#include <string.h>

#include "log.h"

struct renderer *render_create(const char *name, const struct geometry *geom, unsigned threads)
{
	struct render_gl_options gl = { .backend = name, .threads = threads };
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

/* Entry (x, y) of the 16x16 Bayer index matrix, 0..255: bit-reverse of the
 * interleaved bits of x ^ y and y (recursive Bayer construction). */
static unsigned bayer16(unsigned x, unsigned y)
{
	unsigned a = (x ^ y) & 15, b = y & 15, v = 0;
	for (int i = 0; i < 4; i++) {
		v |= ((a >> i) & 1u) << (7 - 2 * i);
		v |= ((b >> i) & 1u) << (6 - 2 * i);
	}
	return v;
}

uint8_t render_dither_threshold(uint32_t k, uint32_t u, uint32_t v)
{
	/* Phase: image k shifts the matrix by p = 97 k mod 256 (x by p % 16, y
	 * by p / 16). 97 is odd, so any 256 consecutive images all differ, and
	 * neighbouring images are offset by (1, 6): no two adjacent slices light
	 * the same pixels of a mid-grey area. */
	uint32_t p = (k * 97u) & 255u;
	unsigned idx = bayer16((u + (p & 15u)) & 15u, (v + (p >> 4)) & 15u);
	/* 0..255 -> 0..254, so 0 is never lit and 255 always. */
	return (uint8_t)((idx * 255u) >> 8);
}
