/* The GL renderer: docs/design.md section 5's pipeline on OpenGL ES 3.1 (EGL) or
 * desktop OpenGL 4.5 (OSMesa), with the same GLSL (gl_shaders.h).
 *
 * Per volume the CPU bins the scene exactly as the CPU renderer does
 * (bin.h) and uploads the sorted primitives as a texture, three texels a
 * primitive, and the per-image points as a vertex buffer. Images are drawn
 * in batches into an RGBA8 atlas (image b of a batch at rows b*H .. b*H +
 * H - 1), each with its own projection: a thin slab around the slice plane,
 * seen in perspective from a point on the slice's normal, its sample grid
 * jittered by a sub-pixel offset fixed per image. Per image, only the runs
 * of primitives binned to it are drawn: faces clipped to the bow tie in the
 * fragment shader; sections with the slice plane, triangle edges and
 * segments clipped to the lobes, as lines and points; the binned points,
 * as squares of their size; grids (gl_grid.c), a quad per grid draw whose
 * fragment shader samples the grid's 3-D texture at the pixel centres
 * inside its box. Colours combine by MAX blending, and fragments
 * mark the tile rows they touch (a grid quad's rows are marked from the
 * CPU before the batch instead). gl_pack.c then halftones and packs the
 * touched tiles of the batch on the GPU and collects the non-empty ones
 * while the GPU draws the next batch. This file: set-up, upload, drawing,
 * the render and its failures. A scene with a turned draw (scene.h) is
 * rendered whole by the CPU renderer. In the even and uniform brightness
 * models (geometry.brightness, brightness.h) the segment and triangle
 * programs and the pack pass are built with BRIGHT (gl_shaders.h): each
 * primitive's weights are worked out per image in the vertex shaders, its
 * colour weighted per column in the fragment shaders, and the thinned band
 * halftoned with the CPU renderer's Bresenham pattern; points are not
 * weighted, and the face pass has no axis bias (GL_BRIGHT_AXIS_BIAS_PX). */
#include "render_gl.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "bin.h"
#include "gl_context.h"
#include "gl_grid.h"
#include "gl_pack.h"
#include "gl_shaders.h"
#include "gl_upload.h"
#include "log.h"
#include "pool.h"
#include "render_cpu.h"
#include "render_gl_priv.h"

static const char *const uniform_names[UNI_COUNT] = { "u_image", "u_slice", "u_eye", "u_frame", "u_prims", "u_tile" };

/* Compiles src, with prelude (if not NULL) inserted right after its
 * #version line: the BRIGHT forms of gl_shaders.h. */
static GLuint compile(struct render_gl *r, GLenum type, const char *src, const char *prelude, const char *what)
{
	bool bad = r->fault == GL_FAULT_SHADER;
	size_t head = sizeof(GL_SHADER_VERSION) - 1;
	if (!prelude || strncmp(src, GL_SHADER_VERSION, head) != 0)
		return gl_shader_compile(r->gl, type, src, what, bad);
	size_t len = strlen(src), plen = strlen(prelude);
	char *text = malloc(len + plen + 1);
	if (!text)
		return 0;
	memcpy(text, src, head);
	memcpy(text + head, prelude, plen);
	memcpy(text + head + plen, src + head, len - head + 1);
	GLuint sh = gl_shader_compile(r->gl, type, text, what, bad);
	free(text);
	return sh;
}

/* The uniforms of the brightness model, which stay with the program: the
 * wall weight, the band and M, the tables' texture unit. */
static void set_bright_uniforms(struct render_gl *r, GLuint program)
{
	const struct gl_api *gl = r->gl;
	const struct brightness_map *m = &r->bright;
	gl->UseProgram(program);
	gl->Uniform4f(gl->GetUniformLocation(program, "u_wall"), m->wall, 0.0f, 0.0f, 0.0f);
	gl->Uniform4ui(gl->GetUniformLocation(program, "u_band"), m->band_lo, m->band_hi, m->images, 0);
	gl->Uniform1i(gl->GetUniformLocation(program, "u_bright"), GL_BRIGHT_UNIT);
	gl->UseProgram(0);
}

static int draw_program(struct render_gl *r, struct gl_program *p, const char *vs, const char *fs, bool bright,
			const char *what)
{
	GLuint sh[2] = { compile(r, GL_VERTEX_SHADER, vs, bright ? gl_bright_vs_prelude : NULL, what),
			 compile(r, GL_FRAGMENT_SHADER, fs, bright ? gl_bright_prelude : NULL, what) };
	p->id = gl_program_link(r->gl, sh, 2, what);
	if (!p->id)
		return -EINVAL;
	for (int i = 0; i < UNI_COUNT; i++)
		p->uni[i] = r->gl->GetUniformLocation(p->id, uniform_names[i]);
	if (bright)
		set_bright_uniforms(r, p->id);
	return 0;
}

/* The programs; with the brightness model on, the segment and triangle
 * programs and the pack pass in their BRIGHT form (points are never
 * weighted). */
static int build_programs(struct render_gl *r)
{
	bool bright = r->bright_on;
	int e = draw_program(r, &r->face, gl_face_vs, gl_face_fs, bright, "face");
	if (e == 0)
		e = draw_program(r, &r->section, gl_section_vs, gl_flat_fs, bright, "section");
	if (e == 0)
		e = draw_program(r, &r->point, gl_point_vs, gl_flat_fs, false, "point");
	if (e == 0)
		e = draw_program(r, &r->grid, gl_grid_vs, gl_grid_fs, bright, "grid");
	if (e < 0)
		return e;
	GLuint cs = compile(r, GL_COMPUTE_SHADER, gl_pack_cs, bright ? gl_bright_prelude : NULL, "pack");
	r->pack = gl_program_link(r->gl, &cs, 1, "pack");
	cs = compile(r, GL_COMPUTE_SHADER, gl_list_cs, NULL, "list");
	r->list = gl_program_link(r->gl, &cs, 1, "list");
	if (!r->pack || !r->list)
		return -EINVAL;
	r->pack_uni = r->gl->GetUniformLocation(r->pack, "u_pack");
	r->pack_colour = r->gl->GetUniformLocation(r->pack, "u_colour");
	r->list_count = r->gl->GetUniformLocation(r->list, "u_count");
	if (bright)
		set_bright_uniforms(r, r->pack);
	return 0;
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
	GLint sizes[2] = { 0, 0 };
	bool desktop = r->ctx.backend == GL_BACKEND_OSMESA;
	gl->GetIntegerv(desktop ? GL_POINT_SIZE_RANGE : GL_ALIASED_POINT_SIZE_RANGE, sizes);
	if (sizes[1] < BIN_POINT_MAX_SIZE) {
		log_warn("GL renderer: points reach %d pixels here, not %d", sizes[1], BIN_POINT_MAX_SIZE);
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
	/* More than the primitive texture holds (or max_prims) renders on
	 * the CPU (upload()). */
	uint64_t fits = (uint64_t)max_tex * r->tex_width / GL_PRIM_TEXELS;
	r->base.native_prims = r->opts.max_prims && r->opts.max_prims < fits ? r->opts.max_prims : fits;
	return 0;
}

/* The brightness map as the shaders read it: for the fragment shaders a
 * texture of GL_BRIGHT_ROWS rows of W texels, rate[u] and line_rate[u] as
 * float bits; for the pack pass a storage buffer of n[u] (W words) and then
 * phase[i * 16 + y] ((W / 2 + 1) * 16 words). */
static int create_bright_tables(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct brightness_map *m = &r->bright;
	uint32_t w = m->width, phases = (w / 2 + 1) * 16;
	uint32_t *t = calloc((size_t)w * GL_BRIGHT_ROWS + w + phases, sizeof(*t));
	if (!t)
		return -ENOMEM;
	uint32_t *buf = t + (size_t)w * GL_BRIGHT_ROWS;
	for (uint32_t u = 0; u < w; u++) {
		memcpy(&t[u], &m->rate[u], sizeof(t[u]));
		memcpy(&t[w + u], &m->line_rate[u], sizeof(t[u]));
		buf[u] = m->n[u];
	}
	for (uint32_t i = 0; i < phases; i++)
		buf[w + i] = m->phase[i];
	r->bright_tex = gl_make_texture(gl, GL_R32UI, w, GL_BRIGHT_ROWS);
	gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, (GLsizei)w, GL_BRIGHT_ROWS, GL_RED_INTEGER, GL_UNSIGNED_INT, t);
	gl->GenBuffers(1, &r->bright_buf);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->bright_buf);
	gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((w + phases) * sizeof(*buf)), buf, GL_STATIC_DRAW);
	free(t);
	return 0;
}

/* The vertex array of the points and the atlas the batches draw into, as
 * a framebuffer. */
static int create_atlas(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	gl->GenVertexArrays(1, &r->vao);
	gl->BindVertexArray(r->vao);
	gl->GenBuffers(1, &r->point_buf);
	gl->BindBuffer(GL_ARRAY_BUFFER, r->point_buf);
	gl->VertexAttribIPointer(0, 2, GL_UNSIGNED_INT, sizeof(struct bin_point), NULL);
	gl->EnableVertexAttribArray(0);

	r->atlas = gl_make_texture(gl, GL_RGBA8, g->width, g->height * r->batch);
	gl->GenFramebuffers(1, &r->fbo);
	gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
	gl->FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, r->atlas, 0);
	if (gl->CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
		log_warn("GL renderer: the RGBA8 atlas is not a complete framebuffer");
		return -ENOTSUP;
	}
	r->atlas_dirty = true;
	return 0;
}

/* The fixed state: overlaps combine by MAX (blending), rows packed. */
static int set_state(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	gl->ClearColor(0, 0, 0, 0);
	if (r->ctx.backend == GL_BACKEND_OSMESA)
		gl->Enable(GL_PROGRAM_POINT_SIZE);
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

static int create_objects(struct render_gl *r)
{
	const struct geometry *g = &r->base.geom;
	int e = check_limits(r);
	if (e == 0)
		e = create_atlas(r);
	if (e == 0)
		e = gl_pack_create_buffers(r);
	if (e < 0)
		return e;
	r->slot_of = malloc((size_t)r->batch * r->tiles_per_image * sizeof(*r->slot_of));
	r->rgba = r->opts.naive ? malloc((size_t)g->width * g->height * 4) : NULL;
	if (!r->slot_of || (r->opts.naive && !r->rgba))
		return -ENOMEM;
	if (r->bright_on && (e = create_bright_tables(r)) < 0)
		return e;
	if ((e = gl_grid_create(r)) < 0) {
		log_warn("GL renderer: no 3-D textures here");
		return e;
	}
	return set_state(r);
}

static void destroy_gl(struct render_gl *r)
{
	if (!r->have_ctx)
		return;
	const struct gl_api *gl = r->gl;
	if (r->have_api && gl_context_bind(&r->ctx) == 0) {
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
		gl->DeleteTextures(1, &r->bright_tex);
		gl->DeleteBuffers(1, &r->bright_buf);
		gl->DeleteBuffers(1, &r->point_buf);
		gl->DeleteVertexArrays(1, &r->vao);
		gl->DeleteProgram(r->face.id);
		gl->DeleteProgram(r->section.id);
		gl->DeleteProgram(r->point.id);
		gl->DeleteProgram(r->pack);
		gl->DeleteProgram(r->list);
		gl->DeleteProgram(r->grid.id);
		gl_grid_release(r, true);
	}
	r->grid_tex_count = 0; /* gone with the context, if not above */
	gl_context_destroy(&r->ctx);
	r->have_ctx = false;
	memset(r->out, 0, sizeof(r->out));
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
	/* The face pass's bias near the axis (u_slice.w): none in the
	 * brightness models (GL_BRIGHT_AXIS_BIAS_PX); the slab and the eye
	 * stay where the exact model has them. */
	double face_bias = r->bright_on ? GL_BRIGHT_AXIS_BIAS_PX * 2.0 / g->width : bias;
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
		.slice = { (float)cos(theta), (float)sin(theta), (float)tau, (float)face_bias },
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
			r->gl->DrawArrays(mode, (GLint)(runs[i].begin * verts),
					  (GLsizei)((runs[i].end - runs[i].begin) * verts));
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
	gl_grid_draw(r, k, slot, u.tile);
	uint32_t p0 = b->point_start[k], p1 = b->point_start[k + 1];
	if (p1 > p0) {
		/* GL keeps a point whose centre is in the viewport whole, and
		 * need not clip the rest of its square to the viewport
		 * (llvmpipe does, GPUs often do not): the scissor keeps a
		 * square at an image edge out of the neighbouring image. */
		use_program(r, &r->point, &u);
		gl->Enable(GL_SCISSOR_TEST);
		gl->Scissor(0, (GLint)(slot * g->height), (GLsizei)g->width, (GLsizei)g->height);
		gl->DrawArrays(GL_POINTS, (GLint)p0, (GLsizei)(p1 - p0));
		gl->Disable(GL_SCISSOR_TEST);
	}
}

/* Binds what every draw uses. The pack pass leaves the atlas and the tile
 * marks zero; after a render that stopped half-way (or a naive one) they
 * may not be: then both are cleared. */
static int begin_batches(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	gl->BindFramebuffer(GL_FRAMEBUFFER, r->fbo);
	gl->BindVertexArray(r->vao);
	gl->ActiveTexture(GL_TEXTURE0);
	gl->BindTexture(GL_TEXTURE_2D, r->prim_tex);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, r->touched);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, r->tile_list);
	if (r->bright_tex) {
		gl->ActiveTexture(GL_TEXTURE0 + GL_BRIGHT_UNIT);
		gl->BindTexture(GL_TEXTURE_2D, r->bright_tex);
		gl->ActiveTexture(GL_TEXTURE0);
	}
	if (r->atlas_dirty || r->opts.naive) {
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
	return 0;
}

static int render_batches(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	int err = begin_batches(r), cur = 0;
	if (err < 0)
		return err;
	for (uint32_t first = 0; first < r->images && err == 0; first += r->batch) {
		uint32_t n = r->images - first < r->batch ? r->images - first : r->batch;
		if (r->opts.naive)
			gl->Clear(GL_COLOR_BUFFER_BIT);
		err = gl_grid_mark(r, first, n);
		if (err < 0)
			break;
		for (uint32_t i = 0; i < n; i++)
			draw_image(r, first + i, i);
		if (r->opts.naive) {
			err = gl_pack_naive(r, first);
			continue;
		}
		gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
		struct gl_batch *out = &r->out[cur];
		out->first = first;
		out->n = n;
		gl_pack_batch(r, out);
		/* Collect the previous batch while this one runs. */
		cur ^= 1;
		err = gl_pack_collect(r, &r->out[cur]);
	}
	for (int i = 0; i < 2; i++) {
		int e = gl_pack_collect(r, &r->out[cur ^ 1]);
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

/* render_stats of a GL render that began at t0 and finished binning at t1
 * (docs/rendering.md says what each time covers). */
static void set_stats(struct render_gl *r, uint64_t t0, uint64_t t1)
{
	struct render_stats *st = &r->base.stats;
	st->engine = RENDER_ENGINE_GL;
	st->total_ns = (uint64_t)now_ns() - t0;
	st->bin_ns = t1 - t0;
	st->pack_ns = r->wait_ns + r->copy_ns;
	st->raster_ns = st->total_ns - st->bin_ns - st->pack_ns;
	st->prims = r->bins.prim_count + r->bins.point_count;
	st->bins_kept = r->bins.kept;
	st->threads = pool_workers(r->pool);
	if (r->opts.naive)
		st->tiles = volume_tile_count(r->vol);
}

/* The GL part of a volume binned in r->bins: in the bound context, the
 * grids, the upload, the batches, and whether the context survived. */
static int gl_pass(struct render_gl *r, const struct scene *scene)
{
	int err = gl_context_bind(&r->ctx);
	if (err == 0)
		err = gl_grid_prepare(r, scene);
	if (err == 0)
		err = gl_upload(r);
	if (err == 0)
		err = render_batches(r);
	if (err == 0 || err == -ETIMEDOUT || err == -EIO) {
		int lost = check_context(r);
		err = lost < 0 ? lost : err;
	}
	r->uploaded = r->uploaded && err == 0; /* after an error, what the texture holds is not known */
	gl_context_unbind(&r->ctx);
	r->volumes++;
	return err;
}

/* After a GL pass that failed with err: the scene on the CPU (grids or
 * primitives too many for GL: this scene only; a lost or untrusted
 * context: for good), or err (no memory, or no fallback wanted). */
static int gl_failed(struct render_gl *r, const struct scene *scene, struct volume *out, int err)
{
	if (err == -EFBIG && !r->opts.no_fallback) /* grids too large: logged, this scene only */
		return render_on_cpu(r, scene, out);
	if (err == -E2BIG && !r->opts.no_fallback) {
		/* This scene only: the next one may fit again. */
		if (!r->told_too_big)
			log_warn("GL renderer: %u primitives do not fit the primitive texture: volumes that large "
				 "render on the CPU",
				 r->bins.prim_count);
		r->told_too_big = true;
		return render_on_cpu(r, scene, out);
	}
	if (err == -ENOMEM || r->opts.no_fallback)
		return err;
	/* For good: the context is gone or cannot be trusted. */
	log_error("GL renderer (%s) failed (%s): falling back to the CPU renderer", gl_backend_name(r->ctx.backend),
		  strerror(-err));
	destroy_gl(r);
	r->gl_dead = true;
	return render_on_cpu(r, scene, out);
}

static int render_gl_volume(struct renderer *base, const struct scene *scene, struct volume *out)
{
	struct render_gl *r = (struct render_gl *)base;
	/* Turned draws (scene.h) are drawn by the CPU renderer only: the whole
	 * scene goes there, whatever no_fallback says. Grids are drawn here
	 * (gl_grid.c), unless they exceed the 3-D texture size or the budget
	 * (-EFBIG, gl_failed()). */
	if (r->gl_dead || (scene && scene_has_turn(scene->draws, scene->draw_count)))
		return render_on_cpu(r, scene, out);
	uint64_t t0 = (uint64_t)now_ns();
	memset(&r->base.stats, 0, sizeof(r->base.stats));
	volume_clear(out);
	r->vol = out;
	r->wait_ns = r->copy_ns = 0;
	int err = bin_build(&r->bins, scene, r->pool);
	uint64_t t1 = (uint64_t)now_ns();
	if (err < 0) /* the next build bins again (bin_build()), and uploads */
		return err;
	err = gl_pass(r, scene);
	if (err < 0)
		return gl_failed(r, scene, out, err);
	set_stats(r, t0, t1);
	return 0;
}

static void render_gl_destroy(struct renderer *base)
{
	struct render_gl *r = (struct render_gl *)base;
	destroy_gl(r);
	gl_grid_free(r);
	render_destroy(r->cpu);
	bin_finish(&r->bins);
	brightness_map_finish(&r->bright);
	pool_destroy(r->pool);
	free(r->slot_of);
	free(r->rgba);
	free(r->staging);
	free(r);
}

static const struct renderer_impl render_egl_impl = {
	.name = "egl",
	.render = render_gl_volume,
	.destroy = render_gl_destroy,
};
static const struct renderer_impl render_osmesa_impl = {
	.name = "osmesa",
	.render = render_gl_volume,
	.destroy = render_gl_destroy,
};

const char *render_gl_describe(const struct renderer *base)
{
	if (base->impl != &render_egl_impl && base->impl != &render_osmesa_impl)
		return "";
	return ((const struct render_gl *)base)->description;
}

/* Whether this process may map memory both writable and executable.
 * llvmpipe compiles shaders to machine code at run time and needs it;
 * where it is denied (systemd's MemoryDenyWriteExecute=, the kernel's
 * PR_SET_MDWE) llvmpipe crashes at its first shader instead of failing. */
static bool jit_allowed(void)
{
	size_t page = (size_t)sysconf(_SC_PAGESIZE);
	void *p = mmap(NULL, page, PROT_READ | PROT_WRITE | PROT_EXEC, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
	if (p == MAP_FAILED)
		return false;
	munmap(p, page);
	return true;
}

/* Makes the context (left unbound) and everything the pipeline keeps in
 * it. */
static int open_gl(struct render_gl *r, enum gl_backend backend)
{
	int err = gl_context_create(&r->ctx, backend);
	r->have_ctx = true;
	r->have_api = err == 0;
	r->gl = &r->ctx.gl;
	if (err == 0 && r->opts.hardware_only && !r->ctx.hardware) {
		log_info("GL renderer %s: %s is a software rasterizer", gl_backend_name(backend), r->ctx.renderer);
		err = -ENODEV;
	}
	if (err == 0 && !r->ctx.hardware && !jit_allowed()) {
		log_warn("GL renderer %s: %s compiles shaders to machine code, and this process may not map "
			 "memory writable and executable (MemoryDenyWriteExecute=; docs/rendering.md)",
			 gl_backend_name(backend), r->ctx.renderer);
		err = -ENOTSUP;
	}
	if (err == 0)
		err = build_programs(r);
	if (err == 0)
		err = create_objects(r);
	if (err == 0) {
		snprintf(r->description, sizeof(r->description), "%s, %s%s", r->ctx.renderer, r->ctx.version,
			 r->ctx.hardware ? "" : " (software)");
		log_info("GL renderer %s: %s, %u images per batch", gl_backend_name(backend), r->description, r->batch);
	}
	gl_context_unbind(&r->ctx);
	return err;
}

/* The backend an options' name picks (NULL: EGL); false for none. */
static bool backend_of(const char *name, enum gl_backend *out)
{
	if (!name || !strcmp(name, "egl"))
		*out = GL_BACKEND_EGL;
	else if (!strcmp(name, "osmesa"))
		*out = GL_BACKEND_OSMESA;
	else
		return false;
	return true;
}

struct renderer *render_gl_create(const struct geometry *geom, const struct render_gl_options *opts)
{
	static const struct render_gl_options defaults = { 0 };
	if (!opts)
		opts = &defaults;
	enum gl_backend backend;
	if (!backend_of(opts->backend, &backend)) {
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
	r->bins.keep = opts->keep;
	if (err == 0)
		err = brightness_map_init(&r->bright, geom);
	r->bright_on = err == 0 && brightness_active(&r->bright);
	r->tiles_per_image = volume_geometry_tiles(geom);
	long cores = sysconf(_SC_NPROCESSORS_ONLN);
	unsigned threads = opts->threads ? opts->threads : cores > 0 ? (unsigned)cores : 1;
	r->pool = err == 0 ? pool_create(threads) : NULL;
	if (err == 0 && !r->pool)
		err = -ENOMEM;
	if (err == 0)
		err = open_gl(r, backend);
	if (err < 0) {
		render_gl_destroy(&r->base);
		errno = -err;
		return NULL;
	}
	return &r->base;
}
