/* Composition of packed volumes by OR, plain or run-length coded
 * (compose.h). */
#include "compose.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "halftone.h"
#include "pool.h"

static size_t or_coded_tile(const uint8_t *in, size_t avail, uint8_t *dst)
{
	return rle_or_coded(in, avail, dst, VOLUME_TILE_BYTES);
}

/* Patches of at most this many dirty tiles run on the calling thread:
 * waking the pool's workers costs tens of microseconds on some machines
 * (pool.h), less when they have just worked (compose_use_pool()), and a
 * patch's work per image is mostly waiting for memory, which two workers
 * on neighbouring images share badly. Measured with spindle-bench-cache at
 * perspecta: the bunny beside the dragon (about 400 tiles a patch) is
 * patched faster alone; S4 with a tenth moving (thousands) on both. */
#define COMPOSE_FEW_TILES 2048
#define COMPOSE_FEW_TILES_AWAKE 512

struct compose_worker {
	uint8_t *tiles;   /* one dense image (tiles_per_image * VOLUME_TILE_BYTES): tile t gathered where touched[t] */
	uint8_t *touched; /* tiles_per_image flags, all 0 between images */
	uint8_t *run;     /* lay_run()'s tiles: tiles_per_image of them */
	uint8_t *mask;    /* and their presence: mask_bytes */
	int err;
};

struct compose {
	struct pool *pool;
	unsigned workers;
	bool awake;                   /* its pool's workers have just worked */
	uint32_t few_cold, few_awake; /* patches run on this thread up to these many tiles */
	uint32_t tiles_per_image, mask_bytes, image_count;
	struct compose_worker *w;
	struct geometry geom;
	halftone_fn halftone;
	struct brightness_tables thr; /* per volume image, made once */
	struct tile_set all_dirty;    /* every tile of every image: compose_volumes() */
	const struct turned_source *turned;
	/* Patching: the sources with tiles in image k = dirty->list[p] are
	 * img_src[img_first[p] .. img_first[p + 1]), each with the mask bytes
	 * it lies in there; pos[k] is p. */
	uint32_t *img_first, *pos;
	struct img_source {
		uint32_t src;
		struct rle_span span;
	} * img_src;
	size_t img_src_cap;
	/* Per call: */
	const struct tile_set *dirty;
	uint64_t dirty_tiles; /* in it (compose_last_tiles()) */
	struct volume *out;
	const struct compose_source *src;
	unsigned n;
	uint32_t jobs; /* run_images(): images (or list positions) 0 .. jobs */
	atomic_uint next_image;
};

/* Each worker's dense image and run (compose_destroy() frees them). */
static int workers_create(struct compose *c)
{
	if (!(c->w = calloc(c->workers, sizeof(*c->w))))
		return -ENOMEM;
	for (unsigned i = 0; i < c->workers; i++) {
		struct compose_worker *w = &c->w[i];
		w->tiles = malloc((size_t)c->tiles_per_image * VOLUME_TILE_BYTES);
		w->touched = calloc(c->tiles_per_image, 1);
		w->run = malloc((size_t)c->tiles_per_image * VOLUME_TILE_BYTES);
		w->mask = calloc(c->mask_bytes, 1);
		if (!w->tiles || !w->touched || !w->run || !w->mask)
			return -ENOMEM;
	}
	return 0;
}

struct compose *compose_create(const struct geometry *geom, struct pool *pool)
{
	struct volume *probe = volume_create(geom); /* its tiling */
	if (!probe)
		return NULL;
	struct compose *c = calloc(1, sizeof(*c));
	if (!c) {
		volume_destroy(probe);
		return NULL;
	}
	c->pool = pool;
	c->few_cold = COMPOSE_FEW_TILES;
	c->few_awake = COMPOSE_FEW_TILES_AWAKE;
	c->geom = *geom;
	c->halftone = halftone_pick(NULL);
	c->workers = pool ? pool_workers(pool) : 1;
	c->tiles_per_image = volume_tiles_per_image(probe);
	c->mask_bytes = probe->mask_bytes;
	c->image_count = probe->image_count;
	volume_destroy(probe);
	struct brightness_map bright;
	if (brightness_map_init(&bright, geom) < 0)
		goto fail;
	int err = brightness_tables_init(&c->thr, &bright);
	brightness_map_finish(&bright);
	if (err < 0)
		goto fail;
	if (tile_set_init(&c->all_dirty, c->image_count, c->tiles_per_image) < 0)
		goto fail;
	tile_set_fill(&c->all_dirty);
	if (workers_create(c) < 0)
		goto fail;
	return c;
fail:
	compose_destroy(c);
	errno = ENOMEM;
	return NULL;
}

void compose_destroy(struct compose *c)
{
	if (!c)
		return;
	for (unsigned i = 0; c->w && i < c->workers; i++) {
		free(c->w[i].tiles);
		free(c->w[i].touched);
		free(c->w[i].run);
		free(c->w[i].mask);
	}
	free(c->w);
	brightness_tables_finish(&c->thr);
	tile_set_finish(&c->all_dirty);
	free(c->img_first);
	free(c->pos);
	free(c->img_src);
	free(c);
}

/* Tile t of w's dense image |= src (= src, when not touched yet). */
static void dense_or(struct compose_worker *w, uint32_t t, const uint8_t *src)
{
	uint8_t *dst = w->tiles + (size_t)t * VOLUME_TILE_BYTES;
	if (w->touched[t]) {
		volume_tile_or(dst, src);
		return;
	}
	volume_tile_copy(dst, src);
	w->touched[t] = 1;
}

/* Tile t of w's dense image, touched (zero, when it was not). */
static uint8_t *dense_touch(struct compose_worker *w, uint32_t t)
{
	uint8_t *dst = w->tiles + (size_t)t * VOLUME_TILE_BYTES;
	if (!w->touched[t])
		volume_tile_zero(dst);
	w->touched[t] = 1;
	return dst;
}

/* The touched tiles of w's dense image, in order, as image k of c->out
 * (count of them), leaving none touched. */
static int emit_image(struct compose *c, struct compose_worker *w, uint32_t k, uint32_t count)
{
	if (!count)
		return 0;
	int err = volume_image_reserve(c->out, k, count);
	for (uint32_t t = 0; t < c->tiles_per_image; t++) {
		if (!w->touched[t])
			continue;
		if (err == 0)
			err = volume_image_append(c->out, k, t, w->tiles + (size_t)t * VOLUME_TILE_BYTES);
		w->touched[t] = 0;
	}
	return err;
}

typedef int (*image_fn)(struct compose *c, struct compose_worker *w, uint32_t k);

struct image_job {
	struct compose *c;
	image_fn fn;
};

/* Images are handed out one at a time; the first error wins. */
static void image_job(void *arg, unsigned index)
{
	struct image_job *j = arg;
	struct compose_worker *w = &j->c->w[index];
	for (;;) {
		uint32_t k = atomic_fetch_add(&j->c->next_image, 1);
		if (k >= j->c->jobs)
			break;
		int err = j->fn(j->c, w, k);
		if (err < 0 && w->err == 0)
			w->err = err;
	}
}

/* fn on images (or list positions) 0 .. count of c->out, on the pool's
 * workers (on this thread, as worker 0, without a pool). */
static int run_images(struct compose *c, struct volume *out, image_fn fn, uint32_t count)
{
	struct image_job j = { c, fn };
	c->out = out;
	c->jobs = count;
	atomic_store(&c->next_image, 0);
	for (unsigned i = 0; i < c->workers; i++)
		c->w[i].err = 0;
	if (c->pool)
		pool_run(c->pool, image_job, &j);
	else
		image_job(&j, 0);
	int err = 0;
	for (unsigned i = 0; i < c->workers && !err; i++)
		err = c->w[i].err;
	c->out = NULL;
	return err;
}

bool compose_use_pool(struct compose *c, struct pool *pool, bool awake)
{
	if (!pool || !c->pool || pool_workers(pool) != c->workers)
		return false;
	c->pool = pool;
	c->awake = awake;
	return true;
}

void compose_set_few_tiles(struct compose *c, uint32_t cold, uint32_t awake)
{
	c->few_cold = cold;
	c->few_awake = awake;
}

static int check_sources(const struct compose *c, const struct volume *out, const struct tile_set *dirty,
			 const struct compose_source *src, unsigned n)
{
	if (out->image_count != c->image_count || volume_tiles_per_image(out) != c->tiles_per_image ||
	    dirty->image_count != c->image_count || dirty->mask_bytes != c->mask_bytes)
		return -EINVAL;
	for (unsigned s = 0; s < n; s++) {
		if (src[s].vol == out || (!src[s].vol && !src[s].rle))
			return -EINVAL;
		if (src[s].vol && src[s].vol->image_count != c->image_count)
			return -EINVAL;
		if (src[s].rle &&
		    (src[s].rle->image_count != c->image_count || src[s].rle->mask_bytes != c->mask_bytes ||
		     src[s].rle->tile_bytes != VOLUME_TILE_BYTES))
			return -EINVAL;
	}
	return 0;
}

/* ---- patching ---- */

static bool bit(const uint8_t *mask, uint32_t t)
{
	return (mask[t / 8] >> (t % 8)) & 1;
}

static const uint8_t *source_mask(const struct compose_source *s, uint32_t k)
{
	if (s->vol)
		return s->vol->images[k].tile_count ? s->vol->images[k].mask : NULL;
	return s->rle->images[k].tile_count ? s->rle->images[k].data : NULL;
}

/* The codes of a coded image's tiles (after its mask and offsets), and
 * how many bytes of them. */
static const uint8_t *rle_codes(const struct compose *c, const struct rle_image *img, size_t *avail)
{
	size_t head = c->mask_bytes + (size_t)img->tile_count * sizeof(uint32_t);
	*avail = img->len - head;
	return img->data + head;
}

/* ORs the tiles of image k that lie in dirty of source is (whose mask is
 * zero outside is's span) into w's dense image. */
static int gather_dirty(const struct compose *c, struct compose_worker *w, const struct img_source *is, uint32_t k,
			const uint8_t *dirty)
{
	const uint32_t bytes = c->mask_bytes, w0 = is->span.first / 8, w1 = is->span.last / 8;
	uint32_t x = w0;
	while (x <= w1 && !volume_mask_word(dirty, bytes, x)) /* without reading the source */
		x++;
	if (x > w1)
		return 0;
	const struct compose_source *s = &c->src[is->src];
	const uint8_t *mask = source_mask(s, k);
	const uint8_t *tiles = s->vol ? s->vol->images[k].tiles : NULL;
	const struct rle_image *img = s->rle ? &s->rle->images[k] : NULL;
	size_t avail = 0;
	const uint8_t *codes = img ? rle_codes(c, img, &avail) : NULL;
	uint32_t base = 0; /* the stored index of word x's first tile (none before w0) */
	for (x = w0; x <= w1; x++) {
		uint64_t m = volume_mask_word(mask, bytes, x);
		for (uint64_t both = m & volume_mask_word(dirty, bytes, x); both; both &= both - 1) {
			uint32_t bitno = (uint32_t)__builtin_ctzll(both), t = x * 64 + bitno;
			uint32_t i = base + volume_word_bits(m & ((1ull << bitno) - 1));
			if (tiles) {
				dense_or(w, t, tiles + (size_t)i * VOLUME_TILE_BYTES);
				continue;
			}
			uint32_t off;
			memcpy(&off, img->data + c->mask_bytes + i * sizeof(uint32_t), sizeof(off));
			if (off >= avail || !or_coded_tile(codes + off, avail - off, dense_touch(w, t)))
				return -EINVAL;
		}
		base += volume_word_bits(m);
	}
	return 0;
}

/* Writes the gathered (touched) dirty tiles that are still in w's dense
 * image over old's, whose mask holds them, leaving none touched. */
static void write_touched(const struct compose *c, struct compose_worker *w, struct volume_image *old,
			  const uint8_t *dirty)
{
	uint32_t base = 0; /* the stored index of word x's first tile */
	for (uint32_t x = 0; x < volume_mask_words(c->mask_bytes); x++) {
		uint64_t m = volume_mask_word(old->mask, c->mask_bytes, x);
		for (uint64_t d = volume_mask_word(dirty, c->mask_bytes, x) & m; d; d &= d - 1) {
			uint32_t bitno = (uint32_t)__builtin_ctzll(d), t = x * 64 + bitno;
			if (!w->touched[t]) /* spliced in already (lay_run()) */
				continue;
			uint32_t i = base + volume_word_bits(m & ((1ull << bitno) - 1));
			volume_tile_copy(old->tiles + (size_t)i * VOLUME_TILE_BYTES,
					 w->tiles + (size_t)t * VOLUME_TILE_BYTES);
			w->touched[t] = 0;
		}
		base += volume_word_bits(m);
	}
}

/* The first and last dirty tiles whose presence changes (old has them
 * and the sources no longer do, or the other way); false when none does. */
static bool presence_changes(const struct compose *c, const struct compose_worker *w, const struct volume_image *old,
			     const uint8_t *dirty, uint32_t *first, uint32_t *last)
{
	bool any = false;
	for (uint32_t x = 0; x < volume_mask_words(c->mask_bytes); x++) {
		uint64_t m = volume_mask_word(old->mask, c->mask_bytes, x);
		for (uint64_t d = volume_mask_word(dirty, c->mask_bytes, x); d; d &= d - 1) {
			uint32_t bitno = (uint32_t)__builtin_ctzll(d), t = x * 64 + bitno;
			if (((m >> bitno) & 1) == (w->touched[t] != 0))
				continue;
			*first = any ? *first : t;
			*last = t;
			any = true;
		}
	}
	return any;
}

/* Tiles first..last of image old as they are to be, in order in w->run
 * with their presence in w->mask: the gathered tiles where dirty (taken
 * from w's dense image, left untouched there), else old's stored
 * ones (from index at on). */
static void lay_run(const struct compose *c, struct compose_worker *w, const struct volume_image *old,
		    const uint8_t *dirty, uint32_t first, uint32_t last, uint32_t at)
{
	uint32_t i = at, n = 0;
	for (uint32_t t = first; t <= last; t++) {
		bool had = bit(old->mask, t), has = had;
		uint8_t *to = w->run + (size_t)n * VOLUME_TILE_BYTES;
		if (bit(dirty, t)) {
			has = w->touched[t];
			if (has) {
				volume_tile_copy(to, w->tiles + (size_t)t * VOLUME_TILE_BYTES);
				w->touched[t] = 0;
			}
		} else if (had) {
			volume_tile_copy(to, old->tiles + (size_t)i * VOLUME_TILE_BYTES);
		}
		i += had;
		n += has;
		uint8_t m = (uint8_t)(1u << (t % 8));
		w->mask[t / 8] = (uint8_t)(has ? w->mask[t / 8] | m : w->mask[t / 8] & ~m);
	}
}

/* Image k of c->out patched in place: where tiles come or go, the run
 * from the first such to the last is laid out anew and spliced in
 * (volume_image_splice(): the tiles before it stay, those after it move
 * by one memmove); the other gathered tiles are written over their
 * places. A small object moving over a large static one so costs the
 * tiles about it, not the whole image. 0 or -ENOMEM. */
static int patch_shifted(const struct compose *c, struct compose_worker *w, uint32_t k, const uint8_t *dirty)
{
	struct volume_image *old = &c->out->images[k];
	uint32_t first = 0, last = 0;
	if (presence_changes(c, w, old, dirty, &first, &last)) {
		lay_run(c, w, old, dirty, first, last, volume_stored_index(old->mask, first));
		int err = volume_image_splice(c->out, k, first, last, w->mask, w->run);
		if (err < 0)
			return err;
	}
	write_touched(c, w, old, dirty);
	return 0;
}

/* Image k = c->dirty->list[p] of c->out anew: its dirty tiles composed
 * from the sources (gathered into w's dense image first), then patched
 * in place. */
static int patch_image(struct compose *c, struct compose_worker *w, uint32_t p)
{
	uint32_t k = c->dirty->list[p];
	const uint8_t *dirty = c->dirty->mask + (size_t)k * c->mask_bytes;
	if (volume_all_zero(dirty, c->mask_bytes))
		return 0;
	c->out->images[k].stamp = 0; /* its tiles change in place below */
	int err = 0;
	for (uint32_t i = c->img_first[p]; i < c->img_first[p + 1] && err == 0; i++)
		err = gather_dirty(c, w, &c->img_src[i], k, dirty);
	if (err == 0)
		err = patch_shifted(c, w, k, dirty);
	if (err < 0) /* leave none touched for the next */
		memset(w->touched, 0, c->tiles_per_image);
	return err;
}

typedef void (*lit_fn)(struct compose *c, unsigned s, uint32_t p, struct rle_span span);

/* Calls fn(c, s, p, span) for each position p of the patch's list whose
 * image source s has tiles in, with the mask bytes they lie in (all,
 * where not known): along the source's list of images with tiles or the
 * patch's, whichever is shorter. */
static void for_each_lit(struct compose *c, unsigned s, lit_fn fn)
{
	const struct compose_source *src = &c->src[s];
	const struct tile_set *d = c->dirty;
	const struct rle_volume *r = src->rle;
	if (r && r->lit && r->lit_count < d->listed) {
		for (uint32_t i = 0; i < r->lit_count; i++)
			if (d->images[r->lit[i]])
				fn(c, s, c->pos[r->lit[i]], r->images[r->lit[i]].span);
		return;
	}
	for (uint32_t p = 0; p < d->listed; p++) {
		uint32_t k = d->list[p];
		if (source_mask(src, k))
			fn(c, s, p, r ? r->images[k].span : (struct rle_span){ 0, c->mask_bytes - 1 });
	}
}

static void count_lit(struct compose *c, unsigned s, uint32_t p, struct rle_span span)
{
	c->img_first[p + 1]++;
}

static void place_lit(struct compose *c, unsigned s, uint32_t p, struct rle_span span)
{
	c->img_src[c->img_first[p]++] = (struct img_source){ s, span };
}

/* The sources of each image the patch marks (img_first, img_src): an
 * object touches a few images, and there may be thousands of objects. */
static int index_sources(struct compose *c)
{
	const uint32_t listed = c->dirty->listed;
	if (!c->img_first && !(c->img_first = malloc((c->image_count + 1) * sizeof(*c->img_first))))
		return -ENOMEM;
	if (!c->pos && !(c->pos = malloc(c->image_count * sizeof(*c->pos))))
		return -ENOMEM;
	memset(c->img_first, 0, (listed + 1) * sizeof(*c->img_first));
	for (uint32_t p = 0; p < listed; p++)
		c->pos[c->dirty->list[p]] = p;
	for (unsigned s = 0; s < c->n; s++)
		for_each_lit(c, s, count_lit);
	for (uint32_t p = 0; p < listed; p++)
		c->img_first[p + 1] += c->img_first[p];
	size_t total = c->img_first[listed];
	if (total > c->img_src_cap) {
		struct img_source *a = realloc(c->img_src, total * sizeof(*a));
		if (!a)
			return -ENOMEM;
		c->img_src = a;
		c->img_src_cap = total;
	}
	/* Placed at their image's start, which moves on to the next's. */
	for (unsigned s = 0; s < c->n; s++)
		for_each_lit(c, s, place_lit);
	for (uint32_t p = listed; p > 0; p--)
		c->img_first[p] = c->img_first[p - 1];
	c->img_first[0] = 0;
	return 0;
}

/* Whether so few tiles are dirty (a small object moving) that waking the
 * pool's workers would cost more than patching them on this thread. */
static bool few_dirty(const struct compose *c)
{
	return c->dirty_tiles <= (c->awake ? c->few_awake : c->few_cold);
}

/* A patch of few tiles, on this thread: the listed images in turn. */
static int patch_alone(struct compose *c, struct volume *vol)
{
	int err = 0;
	c->out = vol;
	for (uint32_t p = 0; p < c->dirty->listed && err == 0; p++)
		err = patch_image(c, &c->w[0], p);
	c->out = NULL;
	return err;
}

int compose_patch(struct compose *c, struct volume *vol, const struct tile_set *dirty, const struct compose_source *src,
		  unsigned n)
{
	int err = check_sources(c, vol, dirty, src, n);
	if (err < 0)
		return err;
	c->src = src;
	c->n = n;
	c->dirty = dirty;
	c->dirty_tiles = tile_set_count(dirty);
	if ((err = index_sources(c)) < 0)
		return err;
	return few_dirty(c) ? patch_alone(c, vol) : run_images(c, vol, patch_image, dirty->listed);
}

uint64_t compose_last_tiles(const struct compose *c)
{
	return c->dirty_tiles;
}

/* A composition from nothing is a patch of an empty volume where every
 * tile is dirty. */
int compose_volumes(struct compose *c, struct volume *out, const struct compose_source *src, unsigned n)
{
	if (out->image_count != c->image_count)
		return -EINVAL;
	volume_clear(out);
	return compose_patch(c, out, &c->all_dirty, src, n);
}

/* Image k of dirty |= mask over bytes first..last. */
static void mark_image(struct tile_set *dirty, uint32_t k, const uint8_t *mask, uint32_t first, uint32_t last)
{
	uint8_t *d = tile_set_flag(dirty, k);
	for (uint32_t b = first; b <= last; b++)
		d[b] |= mask[b];
}

void compose_add_footprint(struct tile_set *dirty, const struct compose_source *src)
{
	const struct rle_volume *r = src->rle;
	for (uint32_t i = 0; r && r->lit && i < r->lit_count; i++) {
		const struct rle_image *img = &r->images[r->lit[i]];
		mark_image(dirty, r->lit[i], img->data, img->span.first, img->span.last);
	}
	if (r && r->lit)
		return;
	for (uint32_t k = 0; k < dirty->image_count; k++) {
		const uint8_t *mask = source_mask(src, k);
		if (mask)
			mark_image(dirty, k, mask, 0, dirty->mask_bytes - 1);
	}
}

/* ---- turned canvases ---- */

bool compose_can_turn(const struct compose *c)
{
	return c->halftone && (!c->geom.mirrored || c->geom.width % VOLUME_TILE == 0);
}

/* Canvas tile src mirrored left to right into dst (rows stay). */
static void mirror_canvas(const uint8_t *src, uint8_t *dst)
{
	for (uint32_t row = 0; row < 3 * VOLUME_TILE; row++) {
		const uint8_t *s = src + (size_t)row * HALFTONE_ROW_BYTES;
		uint8_t *d = dst + (size_t)row * HALFTONE_ROW_BYTES;
		for (uint32_t x = 0; x < VOLUME_TILE; x++)
			d[halftone_pos(VOLUME_TILE - 1 - x)] = s[halftone_pos(x)];
	}
}

/* Canvas tile (row mask first) halftoned at image k's phase and ORed into
 * tile t of w's dense image; *count counts the tiles newly touched. */
static void halftone_into(struct compose *c, struct compose_worker *w, uint32_t k, uint32_t t, const uint8_t *tile,
			  uint32_t *count)
{
	uint8_t packed[VOLUME_TILE_BYTES];
	uint32_t rows, tiles_x = volume_tiles_across(c->geom.width);
	memcpy(&rows, tile, sizeof(rows));
	if (c->halftone(tile + sizeof(rows), rows, brightness_table(&c->thr, k, t % tiles_x), packed)) {
		*count += !w->touched[t];
		dense_or(w, t, packed);
	}
}

/* A turned source's coded canvas tile t (of code, avail bytes), mirrored
 * when asked, lifted, halftoned at image k's phase and ORed into w's dense
 * image; *count counts the tiles newly touched. Returns the coded bytes
 * read, 0 when the code is broken. */
static size_t turn_tile(struct compose *c, struct compose_worker *w, uint32_t k, uint32_t t, bool mirror, int32_t lift,
			const uint8_t *code, size_t avail, uint32_t *count)
{
	uint8_t buf[CANVAS_TILE_BYTES], mirrored[CANVAS_TILE_BYTES], lifted[2][CANVAS_TILE_BYTES];
	memset(buf, 0, sizeof(buf));
	size_t used = rle_or_coded(code, avail, buf, CANVAS_TILE_BYTES);
	if (!used)
		return 0;
	const uint8_t *tile = buf;
	uint32_t tiles_x = volume_tiles_across(c->geom.width);
	if (mirror) {
		memcpy(mirrored, buf, sizeof(uint32_t)); /* the row mask */
		mirror_canvas(buf + sizeof(uint32_t), mirrored + sizeof(uint32_t));
		tile = mirrored;
		t = (t / tiles_x) * tiles_x + (tiles_x - 1 - t % tiles_x);
	}
	if (!lift) {
		halftone_into(c, w, k, t, tile, count);
		return used;
	}
	uint32_t ty[2];
	unsigned parts = canvas_tile_lift(tile, t / tiles_x, lift, c->geom.height, lifted, ty);
	for (unsigned i = 0; i < parts; i++)
		halftone_into(c, w, k, ty[i] * tiles_x + t % tiles_x, lifted[i], count);
	return used;
}

/* Image k of every turned source into w's dense image, then packed into
 * c->out. */
static int turn_image(struct compose *c, struct compose_worker *w, uint32_t k)
{
	uint32_t count = 0;
	for (unsigned s = 0; s < c->n; s++) {
		bool mirror;
		uint32_t j = geometry_turn_source(&c->geom, k, c->turned[s].turn % c->geom.images_per_rev, &mirror);
		const struct rle_image *img = &c->turned[s].canvas->images[j];
		if (!img->tile_count)
			continue;
		size_t avail;
		const uint8_t *code = rle_codes(c, img, &avail);
		for (uint32_t t = 0; t < c->tiles_per_image; t++) {
			if (!bit(img->data, t))
				continue;
			size_t used = turn_tile(c, w, k, t, mirror, c->turned[s].lift, code, avail, &count);
			if (!used)
				return -EINVAL;
			code += used;
			avail -= used;
		}
	}
	return emit_image(c, w, k, count);
}

int compose_turned(struct compose *c, struct volume *out, const struct turned_source *src, unsigned n)
{
	if (!compose_can_turn(c) || out->image_count != c->image_count)
		return -EINVAL;
	for (unsigned s = 0; s < n; s++)
		if (src[s].canvas->tile_bytes != CANVAS_TILE_BYTES || src[s].canvas->image_count != c->image_count)
			return -EINVAL;
	volume_clear(out);
	c->turned = src;
	c->n = n;
	return run_images(c, out, turn_image, c->image_count);
}

unsigned canvas_tile_lift(const uint8_t *src, uint32_t ty, int32_t lift, uint32_t height,
			  uint8_t out[2][CANVAS_TILE_BYTES], uint32_t out_ty[2])
{
	/* Row y of the tile lands on image row top + y: tile row first or
	 * the next (floor division: top may be negative). */
	int64_t top = (int64_t)ty * VOLUME_TILE - lift;
	int64_t first = top >= 0 ? top / VOLUME_TILE : -((-top + VOLUME_TILE - 1) / VOLUME_TILE);
	uint32_t rows, masks[2] = { 0, 0 };
	memcpy(&rows, src, sizeof(rows));
	memset(out, 0, 2 * (size_t)CANVAS_TILE_BYTES);
	for (; rows; rows &= rows - 1) {
		uint32_t y = (uint32_t)__builtin_ctz(rows);
		int64_t v = top + y;
		if (v < 0 || v >= height)
			continue;
		unsigned i = (unsigned)(v / VOLUME_TILE - first);
		uint32_t dy = (uint32_t)(v % VOLUME_TILE);
		masks[i] |= 1u << dy;
		for (int p = 0; p < 3; p++)
			memcpy(out[i] + sizeof(uint32_t) + p * HALFTONE_PLANE_BYTES + dy * HALFTONE_ROW_BYTES,
			       src + sizeof(uint32_t) + p * HALFTONE_PLANE_BYTES + y * HALFTONE_ROW_BYTES,
			       HALFTONE_ROW_BYTES);
	}
	unsigned n = 0;
	for (unsigned i = 0; i < 2; i++) {
		if (!masks[i])
			continue;
		if (n != i)
			memcpy(out[n], out[i], CANVAS_TILE_BYTES);
		memcpy(out[n], &masks[i], sizeof(uint32_t));
		out_ty[n++] = (uint32_t)(first + i);
	}
	return n;
}

int rle_volume_decode(const struct rle_volume *r, struct volume *out)
{
	struct compose *c = compose_create(&out->geom, NULL);
	if (!c)
		return -ENOMEM;
	struct compose_source s = { .rle = r };
	int err = compose_volumes(c, out, &s, 1);
	compose_destroy(c);
	return err;
}
