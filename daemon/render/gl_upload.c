/* The GL renderer's input (gl_upload.h). */
#include "gl_upload.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "bin.h"
#include "pool.h"
#include "render_gl_priv.h"

GLuint gl_make_texture(const struct gl_api *gl, GLenum fmt, uint32_t w, uint32_t h)
{
	GLuint t;
	gl->GenTextures(1, &t);
	gl->BindTexture(GL_TEXTURE_2D, t);
	gl->TexStorage2D(GL_TEXTURE_2D, 1, fmt, (GLsizei)w, (GLsizei)h);
	gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
	gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
	return t;
}

/* Rearranges primitives [begin, end) of the bins into the texture layout
 * of gl_shaders.h: each vertex in a texel of its own, with the two words of
 * flags in the texels' fourth components. */
static uint32_t stage_prims(const struct bin_prim *src, uint32_t *dst, uint32_t begin, uint32_t end)
{
	uint32_t triangles = 0;
	for (uint32_t i = begin; i < end; i++) {
		const uint32_t *w = (const uint32_t *)&src[i];
		triangles += src[i].nverts == 3;
		uint32_t *d = dst + (size_t)i * 12;
		memcpy(d, w, 12);
		d[3] = w[9];
		memcpy(d + 4, w + 3, 12);
		d[7] = w[10];
		memcpy(d + 8, w + 6, 12);
		d[11] = 0;
	}
	return triangles;
}

struct stage_job {
	const struct bin_set *bins;
	uint32_t *dst;
	unsigned workers;
	atomic_uint triangles;
};

static void stage_worker(void *arg, unsigned worker)
{
	struct stage_job *j = arg;
	uint64_t n = j->bins->prim_count;
	uint32_t t = stage_prims(j->bins->prims, j->dst, (uint32_t)(n * worker / j->workers),
				 (uint32_t)(n * (worker + 1) / j->workers));
	atomic_fetch_add(&j->triangles, t);
}

/* Stages the binned primitives in the texture's layout and uploads them. */
static int upload_prims(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct bin_set *b = &r->bins;
	uint64_t texels = (uint64_t)b->prim_count * GL_PRIM_TEXELS;
	uint64_t rows = (texels + r->tex_width - 1) / r->tex_width;
	GLint max_tex = 0;
	gl->GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
	if (rows > (uint64_t)max_tex || (r->opts.max_prims && b->prim_count > r->opts.max_prims))
		return -E2BIG;
	if (b->prim_count > r->staging_cap) {
		size_t cap = b->prim_count + b->prim_count / 2;
		uint32_t *s = realloc(r->staging, cap * GL_PRIM_TEXELS * 16);
		if (!s)
			return -ENOMEM;
		r->staging = s;
		r->staging_cap = cap;
	}
	struct stage_job job = { b, r->staging, pool_workers(r->pool), 0 };
	pool_run(r->pool, stage_worker, &job);
	r->triangles = atomic_load(&job.triangles);
	if (rows < 1)
		rows = 1;
	if (rows > r->tex_rows) {
		uint64_t cap = rows + rows / 2 < (uint64_t)max_tex ? rows + rows / 2 : (uint64_t)max_tex;
		gl->DeleteTextures(1, &r->prim_tex);
		r->prim_tex = gl_make_texture(gl, GL_RGBA32UI, r->tex_width, (uint32_t)cap);
		r->tex_rows = (uint32_t)cap;
	}
	gl->ActiveTexture(GL_TEXTURE0);
	gl->BindTexture(GL_TEXTURE_2D, r->prim_tex);
	uint64_t full = texels / r->tex_width, rest = texels % r->tex_width;
	if (full)
		gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)r->tex_width, (GLsizei)full, GL_RGBA_INTEGER,
				  GL_UNSIGNED_INT, r->staging);
	if (rest)
		gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, (GLint)full, (GLsizei)rest, 1, GL_RGBA_INTEGER, GL_UNSIGNED_INT,
				  r->staging + full * r->tex_width * 4);
	return 0;
}

int gl_upload(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct bin_set *b = &r->bins;
	if (b->kept && r->uploaded)
		return 0;
	r->uploaded = false;
	int err = upload_prims(r);
	if (err < 0)
		return err;
	size_t pbytes = (size_t)b->point_count * sizeof(struct bin_point);
	gl->BindBuffer(GL_ARRAY_BUFFER, r->point_buf);
	gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(pbytes ? pbytes : 8), pbytes ? b->points : NULL, GL_STREAM_DRAW);
	r->uploaded = true;
	return 0;
}
