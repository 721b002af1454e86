/* Volumes (protocol 6, docs/volumes.md): display.create_volume copies a
 * client's samples once into the renderers' layout (scene.h, scene_grid:
 * the up axis y fastest; a big volume a few slices per turn of the event
 * loop, its client's later requests waiting); list.draw_volume draws one with a transfer
 * function; list.set_volume_lut sets the lookup table of the draws that
 * follow. The samples count against the client's max-buffer-bytes and the
 * daemon's memory-budget while the volume object lives; a draw of one
 * counts 1 + its table's entries as vertices (max-vertices). */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>

#include "client.h"
#include "draw.h"
#include "grid.h"
#include "log.h"
#include "prefault.h"
#include "stage.h"

#define VOLUME_MAX_SIZE 4096
#define VOLUME_MAX_SAMPLES (1ull << 31)
#define VOLUME_MAX_LUT 4096

static uint32_t sample_bytes(uint32_t type)
{
	switch (type) {
	case SCENE_GRID_U8:
		return 1;
	case SCENE_GRID_U16:
	case SCENE_GRID_I16:
		return 2;
	case SCENE_GRID_F32:
	case SCENE_GRID_RGBA8:
		return 4;
	}
	return 0;
}

/* Sample (x, y, z) of src (x fastest, little-endian) to the grid's layout
 * (y fastest): sample (x, y, z) at (z nx + x) ny + y. Each z slice is a
 * transpose, done in tiles of RELAYOUT_TILE squared samples so that both
 * sides stay in cache; src may be unaligned (a client's offset), hence
 * memcpy(); byte-swapped (a big-endian host) one byte at a time. */
#define RELAYOUT_TILE 32
#define TRANSPOSE(T)                                                                                       \
	static void transpose_##T(T *dst, const uint8_t *src, uint32_t nx, uint32_t ny)                    \
	{                                                                                                  \
		for (uint32_t y0 = 0; y0 < ny; y0 += RELAYOUT_TILE)                                        \
			for (uint32_t x0 = 0; x0 < nx; x0 += RELAYOUT_TILE) {                              \
				uint32_t y1 = y0 + RELAYOUT_TILE < ny ? y0 + RELAYOUT_TILE : ny;           \
				uint32_t x1 = x0 + RELAYOUT_TILE < nx ? x0 + RELAYOUT_TILE : nx;           \
				for (uint32_t x = x0; x < x1; x++)                                         \
					for (uint32_t y = y0; y < y1; y++)                                 \
						memcpy(&dst[(size_t)x * ny + y],                           \
						       src + ((size_t)y * nx + x) * sizeof(T), sizeof(T)); \
			}                                                                                  \
	}
TRANSPOSE(uint8_t)
TRANSPOSE(uint16_t)
TRANSPOSE(uint32_t)
#undef TRANSPOSE

static void relayout(void *dst, const uint8_t *src, const uint32_t n[3], uint32_t size, bool swap, uint32_t z0,
		     uint32_t z1)
{
	size_t slice = (size_t)n[0] * n[1];
	for (uint64_t z = z0; z < z1; z++) {
		uint8_t *out = (uint8_t *)dst + z * slice * size;
		const uint8_t *in = src + z * slice * size;
		if (swap) {
			for (uint64_t y = 0; y < n[1]; y++)
				for (uint64_t x = 0; x < n[0]; x++)
					for (uint32_t b = 0; b < size; b++)
						out[(x * n[1] + y) * size + b] =
							in[(y * n[0] + x) * size + size - 1 - b];
		} else if (size == 1) {
			transpose_uint8_t(out, in, n[0], n[1]);
		} else if (size == 2) {
			transpose_uint16_t((uint16_t *)(void *)out, in, n[0], n[1]);
		} else {
			transpose_uint32_t((uint32_t *)(void *)out, in, n[0], n[1]);
		}
	}
}

/* The arguments' sizes and spacing; the sample bytes in *bytes. */
static int check_shape(struct client *c, const struct proto_display_create_volume_args *a, uint64_t *bytes)
{
	const uint32_t n[3] = { a->nx, a->ny, a->nz };
	const float s[3] = { a->sx, a->sy, a->sz };
	uint32_t size = sample_bytes(a->type);
	if (!size)
		return client_fail(c, 1, PROTO_ERR_VALUE, "create_volume: type %u", a->type);
	uint64_t samples = 1;
	for (int i = 0; i < 3; i++) {
		if (n[i] < 1 || n[i] > VOLUME_MAX_SIZE)
			return client_fail(c, 1, PROTO_ERR_VALUE, "create_volume: size %u (1 to %d)", n[i],
					   VOLUME_MAX_SIZE);
		if (!(isfinite(s[i]) && s[i] > 0.0f))
			return client_fail(c, 1, PROTO_ERR_VALUE, "create_volume: spacing %g", (double)s[i]);
		samples *= n[i];
	}
	if (samples > VOLUME_MAX_SAMPLES)
		return client_fail(c, 1, PROTO_ERR_VALUE, "create_volume: %llu samples (at most 2^31)",
				   (unsigned long long)samples);
	/* The samples, and the maximum of each brick of them. */
	*bytes = samples * size + (uint64_t)n[0] * n[2] * scene_grid_bricks(n[1]) * sizeof(float);
	return 0;
}

/* A grid for a's samples, not yet made (bytes: samples and bricks' maxima
 * together). NULL when out of memory. */
static struct vgrid *vgrid_new(const struct proto_display_create_volume_args *a, uint64_t bytes)
{
	struct vgrid *g = calloc(1, sizeof(*g));
	uint64_t bricks = (uint64_t)a->nx * a->nz * scene_grid_bricks(a->ny);
	void *samples = malloc(bytes - bricks * sizeof(float));
	float *brick_max = malloc(bricks * sizeof(float));
	if (!g || !samples || !brick_max) {
		free(g);
		free(samples);
		free(brick_max);
		return NULL;
	}
	*g = (struct vgrid){
		.refs = 1,
		.bytes = bytes,
		.grid = { a->type, { a->nx, a->ny, a->nz }, { a->sx, a->sy, a->sz }, samples, brick_max },
		.samples = samples,
		.brick_max = brick_max,
	};
	return g;
}

/* Slices z0 .. z1 - 1 of g made from src (the client's, x fastest): laid
 * out for the renderers, their bricks' maxima made. */
static void vgrid_make(struct vgrid *g, const uint8_t *src, uint32_t z0, uint32_t z1)
{
	/* RGBA8 is bytes; the wider types are little-endian on the wire. */
	bool swap = __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__ && g->grid.type != SCENE_GRID_RGBA8;
	size_t slab = (size_t)g->grid.n[0] * g->grid.n[1] * sample_bytes(g->grid.type);
	prefault_write((uint8_t *)g->samples + z0 * slab, (z1 - z0) * slab); /* written whole below */
	relayout(g->samples, src, g->grid.n, sample_bytes(g->grid.type), swap, z0, z1);
	grid_brick_max_slabs(&g->grid, z0, z1, g->brick_max);
}

/* A volume bigger than a step is made a step at a time, one per turn of
 * the event loop, so that the other clients are served meanwhile; its
 * client's later requests wait (client.h, building) until it is made. Its
 * buffer cannot go before then: only its client could destroy it. */
#define BUILD_STEP_BYTES (8u << 20)

struct vbuild {
	struct client *c;
	struct vgrid *g;
	const uint8_t *src;
	uint32_t z, slices; /* the next slice; slices a step */
	struct sd_event_source *step;
};

static int build_step(sd_event_source *s, void *data)
{
	struct vbuild *b = data;
	const struct scene_grid *gr = &b->g->grid;
	uint32_t z1 = gr->n[2] - b->z > b->slices ? b->z + b->slices : gr->n[2];
	vgrid_make(b->g, b->src, b->z, z1);
	b->z = z1;
	if (b->z < gr->n[2]) {
		sd_event_source_set_enabled(s, SD_EVENT_ONESHOT);
		return 0;
	}
	struct client *c = b->c;
	log_debug("volume of %ux%ux%u samples made in %u steps", gr->n[0], gr->n[1], gr->n[2],
		  (gr->n[2] + b->slices - 1) / b->slices);
	volumes_cancel_build(c); /* done: frees b */
	client_resume(c);
	return 0;
}

void volumes_cancel_build(struct client *c)
{
	struct vbuild *b = c->building;
	if (!b)
		return;
	sd_event_source_disable_unref(b->step);
	free(b);
	c->building = NULL;
}

/* Makes g from src now when it is small, else starts making it a step at a
 * time (c waits). 0, or -ENOMEM. */
static int vgrid_start(struct client *c, struct vgrid *g, const uint8_t *src)
{
	const struct scene_grid *gr = &g->grid;
	size_t slice = (size_t)gr->n[0] * gr->n[1] * sample_bytes(gr->type);
	if (slice * gr->n[2] <= BUILD_STEP_BYTES) {
		vgrid_make(g, src, 0, gr->n[2]);
		return 0;
	}
	struct vbuild *b = calloc(1, sizeof(*b));
	if (!b)
		return -ENOMEM;
	*b = (struct vbuild){ c, g, src, 0, (uint32_t)(BUILD_STEP_BYTES / slice ? BUILD_STEP_BYTES / slice : 1), NULL };
	if (sd_event_add_defer(c->env->event, &b->step, build_step, b) < 0) {
		free(b);
		vgrid_make(g, src, 0, gr->n[2]); /* no event source: now, then */
		return 0;
	}
	c->building = b;
	return 0;
}

int objects_create_volume(struct client *c, const struct proto_display_create_volume_args *a)
{
	uint64_t bytes = 0;
	int r = check_shape(c, a, &bytes);
	if (r < 0)
		return r;
	const struct buffer *b = objects_buffer(c, 1, a->buffer, "create_volume");
	if (!b)
		return -EPROTO;
	uint64_t need = (uint64_t)a->nx * a->ny * a->nz * sample_bytes(a->type);
	if (a->offset > b->size || need > b->size - a->offset)
		return client_fail(c, 1, PROTO_ERR_VALUE,
				   "create_volume: %llu bytes from offset %llu, buffer %u has %llu",
				   (unsigned long long)need, (unsigned long long)a->offset, a->buffer,
				   (unsigned long long)b->size);
	if ((r = objects_charge(c, bytes)) < 0)
		return r;
	struct volume_obj *vo = calloc(1, sizeof(*vo));
	struct vgrid *g = vo ? vgrid_new(a, bytes) : NULL;
	if (!g) {
		free(vo);
		objects_uncharge(c, bytes);
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	vo->grid = g;
	vo->base.client = c;
	if ((r = object_register(c, &vo->base, a->id, PROTO_IFACE_VOLUME)) < 0) {
		objects_uncharge(c, bytes);
		vgrid_unref(g);
		free(vo);
		return r;
	}
	if (vgrid_start(c, g, b->map + a->offset) < 0) /* the object goes with c */
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	return 0;
}

void volume_object_destroy(struct volume_obj *vo)
{
	struct client *c = vo->base.client;
	struct vgrid *g = vo->grid;
	g->gone = true;
	objects_uncharge(c, g->bytes);
	/* Drawn by a list: the scene loses it. */
	if (g->refs > 1 && !c->dead)
		stage_changed(c->env->stage);
	vgrid_unref(g);
	free(vo);
}

const struct proto_volume_requests volume_requests = {
	.destroy = objects_destroy_req,
};

int volumes_list_draw(void *target, const struct proto_list_draw_volume_args *a)
{
	struct list *l = target;
	struct client *c = l->base.client;
	struct volume_obj *vo = idmap_get(&c->objects, a->volume);
	if (!vo || vo->base.type != PROTO_IFACE_VOLUME)
		return client_fail(c, l->base.id, PROTO_ERR_OBJECT, "draw_volume: %u is not a volume", a->volume);
	if (a->sampling > SCENE_TRILINEAR)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw_volume: sampling %u", a->sampling);
	if (!isfinite(a->threshold) || !isfinite(a->window_center) ||
	    !(isfinite(a->window_width) && a->window_width > 0))
		return client_fail(c, l->base.id, PROTO_ERR_VALUE,
				   "draw_volume: threshold %g, window %g/%g (finite, width above 0)",
				   (double)a->threshold, (double)a->window_center, (double)a->window_width);
	float lo = a->window_center - a->window_width / 2, hi = a->window_center + a->window_width / 2;
	if (!(hi > lo)) /* a width too small for the centre's precision */
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "draw_volume: window %g/%g is empty",
				   (double)a->window_center, (double)a->window_width);
	struct vdata *v = calloc(1, sizeof(*v));
	uint8_t *lut = l->lut_count ? malloc((size_t)l->lut_count * 3) : NULL;
	if (!v || (l->lut_count && !lut)) {
		free(v);
		free(lut);
		return client_fail(c, l->base.id, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	if (lut)
		memcpy(lut, l->lut, (size_t)l->lut_count * 3);
	*v = (struct vdata){
		.refs = 1,
		.prim = SCENE_GRID,
		.count = 1 + l->lut_count, /* its weight against max-vertices */
		.grid = vgrid_ref(vo->grid),
		.transfer = { a->threshold, lo, hi, a->sampling, lut, lut ? l->lut_count : 0 },
	};
	return objects_list_append(l, v);
}

int volumes_list_set_lut(void *target, const struct proto_list_set_volume_lut_args *a)
{
	struct list *l = target;
	struct client *c = l->base.client;
	const struct buffer *b = objects_buffer(c, l->base.id, a->buffer, "set_volume_lut");
	if (!b)
		return -EPROTO;
	if (a->count == 0) {
		free(l->lut);
		l->lut = NULL;
		l->lut_count = 0;
		return 0;
	}
	if (a->count < 2 || a->count > VOLUME_MAX_LUT)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE, "set_volume_lut: %u entries (2 to %d)", a->count,
				   VOLUME_MAX_LUT);
	uint64_t bytes = 4ull * a->count;
	if (a->offset > b->size || bytes > b->size - a->offset)
		return client_fail(c, l->base.id, PROTO_ERR_VALUE,
				   "set_volume_lut: %u entries from offset %llu, "
				   "buffer %u has %llu bytes",
				   a->count, (unsigned long long)a->offset, a->buffer, (unsigned long long)b->size);
	uint8_t *lut = malloc((size_t)a->count * 3);
	if (!lut)
		return client_fail(c, l->base.id, PROTO_ERR_NO_MEMORY, "out of memory");
	const uint8_t *src = b->map + a->offset;
	for (uint32_t i = 0; i < a->count; i++)
		for (int ch = 0; ch < 3; ch++) /* alpha applied, as for colours */
			lut[3 * i + ch] = (uint8_t)((src[4 * i + ch] * src[4 * i + 3] + 127) / 255);
	free(l->lut);
	l->lut = lut;
	l->lut_count = a->count;
	return 0;
}
