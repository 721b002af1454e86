/* Grids on the GL renderers (gl_grid.h; docs/rendering.md, "Grids").
 *
 * Each grid drawn is an unsigned integer 3-D texture of its samples in
 * their own layout (width n[1], the grid's up axis, which varies fastest;
 * height n[0]; depth n[2]), sampled by texelFetch, so that nearest and
 * trilinear sampling and the transfer are grid.c's own arithmetic, in
 * float, rather than the GPU's filtering. A texture is made the first
 * time its grid is drawn and kept while renders draw it. A grid is known
 * by scene_draw.grid_id (the daemon numbers its grids, never twice), and
 * its texture is deleted once GL_GRID_KEEP renders in a row have not drawn
 * it (the object cache renders a scene's objects one by one, so a render
 * without the grid does not mean it is gone), or sooner when the textures
 * a volume needs would exceed the budget; where the id is 0 the grid is
 * known by its address, its data's, its type and size, and its texture is
 * deleted by the first render that does not draw it.
 *
 * Per image, each grid draw is one quad over the pixels whose centres may
 * lie in the grid's box (the image's plane rectangle clipped to the box's
 * six faces, widened by a pixel), and the fragment shader does the rest:
 * voxel coordinates of the pixel centre, the box test, sampling, the
 * transfer, the brightness weight of a crossing surface, the tile mark;
 * colours combine by MAX as every draw's do. */
#include "gl_grid.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grid.h"
#include "log.h"
#include "render_gl_priv.h"
#include "volume.h"

static const char *const grid_uniform_names[GRID_UNI_COUNT] = { "u_rect", "u_goff", "u_gdir", "u_gup",
								"u_gn",   "u_gtf",  "u_gcol", "u_glut" };

int gl_grid_create(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	GLuint p = r->grid.id;
	for (int i = 0; i < GRID_UNI_COUNT; i++)
		r->grid_uni[i] = gl->GetUniformLocation(p, grid_uniform_names[i]);
	gl->UseProgram(p);
	gl->Uniform1i(gl->GetUniformLocation(p, "u_grid"), GL_GRID_UNIT);
	gl->Uniform1i(gl->GetUniformLocation(p, "u_lut"), GL_LUT_UNIT);
	gl->UseProgram(0);
	/* The quad's corners come from gl_VertexID: no attributes. */
	gl->GenVertexArrays(1, &r->grid_vao);
	gl->GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &r->max_3d);
	return r->max_3d > 0 ? 0 : -EIO;
}

/* The texture format of a grid type: internal format, format, type, bytes
 * a sample. 0 bytes: not a type the renderers draw. */
struct grid_format {
	GLenum internal, format, type;
	uint32_t bytes;
};

static struct grid_format grid_format(uint32_t type)
{
	switch (type) {
	case SCENE_GRID_U8:
		return (struct grid_format){ GL_R8UI, GL_RED_INTEGER, GL_UNSIGNED_BYTE, 1 };
	case SCENE_GRID_U16:
	case SCENE_GRID_I16: /* the bits as they are; the shader extends the sign */
		return (struct grid_format){ GL_R16UI, GL_RED_INTEGER, GL_UNSIGNED_SHORT, 2 };
	case SCENE_GRID_F32: /* the bits: a NaN stays one on any GPU */
		return (struct grid_format){ GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, 4 };
	case SCENE_GRID_RGBA8:
		return (struct grid_format){ GL_RGBA8UI, GL_RGBA_INTEGER, GL_UNSIGNED_BYTE, 4 };
	}
	return (struct grid_format){ 0, 0, 0, 0 };
}

static uint64_t grid_bytes(const struct scene_grid *g)
{
	return (uint64_t)g->n[0] * g->n[1] * g->n[2] * grid_format(g->type).bytes;
}

/* Whether texture t holds d's grid. */
static bool holds(const struct gl_grid_tex *t, const struct scene_draw *d)
{
	const struct scene_grid *g = d->grid;
	if (t->id != d->grid_id || t->type != g->type || memcmp(t->n, g->n, sizeof(t->n)) != 0)
		return false;
	return t->id || (t->grid == g && t->data == g->data);
}

static uint32_t find_texture(const struct render_gl *r, const struct scene_draw *d)
{
	for (uint32_t i = 0; i < r->grid_tex_count; i++)
		if (holds(&r->grid_tex[i], d))
			return i;
	return UINT32_MAX;
}

/* Deletes texture i, keeping the others' order. */
static void drop_texture(struct render_gl *r, uint32_t i)
{
	if (r->have_api)
		r->gl->DeleteTextures(1, &r->grid_tex[i].tex);
	memmove(&r->grid_tex[i], &r->grid_tex[i + 1], (r->grid_tex_count - i - 1) * sizeof(r->grid_tex[0]));
	r->grid_tex_count--;
}

/* Deletes the textures the render `now` does not draw that have waited
 * long enough (GL_GRID_KEEP; those known by address only at once), then,
 * oldest first, as many of the rest as it takes to leave at most room
 * bytes. */
static void drop_textures(struct render_gl *r, uint64_t now, uint64_t room)
{
	uint64_t bytes = 0;
	for (uint32_t i = 0; i < r->grid_tex_count;) {
		const struct gl_grid_tex *t = &r->grid_tex[i];
		if (t->last != now && (!t->id || now - t->last > GL_GRID_KEEP)) {
			drop_texture(r, i);
		} else {
			bytes += t->bytes;
			i++;
		}
	}
	while (bytes > room) {
		uint32_t oldest = UINT32_MAX;
		for (uint32_t i = 0; i < r->grid_tex_count; i++)
			if (r->grid_tex[i].last != now &&
			    (oldest == UINT32_MAX || r->grid_tex[i].last < r->grid_tex[oldest].last))
				oldest = i;
		if (oldest == UINT32_MAX)
			break;
		bytes -= r->grid_tex[oldest].bytes;
		drop_texture(r, oldest);
	}
}

/* The bound 3-D texture's storage and g's samples in it; GL's error. */
static GLenum fill_texture(const struct gl_api *gl, const struct scene_grid *g, const struct grid_format *f)
{
	gl->TexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
	gl->TexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
	gl->TexStorage3D(GL_TEXTURE_3D, 1, f->internal, (GLsizei)g->n[1], (GLsizei)g->n[0], (GLsizei)g->n[2]);
	GLenum e = gl->GetError();
	if (e != GL_NO_ERROR)
		return e;
	/* In slabs of whole k planes of at most 64 MiB: drivers may copy what
	 * they are given through a staging buffer first. */
	uint64_t plane = (uint64_t)g->n[0] * g->n[1] * f->bytes;
	uint32_t step = plane >= (64u << 20) ? 1 : (uint32_t)((64u << 20) / plane);
	gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
	for (uint32_t k = 0; k < g->n[2]; k += step) {
		uint32_t depth = g->n[2] - k < step ? g->n[2] - k : step;
		gl->TexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, (GLint)k, (GLsizei)g->n[1], (GLsizei)g->n[0], (GLsizei)depth,
				  f->format, f->type, (const uint8_t *)g->data + k * plane);
	}
	gl->PixelStorei(GL_UNPACK_ALIGNMENT, 4);
	return gl->GetError();
}

/* Makes and uploads the texture of d's grid as entry r->grid_tex_count.
 * 0, -EFBIG (GL_OUT_OF_MEMORY), -ENOMEM or -EIO. */
static int make_texture(struct render_gl *r, const struct scene_draw *d)
{
	const struct gl_api *gl = r->gl;
	const struct scene_grid *g = d->grid;
	if (r->grid_tex_count == r->grid_tex_cap) {
		uint32_t cap = r->grid_tex_cap ? 2 * r->grid_tex_cap : 4;
		struct gl_grid_tex *t = realloc(r->grid_tex, cap * sizeof(*t));
		if (!t)
			return -ENOMEM;
		r->grid_tex = t;
		r->grid_tex_cap = cap;
	}
	struct grid_format f = grid_format(g->type);
	struct gl_grid_tex *t = &r->grid_tex[r->grid_tex_count];
	*t = (struct gl_grid_tex){ .id = d->grid_id,
				   .grid = g,
				   .data = g->data,
				   .type = g->type,
				   .n = { g->n[0], g->n[1], g->n[2] },
				   .bytes = grid_bytes(g),
				   .last = r->grid_renders };
	GLenum e = gl->GetError(); /* nothing pending: errors below are this texture's */
	gl->GenTextures(1, &t->tex);
	gl->ActiveTexture(GL_TEXTURE0 + GL_GRID_UNIT);
	gl->BindTexture(GL_TEXTURE_3D, t->tex);
	e = fill_texture(gl, g, &f);
	gl->ActiveTexture(GL_TEXTURE0);
	if (e != GL_NO_ERROR) {
		gl->DeleteTextures(1, &t->tex);
		if (e == GL_OUT_OF_MEMORY) {
			log_warn("GL renderer: no memory for a %ux%ux%u grid's texture (%llu bytes): the volume "
				 "renders on the CPU",
				 g->n[0], g->n[1], g->n[2], (unsigned long long)t->bytes);
			return -EFBIG;
		}
		log_error("GL renderer: GL error 0x%x making a grid texture", e);
		return -EIO;
	}
	r->grid_tex_count++;
	return 0;
}

/* The lookup tables of the prepared draws, entries lut_count of them, as
 * an RGBA8UI texture of GL_LUT_WIDTH entries a row. */
static int upload_luts(struct render_gl *r, uint32_t entries)
{
	const struct gl_api *gl = r->gl;
	uint32_t rows = (entries + GL_LUT_WIDTH - 1) / GL_LUT_WIDTH;
	size_t cap = (size_t)rows * GL_LUT_WIDTH;
	if (cap > r->lut_staging_cap) {
		uint8_t *s = realloc(r->lut_staging, cap * 4);
		if (!s)
			return -ENOMEM;
		r->lut_staging = s;
		r->lut_staging_cap = cap;
	}
	memset(r->lut_staging, 0, cap * 4);
	for (uint32_t i = 0; i < r->grid_draw_count; i++) {
		const struct gl_grid_draw *gd = &r->grid_draws[i];
		const struct scene_transfer *tf = &gd->draw->transfer;
		if (!tf->lut || gd->draw->grid->type == SCENE_GRID_RGBA8)
			continue;
		for (uint32_t e = 0; e < tf->lut_count; e++)
			memcpy(r->lut_staging + 4 * ((size_t)gd->lut + e), tf->lut + 3 * e, 3);
	}
	gl->ActiveTexture(GL_TEXTURE0 + GL_LUT_UNIT);
	if (rows > r->lut_rows) {
		gl->DeleteTextures(1, &r->lut_tex);
		gl->GenTextures(1, &r->lut_tex);
		gl->BindTexture(GL_TEXTURE_2D, r->lut_tex);
		gl->TexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8UI, GL_LUT_WIDTH, (GLsizei)rows);
		gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
		gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
		r->lut_rows = rows;
	}
	gl->BindTexture(GL_TEXTURE_2D, r->lut_tex);
	gl->TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, GL_LUT_WIDTH, (GLsizei)rows, GL_RGBA_INTEGER, GL_UNSIGNED_BYTE,
			  r->lut_staging);
	gl->ActiveTexture(GL_TEXTURE0);
	return 0;
}

/* Adds d (a grid draw that lights something) to the prepared draws, its
 * lookup table from entry *luts on. */
static int add_draw(struct render_gl *r, const struct scene_draw *d, const struct grid_job *job, uint32_t *luts)
{
	if (r->grid_draw_count == r->grid_draw_cap) {
		uint32_t cap = r->grid_draw_cap ? 2 * r->grid_draw_cap : 4;
		struct gl_grid_draw *g = realloc(r->grid_draws, cap * sizeof(*g));
		if (!g)
			return -ENOMEM;
		r->grid_draws = g;
		r->grid_draw_cap = cap;
	}
	struct gl_grid_draw *gd = &r->grid_draws[r->grid_draw_count++];
	gd->draw = d;
	memcpy(gd->lin, job->lin, sizeof(gd->lin));
	memcpy(gd->off, job->off, sizeof(gd->off));
	gd->tex = UINT32_MAX;
	gd->lut = *luts;
	if (d->transfer.lut && d->grid->type != SCENE_GRID_RGBA8)
		*luts += d->transfer.lut_count;
	return 0;
}

/* What a volume needs of the textures (the grid draws' textures found or
 * not): the bytes of those kept that it draws and of new ones in *need,
 * of the new ones alone in *fresh. false: a grid larger than GL allows. */
static bool textures_needed(struct render_gl *r, uint64_t now, uint64_t *need, uint64_t *fresh)
{
	bool fit = true;
	*need = *fresh = 0;
	for (uint32_t i = 0; i < r->grid_draw_count; i++) {
		struct gl_grid_draw *gd = &r->grid_draws[i];
		const struct scene_grid *g = gd->draw->grid;
		gd->tex = find_texture(r, gd->draw);
		if (gd->tex != UINT32_MAX) {
			struct gl_grid_tex *t = &r->grid_tex[gd->tex];
			*need += t->last == now ? 0 : t->bytes;
			t->last = now;
			continue;
		}
		bool again = false; /* a new grid an earlier draw counted */
		for (uint32_t j = 0; j < i && !again; j++)
			again = r->grid_draws[j].tex == UINT32_MAX && r->grid_draws[j].draw->grid == g &&
				r->grid_draws[j].draw->grid_id == gd->draw->grid_id;
		*need += again ? 0 : grid_bytes(g);
		*fresh += again ? 0 : grid_bytes(g);
		for (int a = 0; a < 3; a++)
			fit &= g->n[a] <= (uint32_t)r->max_3d;
	}
	return fit;
}

/* Adds the scene's grid draws that light something to the prepared
 * draws, their lookup tables' entries counted in *luts. */
static int add_draws(struct render_gl *r, const struct scene *scene, uint32_t *luts)
{
	for (uint32_t i = 0; scene && i < scene->draw_count; i++) {
		const struct scene_draw *d = &scene->draws[i];
		struct grid_job job;
		/* What grid.c lights nothing of: no grid (its volume is gone),
		 * no samples, a type it does not know, a transform that
		 * cannot be inverted, a lookup table of no entries. */
		if (d->prim != SCENE_GRID || !d->grid || !d->grid->data || !grid_format(d->grid->type).bytes ||
		    (d->transfer.lut && !d->transfer.lut_count && d->grid->type != SCENE_GRID_RGBA8) ||
		    !grid_prepare(&job, d))
			continue;
		int e = add_draw(r, d, &job, luts);
		if (e < 0)
			return e;
	}
	return 0;
}

/* Points each prepared draw at its grid's texture, making those not
 * kept. */
static int assign_textures(struct render_gl *r)
{
	for (uint32_t i = 0; i < r->grid_draw_count; i++) {
		struct gl_grid_draw *gd = &r->grid_draws[i];
		gd->tex = find_texture(r, gd->draw);
		if (gd->tex == UINT32_MAX) {
			int e = make_texture(r, gd->draw);
			if (e < 0)
				return e;
			gd->tex = r->grid_tex_count - 1;
		}
	}
	return 0;
}

int gl_grid_prepare(struct render_gl *r, const struct scene *scene)
{
	uint64_t now = ++r->grid_renders;
	r->grid_draw_count = 0;
	uint32_t luts = 0;
	int e = add_draws(r, scene, &luts);
	if (e < 0)
		return e;
	/* What this volume needs: the textures kept that it draws, and new
	 * ones (fresh). */
	uint64_t need, fresh;
	bool fit = textures_needed(r, now, &need, &fresh);
	uint64_t budget = r->opts.max_grid_bytes ? r->opts.max_grid_bytes : GL_GRID_BUDGET;
	if (!fit || need > budget) {
		drop_textures(r, now, budget);
		if (!r->told_grid_too_big)
			log_warn("GL renderer: grids of %llu bytes (at most %llu), or larger than %d samples a side: "
				 "volumes with them render on the CPU",
				 (unsigned long long)need, (unsigned long long)budget, r->max_3d);
		r->told_grid_too_big = true;
		return -EFBIG;
	}
	/* Room for the new ones; then the indices again, as dropping moves
	 * the textures kept. */
	drop_textures(r, now, budget - fresh);
	e = assign_textures(r);
	if (e < 0)
		return e;
	return luts ? upload_luts(r, luts) : 0;
}

/* The m-gon poly (in (s, y) of the image plane) clipped to one face of
 * the grid's box, in sample units (face: axis face / 2, its low side for
 * even face); returns its new vertex count. */
static int clip_face(double poly[16][2], int m, int face, const double off[3], const double dir[3], const double up[3],
		     const uint32_t n[3])
{
	int a = face >> 1;
	double sign = face & 1 ? -1.0 : 1.0, bound = face & 1 ? n[a] - 0.5 : -0.5;
	double out[16][2];
	int o = 0;
	for (int i = 0; i < m; i++) {
		const double *p = poly[i], *q = poly[(i + 1) % m];
		double ep = sign * (off[a] + p[0] * dir[a] + p[1] * up[a] - bound);
		double eq = sign * (off[a] + q[0] * dir[a] + q[1] * up[a] - bound);
		if (ep >= 0) {
			out[o][0] = p[0];
			out[o++][1] = p[1];
		}
		if ((ep >= 0) != (eq >= 0) && o < 16) {
			double t = ep / (ep - eq);
			out[o][0] = p[0] + t * (q[0] - p[0]);
			out[o++][1] = p[1] + t * (q[1] - p[1]);
		}
	}
	memcpy(poly, out, sizeof(out[0]) * (size_t)o);
	return o;
}

/* The pixels of an image of g whose centres may lie in the box -0.5 <=
 * f < n - 0.5, f = off + s dir + y up: the image's plane rectangle
 * clipped to the box's six faces, its bounds widened by a pixel: columns
 * px[0] .. px[2], rows px[1] .. px[3]. false: none. */
static bool grid_rect(const struct geometry *g, const double off[3], const double dir[3], const double up[3],
		      const uint32_t n[3], uint32_t px[4])
{
	double h = g->half_height;
	double poly[16][2] = { { -1, -h }, { 1, -h }, { 1, h }, { -1, h } };
	int m = 4;
	for (int face = 0; face < 6 && m > 0; face++)
		m = clip_face(poly, m, face, off, dir, up, n);
	if (m == 0)
		return false;
	double s0 = poly[0][0], s1 = s0, y0 = poly[0][1], y1 = y0;
	for (int i = 1; i < m; i++) {
		s0 = fmin(s0, poly[i][0]);
		s1 = fmax(s1, poly[i][0]);
		y0 = fmin(y0, poly[i][1]);
		y1 = fmax(y1, poly[i][1]);
	}
	/* Pixel u's centre is s = (u + 0.5) 2 / W - 1, row v's y = h - (v +
	 * 0.5) 2 h / H. */
	double w = g->width, hh = g->height;
	double u0 = floor((s0 + 1) / 2 * w - 0.5) - 1, u1 = ceil((s1 + 1) / 2 * w - 0.5) + 1;
	double v0 = floor((h - y1) / (2 * h) * hh - 0.5) - 1, v1 = ceil((h - y0) / (2 * h) * hh - 0.5) + 1;
	u0 = fmax(u0, 0);
	v0 = fmax(v0, 0);
	u1 = fmin(u1, w - 1);
	v1 = fmin(v1, hh - 1);
	if (!(u0 <= u1 && v0 <= v1))
		return false;
	px[0] = (uint32_t)u0;
	px[1] = (uint32_t)v0;
	px[2] = (uint32_t)u1;
	px[3] = (uint32_t)v1;
	return true;
}

/* The pixels grid draw gd may light in image k (grid_rect()), and f's
 * derivatives along the image's plane: dir along s, up along y. */
static bool draw_rect(const struct render_gl *r, const struct gl_grid_draw *gd, uint32_t k, double dir[3], double up[3],
		      uint32_t px[4])
{
	double th = geometry_image_angle(&r->base.geom, k), dx = cos(th), dz = sin(th);
	/* f(s, y) = off + s lin d_k + y lin e_y, as grid_draw_image(). */
	for (int a = 0; a < 3; a++) {
		dir[a] = gd->lin[a][0] * dx + gd->lin[a][2] * dz;
		up[a] = gd->lin[a][1];
	}
	return grid_rect(&r->base.geom, gd->off, dir, up, gd->draw->grid->n, px);
}

int gl_grid_mark(struct render_gl *r, uint32_t first, uint32_t n)
{
	if (!r->grid_draw_count)
		return 0;
	size_t words = (size_t)n * r->tiles_per_image;
	if (words > r->grid_marks_cap) {
		uint32_t *m = realloc(r->grid_marks, words * sizeof(*m));
		if (!m)
			return -ENOMEM;
		r->grid_marks = m;
		r->grid_marks_cap = words;
	}
	memset(r->grid_marks, 0, words * sizeof(*r->grid_marks));
	uint32_t tiles_x = volume_tiles_across(r->base.geom.width);
	for (uint32_t b = 0; b < n; b++)
		for (uint32_t i = 0; i < r->grid_draw_count; i++) {
			double dir[3], up[3];
			uint32_t px[4];
			if (!draw_rect(r, &r->grid_draws[i], first + b, dir, up, px))
				continue;
			uint32_t *m = r->grid_marks + (size_t)b * r->tiles_per_image;
			for (uint32_t v = px[1]; v <= px[3]; v++)
				for (uint32_t tx = px[0] / VOLUME_TILE; tx <= px[2] / VOLUME_TILE; tx++)
					m[(v / VOLUME_TILE) * tiles_x + tx] |= 1u << (v % VOLUME_TILE);
		}
	/* The marks are zero between batches (the list pass clears them):
	 * these are the batch's first. */
	r->gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->touched);
	r->gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(words * sizeof(*r->grid_marks)), r->grid_marks);
	return 0;
}

/* Draws the quad of grid draw gd in image k, where it may light
 * something: its texture and uniforms, then the quad. */
static void draw_quad(const struct render_gl *r, const struct gl_grid_draw *gd, uint32_t k)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	const GLint *uni = r->grid_uni;
	double h = g->half_height, w = g->width, hh = g->height;
	const struct scene_draw *d = gd->draw;
	const struct scene_grid *gr = d->grid;
	const struct scene_transfer *tf = &d->transfer;
	double dir[3], up[3];
	uint32_t px[4];
	if (!draw_rect(r, gd, k, dir, up, px))
		return;
	bool lut = tf->lut && gr->type != SCENE_GRID_RGBA8;
	gl->BindTexture(GL_TEXTURE_3D, r->grid_tex[gd->tex].tex);
	/* Row v is window row v of the slot's viewport, whose bottom is
	 * NDC -1. */
	gl->Uniform4f(uni[GRID_UNI_RECT], (float)(px[0] * 2 / w - 1), (float)(px[1] * 2 / hh - 1),
		      (float)((px[2] + 1) * 2 / w - 1), (float)((px[3] + 1) * 2 / hh - 1));
	gl->Uniform4f(uni[GRID_UNI_OFF], (float)gd->off[0], (float)gd->off[1], (float)gd->off[2],
		      (float)(2.0 / g->width));
	gl->Uniform4f(uni[GRID_UNI_DIR], (float)dir[0], (float)dir[1], (float)dir[2], (float)(2.0 * h / g->height));
	gl->Uniform4f(uni[GRID_UNI_UP], (float)up[0], (float)up[1], (float)up[2], (float)h);
	gl->Uniform4ui(uni[GRID_UNI_N], gr->n[0], gr->n[1], gr->n[2], gr->type);
	gl->Uniform4f(uni[GRID_UNI_TF], tf->threshold, tf->lo, tf->hi, tf->sampling == SCENE_TRILINEAR ? 1.0f : 0.0f);
	gl->Uniform4ui(uni[GRID_UNI_COL], d->rgb[0], d->rgb[1], d->rgb[2], lut ? tf->lut_count : 0);
	gl->Uniform1ui(uni[GRID_UNI_LUT], gd->lut);
	gl->DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
}

void gl_grid_draw(struct render_gl *r, uint32_t k, uint32_t slot, const uint32_t tile[4])
{
	if (!r->grid_draw_count)
		return;
	const struct gl_api *gl = r->gl;
	gl->UseProgram(r->grid.id);
	gl->BindVertexArray(r->grid_vao);
	gl->Uniform4ui(r->grid.uni[UNI_TILE], tile[0], tile[1], tile[2], tile[3]);
	if (r->lut_tex) {
		gl->ActiveTexture(GL_TEXTURE0 + GL_LUT_UNIT);
		gl->BindTexture(GL_TEXTURE_2D, r->lut_tex);
	}
	gl->ActiveTexture(GL_TEXTURE0 + GL_GRID_UNIT);
	for (uint32_t i = 0; i < r->grid_draw_count; i++)
		draw_quad(r, &r->grid_draws[i], k);
	gl->ActiveTexture(GL_TEXTURE0);
	gl->BindVertexArray(r->vao);
}

void gl_grid_release(struct render_gl *r, bool all)
{
	while (r->grid_tex_count)
		drop_texture(r, r->grid_tex_count - 1);
	r->grid_draw_count = 0;
	if (!all || !r->have_api)
		return;
	r->gl->DeleteTextures(1, &r->lut_tex);
	r->gl->DeleteVertexArrays(1, &r->grid_vao);
	r->lut_tex = r->grid_vao = 0;
	r->lut_rows = 0;
}

void gl_grid_free(struct render_gl *r)
{
	free(r->grid_tex);
	free(r->grid_draws);
	free(r->lut_staging);
	free(r->grid_marks);
	r->grid_marks = NULL;
	r->grid_marks_cap = 0;
	r->grid_tex = NULL;
	r->grid_draws = NULL;
	r->lut_staging = NULL;
	r->grid_tex_count = r->grid_tex_cap = r->grid_draw_count = r->grid_draw_cap = 0;
	r->lut_staging_cap = 0;
}
