/* The CPU renderer's kept binning (render_cpu_options.keep): a renderer
 * that keeps its bins while the scene's draws stay the same renders, over
 * random sequences of changes, bit for bit what a fresh renderer renders,
 * and keeps exactly when nothing it bins from changed: the same scene
 * again keeps; a new transform, colour, turn, lift, point size, count,
 * draw added or removed, or new data (a new data_id, also at the same
 * address with other contents) bins again; a draw without a data_id is
 * never kept. On a mirrored and an unmirrored geometry, one and two
 * threads; and the GL renderer on OSMesa (where it runs) against a GL
 * renderer that keeps nothing. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "render_cpu.h"
#include "render_gl.h"
#include "rtest.h"

static uint64_t rng = 0x2545f4914f6cdd1dull;

static double rnd(void)
{
	return rtest_rnd(&rng);
}

static double range(double a, double b)
{
	return rtest_range(&rng, a, b);
}

#define DRAWS 4
#define VERTS 600 /* per draw: 200 triangles, 300 segments, 600 points */

/* A draw's data: vertices the test may rewrite in place. */
struct data {
	float xyz[3 * VERTS];
};

static uint64_t data_ids;

/* Fresh random contents in d, under a new number. */
static uint64_t fill(struct data *d)
{
	for (int i = 0; i < VERTS; i++) {
		double r = range(0.0, 1.0), phi = range(-M_PI, M_PI), y = range(-0.9, 0.9);
		double s = rnd() < 0.5 ? 0.01 : 0.2;
		d->xyz[3 * i] = (float)(r * cos(phi) + range(-s, s));
		d->xyz[3 * i + 1] = (float)(y + range(-s, s));
		d->xyz[3 * i + 2] = (float)(r * sin(phi) + range(-s, s));
	}
	return ++data_ids;
}

static void random_transform(float t[16])
{
	rtest_identity(t);
	float a = (float)range(-M_PI, M_PI), c = cosf(a), s = sinf(a);
	t[0] = c, t[2] = -s, t[8] = s, t[10] = c;
	t[12] = (float)range(-0.1, 0.1);
	t[13] = (float)range(-0.1, 0.1);
}

static void set_count(struct scene_draw *d)
{
	static const enum scene_prim prims[] = { SCENE_TRIANGLES, SCENE_LINES, SCENE_POINTS };
	d->prim = prims[(uint32_t)(rnd() * 3)];
	uint32_t per = d->prim == SCENE_TRIANGLES ? 3 : d->prim == SCENE_LINES ? 2 : 1;
	d->count = (uint32_t)(range(0.3, 1.0) * VERTS) / per * per;
}

/* One random change to the scene (or none). */
static void change(struct scene *s, struct scene_draw *draws, struct data *data, uint32_t g_images, bool turns)
{
	uint32_t i = (uint32_t)(rnd() * s->draw_count);
	struct scene_draw *d = &draws[i];
	int what = (int)(rnd() * 11);
	if (!turns && (what == 5 || what == 6))
		what = 0; /* the GL renderers hand turns and lifts to the CPU */
	switch (what) {
	case 0:
	case 1:
	case 2:
		return; /* the same again */
	case 3:
		random_transform(d->transform);
		return;
	case 4:
		d->rgb[(int)(rnd() * 3)] ^= 0x5a;
		return;
	case 5:
		d->turn = (uint16_t)((d->turn + 1 + (uint32_t)(rnd() * (g_images - 1))) % g_images);
		return;
	case 6:
		d->lift = (int16_t)(rnd() < 0.5 ? -2 : 3);
		return;
	case 7:
		d->point_size = (uint8_t)(d->point_size % 4 + 1);
		return;
	case 8: /* new contents at the same address, a new number */
		d->data_id = fill(&data[i]);
		return;
	case 9: {
		struct scene_draw was = *d;
		set_count(d);
		if (d->prim == was.prim && d->count == was.count)
			d->count -= d->prim == SCENE_TRIANGLES ? 3 : d->prim == SCENE_LINES ? 2 : 1;
		return;
	}
	default: /* a draw more or fewer */
		if (s->draw_count == 1 || (s->draw_count < DRAWS && rnd() < 0.5))
			s->draw_count++;
		else
			s->draw_count--;
		return;
	}
}

/* What the binning is made of (scene.h, scene_draw.data_id): the same
 * numbered data, drawn the same way. */
static bool same_draw(const struct scene_draw *a, const struct scene_draw *b)
{
	return a->data_id && a->data_id == b->data_id && a->prim == b->prim && a->count == b->count &&
	       a->xyz == b->xyz && a->point_size == b->point_size && a->turn == b->turn && a->lift == b->lift &&
	       !memcmp(a->transform, b->transform, sizeof(a->transform)) && !memcmp(a->rgb, b->rgb, 3);
}

/* A pass's draws, as the renderer bins them. */
struct pass {
	struct scene_draw draws[DRAWS];
	uint32_t n;
};

/* Whether the renderer keeps the binning of pass b for pass a: all the same
 * numbered draws (an empty pass keeps nothing). */
static bool same_pass(const struct pass *a, const struct pass *b)
{
	if (!a->n || a->n != b->n)
		return false;
	for (uint32_t i = 0; i < a->n; i++)
		if (!same_draw(&a->draws[i], &b->draws[i]))
			return false;
	return true;
}

/* How many of the renderer's passes over s keep the binning of the pass
 * before (the last pass of the render before: *last, which becomes this
 * render's): each lift's draws, unlifted, lowest lift first, then the
 * draws without a lift (render_cpu.c). */
static uint64_t passes_kept(const struct scene *s, struct pass *last)
{
	uint64_t kept = 0;
	static const int32_t lifts[] = { -2, 3, 0 }; /* change()'s, in order */
	for (int l = 0; l < 3; l++) {
		struct pass p = { 0 };
		for (uint32_t i = 0; i < s->draw_count; i++) {
			if (s->draws[i].lift != lifts[l])
				continue;
			p.draws[p.n] = s->draws[i];
			p.draws[p.n++].lift = 0;
		}
		if (lifts[l] == 0 || p.n) {
			kept += same_pass(&p, last);
			*last = p;
		}
	}
	return kept;
}

/* The draws a sequence starts from: random data, numbered. */
static void first_draws(struct scene_draw draws[DRAWS], struct data data[DRAWS])
{
	for (int i = 0; i < DRAWS; i++) {
		struct rtest_mesh none = { 0 };
		uint8_t rgb[3];
		rtest_colour((uint32_t)i, rgb);
		draws[i] = rtest_draw(SCENE_TRIANGLES, &none, rgb[0], rgb[1], rgb[2]);
		draws[i].xyz = data[i].xyz;
		draws[i].data_id = fill(&data[i]);
		set_count(&draws[i]);
		random_transform(draws[i].transform);
	}
}

/* The scene of the next step: a lift, or a draw without a number, lasts
 * one render, so that most steps can keep (lifted renders bin each lift's
 * draws apart; draws without a number are never kept); then one draw
 * loses its number, or change() changes something. */
static void next_step(struct scene *s, struct scene_draw *draws, struct data *data, uint32_t g_images, bool turns)
{
	for (uint32_t i = 0; i < DRAWS; i++) {
		draws[i].lift = 0;
		if (!draws[i].data_id)
			draws[i].data_id = ++data_ids;
	}
	if (rnd() < 0.05)
		draws[(uint32_t)(rnd() * s->draw_count)].data_id = 0;
	else
		change(s, draws, data, g_images, turns);
}

/* A renderer: the CPU's, or (gl) a GL one, keeping bins or not. */
static struct renderer *make(const struct geometry *g, const char *gl, unsigned threads, bool keep)
{
	if (gl) {
		struct render_gl_options o = { .backend = gl, .threads = threads, .no_fallback = true, .keep = keep };
		return render_gl_create(g, &o);
	}
	struct render_cpu_options o = { .threads = threads, .keep = keep };
	return render_cpu_create_opts(g, &o);
}

static void check_sequence(const struct geometry *g, const char *gl, unsigned threads, int steps)
{
	static struct data data[DRAWS];
	struct scene_draw draws[DRAWS];
	first_draws(draws, data);
	struct scene s = { .draw_count = 2, .draws = draws };
	/* One renderer that keeps, one that never does; on GL a fresh one
	 * each step, which has uploaded nothing before (render_gl.c keeps
	 * the upload of kept bins). */
	struct renderer *kr = make(g, gl, threads, true), *fr = make(g, gl, threads, false);
	struct volume *kv = volume_create(g), *fv = volume_create(g);
	CHECK(kr && fr && kv && fv);
	uint64_t kept = 0, rebinned = 0;
	/* The draws the renderer binned last, when all have a number. */
	struct pass last = { 0 };
	for (int step = 0; step < steps; step++) {
		if (gl && step) {
			render_destroy(fr);
			fr = make(g, gl, threads, false);
			CHECK(fr != NULL);
		}
		CHECK(render_volume(fr, &s, fv) == 0 && render_volume(kr, &s, kv) == 0);
		CHECK_EQ(fr->stats.bins_kept, 0u);
		CHECK_MSG(rtest_same(kv, fv), "%s, %ux%u N %u, %u threads, step %d: a kept render differs",
			  gl ? gl : "cpu", g->width, g->height, g->images_per_rev, threads, step);
		uint64_t want = passes_kept(&s, &last);
		CHECK_MSG(kr->stats.bins_kept == want, "step %d: kept %llu, wanted %llu", step,
			  (unsigned long long)kr->stats.bins_kept, (unsigned long long)want);
		kept += want;
		rebinned += !want;
		next_step(&s, draws, data, g->images_per_rev, !gl);
	}
	CHECK_MSG(kept > (uint64_t)steps / 10 && rebinned > (uint64_t)steps / 4, "kept %llu, binned %llu",
		  (unsigned long long)kept, (unsigned long long)rebinned);
	render_destroy(kr);
	render_destroy(fr);
	volume_destroy(kv);
	volume_destroy(fv);
}

int main(void)
{
	struct geometry small = rtest_small(), odd = rtest_odd();
	check_sequence(&small, NULL, 1, 80);
	check_sequence(&small, NULL, 2, 80);
	check_sequence(&odd, NULL, 2, 80);
	if (rtest_have_gl(&small, "osmesa"))
		check_sequence(&small, "osmesa", 2, 24);
	return check_done();
}
