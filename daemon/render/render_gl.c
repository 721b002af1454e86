/* The GL renderer: DESIGN.md section 5's pipeline on OpenGL ES 3.1 (EGL) or
 * desktop OpenGL 4.5 (OSMesa), with the same GLSL.
 *
 * Per volume the CPU bins the scene exactly as the CPU renderer does
 * (bin.h) and uploads the sorted primitives as a texture of raw words and
 * the per-image points as a vertex buffer. Images are drawn in batches into
 * an RGBA8 atlas (image b of a batch at rows b*H .. b*H + H - 1), each with
 * its own projection: a thin slab around the slice plane, seen in
 * perspective from a point on the slice's normal, its sample grid jittered
 * by a sub-pixel offset fixed per image. Per image, only the runs of
 * primitives binned to it are drawn, three ways (gl_shaders.h): faces
 * clipped to the bow tie in the fragment shader, sections with the slice
 * plane as lines and points, and the binned points. Colours combine by MAX
 * blending. A compute pass then halftones, packs and finds the non-empty
 * tiles of the whole batch, compacting them into a buffer the CPU maps once
 * the batch's fence has signalled, while the GPU draws the next batch; only
 * non-empty packed tiles cross back. */
#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bin.h"
#include "gl_context.h"
#include "gl_shaders.h"
#include "log.h"
#include "pool.h"
#include "render.h"

_Static_assert(sizeof(struct bin_prim) == 11 * 4, "bin_prim is 9 vertex words and 2 more");
_Static_assert(sizeof(struct bin_point) == 2 * 4, "the point attribute is two words");

#define GL_MAX_BATCH 16
#define GL_PRIM_TEXELS 3 /* RGBA32UI texels per primitive (gl_shaders.h) */
/* u_frame.w of the section program: which of a primitive's 16 vertex
 * slots a draw covers (gl_shaders.h). */
#define GL_SECTION_SLOTS 0.0f /* 0-3: sections, 4 vertices a primitive */
#define GL_EDGE_SLOTS 1.0f    /* 4-15: triangle edges, 12 a primitive */
/* Half thickness of the slab the fragment shader accepts on the axis, in
 * pixels: the b of t^2 <= (s tau)^2 + b^2. */
#define GL_AXIS_BIAS_PX 0.25
/* Jitter of the sample grid, at most this many pixels either way. */
#define GL_JITTER_PX 0.25
#define GL_FENCE_TIMEOUT_NS 5000000000ull

enum { UNI_IMAGE, UNI_SLICE, UNI_EYE, UNI_FRAME, UNI_PRIMS, UNI_TILE, UNI_COUNT };
static const char *const uniform_names[UNI_COUNT] = { "u_image", "u_slice", "u_eye", "u_frame", "u_prims", "u_tile" };

struct gl_program {
	GLuint id;
	GLint uni[UNI_COUNT];
};

/* One batch's output on the GPU, and what the CPU needs to collect it. */
struct gl_batch {
	GLuint tiles, ids; /* shader storage: packed tiles; count + tile ids */
	GLsync fence;      /* NULL when nothing is pending */
	uint32_t first, n; /* volume images first .. first + n - 1 */
};

struct render_gl {
	struct renderer base;
	struct render_gl_options opts;
	struct gl_context ctx;
	bool have_ctx;
	enum gl_fault fault;
	const struct gl_api *gl;
	struct pool *pool;
	struct bin_set bins;
	uint32_t images, tiles_per_image, batch;

	struct gl_program face, section, point;
	GLuint pack, list;
	GLint pack_uni, pack_colour, list_count;
	GLuint vao, point_buf, prim_tex, atlas, fbo;
	GLuint touched, tile_list; /* tile marks of a batch; touched tiles as a list */
	bool atlas_dirty;          /* a render stopped half-way: clear first */
	uint32_t tex_width, tex_shift, tex_rows;
	uint32_t *staging;  /* primitives in the texture's layout */
	uint32_t triangles; /* of them, triangles: the edge draws are skipped without */
	size_t staging_cap; /* primitives */
	struct gl_batch out[2];
	int32_t *slot_of;   /* per tile of a batch: its slot in the output, or -1 */
	uint8_t *rgba;      /* naive: one image read back */
	uint64_t volumes;

	struct renderer *cpu; /* renders what GL cannot, created when first needed */
	bool gl_dead;         /* GL failed: every volume renders on the CPU */
	bool told_too_big;    /* logged that a scene exceeds the texture */
	char description[300]; /* GL_RENDERER, GL_VERSION */
	/* Per render: */
	struct volume *vol;
	uint64_t wait_ns, copy_ns;
};

static int draw_program(struct render_gl *r, struct gl_program *p, const char *vs, const char *fs,
			const char *what)
{
	bool bad = r->fault == GL_FAULT_SHADER;
	GLuint sh[2] = { gl_shader_compile(r->gl, GL_VERTEX_SHADER, vs, what, bad),
			 gl_shader_compile(r->gl, GL_FRAGMENT_SHADER, fs, what, bad) };
	p->id = gl_program_link(r->gl, sh, 2, what);
	if (!p->id)
		return -EINVAL;
	for (int i = 0; i < UNI_COUNT; i++)
		p->uni[i] = r->gl->GetUniformLocation(p->id, uniform_names[i]);
	return 0;
}

static int build_programs(struct render_gl *r)
{
	int e = draw_program(r, &r->face, gl_face_vs, gl_face_fs, "face");
	if (e == 0)
		e = draw_program(r, &r->section, gl_section_vs, gl_flat_fs, "section");
	if (e == 0)
		e = draw_program(r, &r->point, gl_point_vs, gl_flat_fs, "point");
	if (e < 0)
		return e;
	bool bad = r->fault == GL_FAULT_SHADER;
	GLuint cs = gl_shader_compile(r->gl, GL_COMPUTE_SHADER, gl_pack_cs, "pack", bad);
	r->pack = gl_program_link(r->gl, &cs, 1, "pack");
	cs = gl_shader_compile(r->gl, GL_COMPUTE_SHADER, gl_list_cs, "list", bad);
	r->list = gl_program_link(r->gl, &cs, 1, "list");
	if (!r->pack || !r->list)
		return -EINVAL;
	r->pack_uni = r->gl->GetUniformLocation(r->pack, "u_pack");
	r->pack_colour = r->gl->GetUniformLocation(r->pack, "u_colour");
	r->list_count = r->gl->GetUniformLocation(r->list, "u_count");
	return 0;
}

static GLuint make_texture(const struct gl_api *gl, GLenum fmt, uint32_t w, uint32_t h)
{
	GLuint t;
	gl->GenTextures(1, &t);
	gl->BindTexture(GL_TEXTURE_2D, t);
	gl->TexStorage2D(GL_TEXTURE_2D, 1, fmt, (GLsizei)w, (GLsizei)h);
	gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
	gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
	return t;
}

/* Checks what the pipeline needs of the context and sizes the batch and the
 * primitive texture from its limits. */
static int check_limits(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	GLint max_tex = 0;
	gl->GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
	if ((uint32_t)max_tex < g->width || (uint32_t)max_tex < g->height) {
		log_warn("GL renderer: images of %ux%u exceed GL_MAX_TEXTURE_SIZE %d", g->width, g->height, max_tex);
		return -E2BIG;
	}
	GLint frag_ssbo = 0;
	gl->GetIntegerv(GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS, &frag_ssbo);
	if (frag_ssbo < 1) {
		log_warn("GL renderer: fragment shaders cannot write storage buffers here");
		return -ENOTSUP;
	}
	uint32_t fit = (uint32_t)max_tex / g->height;
	r->batch = r->opts.batch ? r->opts.batch : GL_MAX_BATCH;
	if (r->batch > fit)
		r->batch = fit;
	if (r->batch > GL_MAX_BATCH)
		r->batch = GL_MAX_BATCH;
	if (r->batch > r->images)
		r->batch = r->images;
	if (r->opts.naive)
		r->batch = 1;
	for (r->tex_shift = 12; (1u << r->tex_shift) > (uint32_t)max_tex; r->tex_shift--)
		;
	r->tex_width = 1u << r->tex_shift;
	return 0;
}

/* The storage buffers of the pack pass: two output sets (double
 * buffering), the tile marks and the tile list, all zero. */
static int create_buffers(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	size_t tiles = (size_t)r->batch * r->tiles_per_image;
	for (int i = 0; i < 2; i++) {
		gl->GenBuffers(1, &r->out[i].tiles);
		gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->out[i].tiles);
		gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(tiles * VOLUME_TILE_BYTES), NULL, GL_STREAM_READ);
		gl->GenBuffers(1, &r->out[i].ids);
		gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->out[i].ids);
		gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((tiles + 1) * 4), NULL, GL_STREAM_READ);
	}
	/* The list: a 3-word header padded to 16 bytes, then (tile, rows). */
	uint32_t *zero = calloc(tiles * 2 + 4, 4);
	if (!zero)
		return -ENOMEM;
	gl->GenBuffers(1, &r->touched);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->touched);
	gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(tiles * 4), zero, GL_DYNAMIC_COPY);
	gl->GenBuffers(1, &r->tile_list);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->tile_list);
	gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((tiles * 2 + 4) * 4), zero, GL_DYNAMIC_COPY);
	free(zero);
	return 0;
}

static int create_objects(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	int e = check_limits(r);
	if (e < 0)
		return e;
	gl->GenVertexArrays(1, &r->vao);
	gl->BindVertexArray(r->vao);
	gl->GenBuffers(1, &r->point_buf);
	gl->BindBuffer(GL_ARRAY_BUFFER, r->point_buf);
	gl->VertexAttribIPointer(0, 2, GL_UNSIGNED_INT, sizeof(struct bin_point), NULL);
	gl->EnableVertexAttribArray(0);

	r->atlas = make_texture(gl, GL_RGBA8, g->width, g->height * r->batch);
	gl->GenFramebuffers(1, &r->fbo);
	gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
	gl->FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, r->atlas, 0);
	if (gl->CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
		log_warn("GL renderer: the RGBA8 atlas is not a complete framebuffer");
		return -ENOTSUP;
	}
	e = create_buffers(r);
	if (e < 0)
		return e;
	r->atlas_dirty = true;
	r->slot_of = malloc((size_t)r->batch * r->tiles_per_image * sizeof(*r->slot_of));
	r->rgba = r->opts.naive ? malloc((size_t)g->width * g->height * 4) : NULL;
	if (!r->slot_of || (r->opts.naive && !r->rgba))
		return -ENOMEM;

	gl->ClearColor(0, 0, 0, 0);
	gl->Enable(GL_BLEND);
	gl->BlendEquation(GL_MAX);
	gl->PixelStorei(GL_PACK_ALIGNMENT, 1);
	gl->PixelStorei(GL_UNPACK_ALIGNMENT, 4);
	GLenum err = gl->GetError();
	if (err != GL_NO_ERROR) {
		log_warn("GL renderer: GL error 0x%x while setting up", err);
		return -EIO;
	}
	return 0;
}

static void destroy_gl(struct render_gl *r)
{
	if (!r->have_ctx)
		return;
	const struct gl_api *gl = r->gl;
	if (gl_context_bind(&r->ctx) == 0) {
		for (int i = 0; i < 2; i++) {
			if (r->out[i].fence)
				gl->DeleteSync(r->out[i].fence);
			gl->DeleteBuffers(1, &r->out[i].tiles);
			gl->DeleteBuffers(1, &r->out[i].ids);
		}
		gl->DeleteBuffers(1, &r->touched);
		gl->DeleteBuffers(1, &r->tile_list);
		gl->DeleteFramebuffers(1, &r->fbo);
		gl->DeleteTextures(1, &r->atlas);
		gl->DeleteTextures(1, &r->prim_tex);
		gl->DeleteBuffers(1, &r->point_buf);
		gl->DeleteVertexArrays(1, &r->vao);
		gl->DeleteProgram(r->face.id);
		gl->DeleteProgram(r->section.id);
		gl->DeleteProgram(r->point.id);
		gl->DeleteProgram(r->pack);
		gl->DeleteProgram(r->list);
	}
	gl_context_destroy(&r->ctx);
	r->have_ctx = false;
	memset(r->out, 0, sizeof(r->out));
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

/* Uploads the binned primitives and points. */
static int upload(struct render_gl *r)
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
		r->prim_tex = make_texture(gl, GL_RGBA32UI, r->tex_width, (uint32_t)cap);
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
	size_t pbytes = (size_t)b->point_count * sizeof(struct bin_point);
	gl->BindBuffer(GL_ARRAY_BUFFER, r->point_buf);
	gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(pbytes ? pbytes : 8), pbytes ? b->points : NULL, GL_STREAM_DRAW);
	return 0;
}

/* The drawing programs' uniforms for image k in batch slot `slot`
 * (gl_shaders.h), computed once per image. */
struct image_uniforms {
	GLuint image[4], tile[4];
	float slice[4], eye[4], frame[4];
};

static void image_uniforms(const struct render_gl *r, uint32_t k, uint32_t slot, struct image_uniforms *u)
{
	const struct geometry *g = &r->base.geom;
	double theta = geometry_image_angle(g, k);
	double tau = tan(M_PI / g->images_per_rev);
	double bias = GL_AXIS_BIAS_PX * 2.0 / g->width;
	double slab = tau + bias;
	/* The eye far enough that perspective moves no point of the slab by
	 * more than a quarter pixel. */
	double eye = 2.0 * g->width * slab + slab;
	/* R2 low-discrepancy sequence: neighbouring images sample far apart. */
	double jx = fmod(0.5 + 0.7548776662466927 * k, 1.0) - 0.5;
	double jy = fmod(0.5 + 0.5698402909980532 * k, 1.0) - 0.5;
	*u = (struct image_uniforms){
		.image = { k, r->images, r->opts.naive ? 1u : 0u, r->tex_shift },
		.tile = { r->vol->tiles_x, r->tiles_per_image, slot, g->height },
		.slice = { (float)cos(theta), (float)sin(theta), (float)tau, (float)bias },
		.eye = { (float)eye, (float)slab, (float)(2 * GL_JITTER_PX * jx * 2.0 / g->width),
			 (float)(2 * GL_JITTER_PX * jy * 2.0 / g->height) },
		.frame = { (float)(1.0 / g->half_height), 2.0f / (float)g->width, 2.0f / (float)g->height,
			   GL_SECTION_SLOTS },
	};
}

/* Makes p current with u. */
static void use_program(struct render_gl *r, const struct gl_program *p, const struct image_uniforms *u)
{
	const struct gl_api *gl = r->gl;
	gl->UseProgram(p->id);
	gl->Uniform4ui(p->uni[UNI_IMAGE], u->image[0], u->image[1], u->image[2], u->image[3]);
	gl->Uniform4ui(p->uni[UNI_TILE], u->tile[0], u->tile[1], u->tile[2], u->tile[3]);
	gl->Uniform4f(p->uni[UNI_SLICE], u->slice[0], u->slice[1], u->slice[2], u->slice[3]);
	gl->Uniform4f(p->uni[UNI_EYE], u->eye[0], u->eye[1], u->eye[2], u->eye[3]);
	gl->Uniform4f(p->uni[UNI_FRAME], u->frame[0], u->frame[1], u->frame[2], u->frame[3]);
	gl->Uniform1i(p->uni[UNI_PRIMS], 0);
}

/* Draws the runs of b->prims with the current program: verts vertices
 * per primitive, in mode. */
static void draw_runs(struct render_gl *r, const struct bin_run *runs, unsigned n, GLenum mode, unsigned verts)
{
	for (unsigned i = 0; i < n; i++)
		if (runs[i].end > runs[i].begin)
			r->gl->DrawArrays(mode, (GLint)(runs[i].begin * verts), (GLsizei)((runs[i].end - runs[i].begin) * verts));
}

static void draw_image(struct render_gl *r, uint32_t k, uint32_t slot)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	const struct bin_set *b = &r->bins;
	struct bin_run runs[2 * BIN_MAX_CLASSES];
	unsigned n;
	if (r->opts.naive) {
		runs[0] = (struct bin_run){ 0, b->prim_count };
		n = 1;
	} else {
		n = bin_runs(b, k, runs);
	}
	struct image_uniforms u;
	image_uniforms(r, k, slot, &u);
	gl->Viewport(0, (GLint)(slot * g->height), (GLsizei)g->width, (GLsizei)g->height);
	use_program(r, &r->face, &u);
	draw_runs(r, runs, n, GL_TRIANGLES, 3);
	use_program(r, &r->section, &u);
	draw_runs(r, runs, n, GL_LINES, 4);
	draw_runs(r, runs, n, GL_POINTS, 4);
	if (r->triangles) {
		gl->Uniform4f(r->section.uni[UNI_FRAME], u.frame[0], u.frame[1], u.frame[2], GL_EDGE_SLOTS);
		draw_runs(r, runs, n, GL_LINES, 12);
		draw_runs(r, runs, n, GL_POINTS, 12);
	}
	uint32_t p0 = b->point_start[k], p1 = b->point_start[k + 1];
	if (p1 > p0) {
		use_program(r, &r->point, &u);
		gl->DrawArrays(GL_POINTS, (GLint)p0, (GLsizei)(p1 - p0));
	}
}

/* Queues halftone + pack of the batch just drawn into out: the touched
 * tiles are listed, then packed (and zeroed in the atlas) by an indirect
 * dispatch over the list. */
static void pack_batch(struct render_gl *r, struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	static const uint32_t zero = 0, list_head[3] = { 0, 1, 1 };
	uint32_t tiles = out->n * r->tiles_per_image;
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, out->ids);
	gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, 4, &zero);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->tile_list);
	gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(list_head), list_head);
	gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
	gl->UseProgram(r->list);
	gl->Uniform1ui(r->list_count, tiles);
	gl->DispatchCompute((tiles + 63) / 64, 1, 1);
	gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);

	gl->UseProgram(r->pack);
	gl->ActiveTexture(GL_TEXTURE1);
	gl->BindTexture(GL_TEXTURE_2D, r->atlas);
	gl->Uniform1i(r->pack_colour, 1);
	gl->Uniform4ui(r->pack_uni, out->first, g->width, g->height, r->tiles_per_image);
	gl->BindImageTexture(0, r->atlas, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out->tiles);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out->ids);
	gl->BindBuffer(GL_DISPATCH_INDIRECT_BUFFER, r->tile_list);
	gl->DispatchComputeIndirect(0);
	gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
			  GL_SHADER_STORAGE_BARRIER_BIT);
	out->fence = gl->FenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
	gl->Flush();
	gl->ActiveTexture(GL_TEXTURE0);
}

/* Reads the tile numbers of a packed batch into slot_of (each tile's slot
 * in the output, or -1). Returns how many tiles were packed, or -EIO when
 * the list cannot be read or is corrupt (out of range, repeated). */
static int map_slots(struct render_gl *r, const struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	uint32_t tiles = out->n * r->tiles_per_image;
	gl->BindBuffer(GL_COPY_READ_BUFFER, out->ids);
	const uint32_t *ids = gl->MapBufferRange(GL_COPY_READ_BUFFER, 0, (GLsizeiptr)((tiles + 1) * 4), GL_MAP_READ_BIT);
	if (!ids)
		return -EIO;
	uint32_t count = ids[0];
	int err = count > tiles ? -EIO : 0;
	for (uint32_t t = 0; t < tiles; t++)
		r->slot_of[t] = -1;
	for (uint32_t i = 0; err == 0 && i < count; i++) {
		if (ids[1 + i] >= tiles || r->slot_of[ids[1 + i]] >= 0)
			err = -EIO;
		else
			r->slot_of[ids[1 + i]] = (int32_t)i;
	}
	gl->UnmapBuffer(GL_COPY_READ_BUFFER);
	if (err < 0)
		log_error("GL renderer: the pack pass returned a corrupt tile list");
	return err < 0 ? err : (int)count;
}

/* Waits for a packed batch and appends its tiles, in tile order, to the
 * volume. */
static int collect_batch(struct render_gl *r, struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	if (!out->fence)
		return 0;
	uint64_t t0 = (uint64_t)now_ns();
	GLenum w = gl->ClientWaitSync(out->fence, GL_SYNC_FLUSH_COMMANDS_BIT, GL_FENCE_TIMEOUT_NS);
	gl->DeleteSync(out->fence);
	out->fence = NULL;
	uint64_t t1 = (uint64_t)now_ns();
	r->wait_ns += t1 - t0;
	if (w != GL_ALREADY_SIGNALED && w != GL_CONDITION_SATISFIED) {
		log_error("GL renderer: a batch did not finish within %llu s",
			  (unsigned long long)(GL_FENCE_TIMEOUT_NS / 1000000000ull));
		return -ETIMEDOUT;
	}
	int count = map_slots(r, out);
	if (count <= 0)
		return count;
	int err = 0;
	gl->BindBuffer(GL_COPY_READ_BUFFER, out->tiles);
	const uint8_t *data = gl->MapBufferRange(GL_COPY_READ_BUFFER, 0, (GLsizeiptr)((size_t)count * VOLUME_TILE_BYTES),
						 GL_MAP_READ_BIT);
	if (!data)
		return -EIO;
	for (uint32_t i = 0; err == 0 && i < out->n; i++) {
		const int32_t *slot = r->slot_of + (size_t)i * r->tiles_per_image;
		for (uint32_t t = 0; err == 0 && t < r->tiles_per_image; t++) {
			if (slot[t] < 0)
				continue;
			uint8_t *dst = volume_image_next(r->vol, out->first + i);
			if (!dst) {
				err = -ENOMEM;
				break;
			}
			memcpy(dst, data + (size_t)slot[t] * VOLUME_TILE_BYTES, VOLUME_TILE_BYTES);
			err = volume_image_push(r->vol, out->first + i, t);
		}
	}
	gl->UnmapBuffer(GL_COPY_READ_BUFFER);
	r->base.stats.tiles += (uint64_t)count;
	r->copy_ns += (uint64_t)now_ns() - t1;
	return err;
}

/* The naive pipeline's back end: the whole RGBA image read back,
 * halftoned and packed on the CPU. */
static int readback_naive(struct render_gl *r, uint32_t k)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	uint64_t t0 = (uint64_t)now_ns();
	gl->ReadPixels(0, 0, (GLsizei)g->width, (GLsizei)g->height, GL_RGBA, GL_UNSIGNED_BYTE, r->rgba);
	uint64_t t1 = (uint64_t)now_ns();
	r->wait_ns += t1 - t0;
	uint8_t tile[VOLUME_TILE_BYTES];
	for (uint32_t t = 0; t < r->tiles_per_image; t++) {
		uint32_t tx = t % r->vol->tiles_x, ty = t / r->vol->tiles_x;
		memset(tile, 0, sizeof(tile));
		for (uint32_t y = 0; y < VOLUME_TILE && ty * VOLUME_TILE + y < g->height; y++) {
			uint32_t v = ty * VOLUME_TILE + y;
			for (uint32_t x = 0; x < VOLUME_TILE && tx * VOLUME_TILE + x < g->width; x++) {
				uint32_t u = tx * VOLUME_TILE + x;
				const uint8_t *px = r->rgba + ((size_t)v * g->width + u) * 4;
				uint8_t thr = render_dither_threshold(k, u, v);
				for (int c = 0; c < 3; c++)
					if (px[c] > thr)
						tile[c * VOLUME_TILE_PLANE_BYTES + y * 4 + x / 8] |= (uint8_t)(0x80u >> (x % 8));
			}
		}
		int e = volume_image_append(r->vol, k, t, tile);
		if (e < 0)
			return e;
	}
	r->copy_ns += (uint64_t)now_ns() - t1;
	return 0;
}

static int render_batches(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
	gl->BindVertexArray(r->vao);
	gl->ActiveTexture(GL_TEXTURE0);
	gl->BindTexture(GL_TEXTURE_2D, r->prim_tex);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, r->touched);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, r->tile_list);
	if (r->atlas_dirty || r->opts.naive) {
		/* The pack pass leaves the atlas zero; after a failed render
		 * it may not be, and the marks may be stale: clear both. */
		size_t bytes = (size_t)r->batch * r->tiles_per_image * 4;
		uint32_t *zero = calloc(1, bytes);
		if (!zero)
			return -ENOMEM;
		gl->Clear(GL_COLOR_BUFFER_BIT);
		gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->touched);
		gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)bytes, zero);
		free(zero);
	}
	r->atlas_dirty = true;
	int err = 0, cur = 0;
	for (uint32_t first = 0; first < r->images && err == 0; first += r->batch) {
		uint32_t n = r->images - first < r->batch ? r->images - first : r->batch;
		if (r->opts.naive)
			gl->Clear(GL_COLOR_BUFFER_BIT);
		for (uint32_t i = 0; i < n; i++)
			draw_image(r, first + i, i);
		if (r->opts.naive) {
			err = readback_naive(r, first);
			continue;
		}
		gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
		struct gl_batch *out = &r->out[cur];
		out->first = first;
		out->n = n;
		pack_batch(r, out);
		/* Collect the previous batch while this one runs. */
		cur ^= 1;
		err = collect_batch(r, &r->out[cur]);
	}
	for (int i = 0; i < 2; i++) {
		int e = collect_batch(r, &r->out[cur ^ 1]);
		err = err ? err : e;
		cur ^= 1;
	}
	if (err == 0 && !r->opts.naive)
		r->atlas_dirty = false;
	return err;
}

/* Checks that the context survived the render. */
static int check_context(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	if (r->fault == GL_FAULT_LOST && r->volumes >= 1) {
		log_error("GL renderer: context lost (GL_GUILTY_CONTEXT_RESET, fault injected by SPINDLE_GL_FAULT)");
		return -ENOTRECOVERABLE;
	}
	if (r->ctx.robust && gl->GetGraphicsResetStatus) {
		GLenum s = gl->GetGraphicsResetStatus();
		if (s != GL_NO_ERROR) {
			log_error("GL renderer: context lost (reset status 0x%x)", s);
			return -ENOTRECOVERABLE;
		}
	}
	GLenum e = gl->GetError();
	if (e != GL_NO_ERROR) {
		log_error("GL renderer: GL error 0x%x", e);
		return -EIO;
	}
	return 0;
}

/* Renders on the CPU renderer, created the first time it is needed. */
static int render_on_cpu(struct render_gl *r, const struct scene *scene, struct volume *out)
{
	if (!r->cpu && !(r->cpu = render_cpu_create(&r->base.geom, r->opts.threads))) {
		log_error("CPU renderer: %s", strerror(errno));
		return -errno;
	}
	int e = render_volume(r->cpu, scene, out);
	r->base.stats = r->cpu->stats;
	return e;
}

static int render_gl_volume(struct renderer *base, const struct scene *scene, struct volume *out)
{
	struct render_gl *r = (struct render_gl *)base;
	if (r->gl_dead)
		return render_on_cpu(r, scene, out);
	uint64_t t0 = (uint64_t)now_ns();
	memset(&r->base.stats, 0, sizeof(r->base.stats));
	volume_clear(out);
	r->vol = out;
	r->wait_ns = r->copy_ns = 0;
	int err = bin_build(&r->bins, scene, r->pool);
	uint64_t t1 = (uint64_t)now_ns();
	if (err < 0)
		return err;
	err = gl_context_bind(&r->ctx);
	if (err == 0)
		err = upload(r);
	if (err == 0)
		err = render_batches(r);
	if (err == 0 || err == -ETIMEDOUT || err == -EIO) {
		int lost = check_context(r);
		err = lost < 0 ? lost : err;
	}
	gl_context_unbind(&r->ctx);
	r->volumes++;
	if (err == -E2BIG && !r->opts.no_fallback) {
		/* This scene only: the next one may fit again. */
		if (!r->told_too_big)
			log_warn("GL renderer: %u primitives do not fit the primitive texture: volumes that large "
				 "render on the CPU",
				 r->bins.prim_count);
		r->told_too_big = true;
		return render_on_cpu(r, scene, out);
	}
	if (err < 0 && (err == -ENOMEM || r->opts.no_fallback))
		return err;
	if (err < 0) {
		/* For good: the context is gone or cannot be trusted. */
		log_error("GL renderer (%s) failed (%s): falling back to the CPU renderer",
			  gl_backend_name(r->ctx.backend), strerror(-err));
		destroy_gl(r);
		r->gl_dead = true;
		return render_on_cpu(r, scene, out);
	}
	struct render_stats *st = &r->base.stats;
	st->total_ns = (uint64_t)now_ns() - t0;
	st->bin_ns = t1 - t0;
	st->pack_ns = r->wait_ns + r->copy_ns;
	st->raster_ns = st->total_ns - st->bin_ns - st->pack_ns;
	st->prims = r->bins.prim_count + r->bins.point_count;
	st->threads = pool_workers(r->pool);
	if (r->opts.naive)
		st->tiles = volume_tile_count(out);
	return 0;
}

static void render_gl_destroy(struct renderer *base)
{
	struct render_gl *r = (struct render_gl *)base;
	destroy_gl(r);
	render_destroy(r->cpu);
	bin_finish(&r->bins);
	pool_destroy(r->pool);
	free(r->slot_of);
	free(r->rgba);
	free(r->staging);
	free(r);
}

static const struct renderer_impl render_egl_impl = { "egl", render_gl_volume, render_gl_destroy };
static const struct renderer_impl render_osmesa_impl = { "osmesa", render_gl_volume, render_gl_destroy };

const char *render_gl_describe(const struct renderer *base)
{
	if (base->impl != &render_egl_impl && base->impl != &render_osmesa_impl)
		return "";
	return ((const struct render_gl *)base)->description;
}

struct renderer *render_gl_create(const struct geometry *geom, const struct render_gl_options *opts)
{
	static const struct render_gl_options defaults = { 0 };
	if (!opts)
		opts = &defaults;
	enum gl_backend backend;
	if (!opts->backend || !strcmp(opts->backend, "egl")) {
		backend = GL_BACKEND_EGL;
	} else if (!strcmp(opts->backend, "osmesa")) {
		backend = GL_BACKEND_OSMESA;
	} else {
		errno = ENOENT;
		return NULL;
	}
	struct render_gl *r = calloc(1, sizeof(*r));
	if (!r) {
		errno = ENOMEM;
		return NULL;
	}
	r->base.impl = backend == GL_BACKEND_EGL ? &render_egl_impl : &render_osmesa_impl;
	r->base.geom = *geom;
	r->opts = *opts;
	r->fault = gl_fault_from_env();
	r->images = geometry_images_per_volume(geom);
	int err = bin_init(&r->bins, geom);
	r->tiles_per_image = ((geom->width + VOLUME_TILE - 1) / VOLUME_TILE) *
			     ((geom->height + VOLUME_TILE - 1) / VOLUME_TILE);
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	unsigned threads = opts->threads ? opts->threads : cores > 0 ? (unsigned)cores : 1;
	r->pool = err == 0 ? pool_create(threads) : NULL;
	if (err == 0 && !r->pool)
		err = -ENOMEM;
	if (err == 0) {
		err = gl_context_create(&r->ctx, backend);
		r->have_ctx = true;
	}
	r->gl = &r->ctx.gl;
	if (err == 0 && opts->hardware_only && !r->ctx.hardware) {
		log_info("GL renderer %s: %s is a software rasterizer", gl_backend_name(backend), r->ctx.renderer);
		err = -ENODEV;
	}
	if (err == 0)
		err = build_programs(r);
	if (err == 0)
		err = create_objects(r);
	if (err == 0) {
		snprintf(r->description, sizeof(r->description), "%s, %s%s", r->ctx.renderer, r->ctx.version,
			 r->ctx.hardware ? "" : " (software)");
		log_info("GL renderer %s: %s, %u images per batch", gl_backend_name(backend), r->description,
			 r->batch);
	}
	if (r->have_ctx)
		gl_context_unbind(&r->ctx);
	if (err < 0) {
		render_gl_destroy(&r->base);
		errno = -err;
		return NULL;
	}
	return &r->base;
}
