#include "output.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include <spindle/spindle.h>

#include "config.h"
#include "mat.h"

/* Spindle objects and list vertices held at most (the daemon's
 * max-objects is 4096 and max-vertices 32 Mi by default, and a client over
 * either is disconnected); past them, segments are sent as immediate
 * geometry, which SGL_GEOM_MAX bounds. */
#define MAX_OBJECTS 3500
#define MAX_VERTICES (20u << 20)

struct sgl_slot {
	struct spindle_layer *layer;
	uint64_t serial; /* of the list it shows, 0: none */
	float m[16];
	bool has_m;
};

struct sgl_out {
	uint32_t ctx_id;
	uint64_t gen; /* the connection its objects were made on */
	struct sgl_slot *slots;
	uint32_t n_slots;
	struct spindle_layer *dyn_layer;
	struct spindle_list *dyn_list;
	struct sgl_geom last_dyn;
	float dyn_m[16];
	bool dyn_has_m, in_flight;
	uint64_t frames, sent, dropped, offline, shown;
	struct sgl_out *next;
};

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static struct spindle *sp;
static uint64_t gen = 1, serials, ticks, next_try;
static bool down_warned;
static float half_height = 1;
static uint32_t objects, vertices;
static struct sgl_out *outs;
static pthread_once_t fork_once = PTHREAD_ONCE_INIT;

static const char *socket_path(void)
{
	const char *p = getenv("SPINDLE_SOCKET");
	return p && *p ? p : SPINDLE_DEFAULT_SOCKET;
}

/* Under the lock: the connection is gone; every object with it. */
static void lost(const char *why)
{
	if (!sp)
		return;
	sgl_warn_once(NULL, "lost the display (%s): the program runs on without it; reconnecting", why);
	spindle_disconnect(sp);
	sp = NULL;
	gen++;
	objects = vertices = 0;
	down_warned = true;
	next_try = sgl_now_ns() + (uint64_t)sgl_config()->retry_ms * 1000000u;
}

static bool check(int r)
{
	if (r >= 0 || r == -EAGAIN)
		return true;
	const char *e = sp ? spindle_get_error(sp) : NULL;
	lost(e ? e : strerror(-r));
	return false;
}

static void on_frame(void *data, const struct spindle_frame *frame)
{
	uint32_t id = (uint32_t)(uintptr_t)data;
	for (struct sgl_out *o = outs; o; o = o->next) {
		if (o->ctx_id == id && o->gen == gen) {
			o->in_flight = false;
			o->shown++;
		}
	}
	sgl_trace("shown ctx %u volume %llu", id, (unsigned long long)frame->volume_seq);
}

static void on_refused(void *data, enum spindle_refusal code, uint32_t object, const char *message)
{
	sgl_warn_once("refused", "the display refused a frame: %s", message);
	/* Its frame callback waits for a later commit: let one come. */
	for (struct sgl_out *o = outs; o; o = o->next)
		o->in_flight = false;
}

static const struct spindle_listener listener = { .refused = on_refused };

static void try_connect(void)
{
	uint64_t now = sgl_now_ns();
	if (sp || now < next_try)
		return;
	next_try = now + (uint64_t)sgl_config()->retry_ms * 1000000u;
	sp = spindle_connect(NULL);
	if (sp && spindle_get_version(sp) < 2) {
		spindle_disconnect(sp);
		sp = NULL;
		errno = EPROTONOSUPPORT;
	}
	if (!sp) {
		if (!down_warned)
			sgl_warn_once(NULL, "no display at %s (%s): the program runs on without it; retrying",
				      socket_path(), strerror(errno));
		down_warned = true;
		return;
	}
	gen++;
	objects = vertices = 0;
	down_warned = false;
	half_height = spindle_get_device_info(sp)->half_height;
	spindle_set_listener(sp, &listener, NULL);
	sgl_note("showing on %s (%s)", spindle_get_device_info(sp)->name, socket_path());
	sgl_trace("connected half-height %g", half_height);
}

/* ---- fork: the child does not share the parent's connection ---- */

static void fork_prepare(void)
{
	pthread_mutex_lock(&lock);
}

static void fork_parent(void)
{
	pthread_mutex_unlock(&lock);
}

static void fork_child(void)
{
	if (sp)
		spindle_disconnect(sp); /* frees and closes the child's copy only */
	sp = NULL;
	gen++;
	objects = vertices = 0;
	next_try = 0;
	pthread_mutex_unlock(&lock);
}

static void register_fork(void)
{
	pthread_atfork(fork_prepare, fork_parent, fork_child);
}

/* ---- per context ---- */

struct sgl_out *sgl_out_create(uint32_t ctx_id)
{
	pthread_once(&fork_once, register_fork);
	struct sgl_out *o = calloc(1, sizeof(*o));
	if (!o)
		abort();
	o->ctx_id = ctx_id;
	sgl_geom_init(&o->last_dyn);
	pthread_mutex_lock(&lock);
	o->gen = gen;
	o->next = outs;
	outs = o;
	pthread_mutex_unlock(&lock);
	return o;
}

/* Under the lock: forgets objects of an older connection (freed with it). */
static void sync_gen(struct sgl_out *o)
{
	if (o->gen == gen)
		return;
	o->gen = gen;
	o->n_slots = 0;
	o->dyn_layer = NULL;
	o->dyn_list = NULL;
	o->dyn_has_m = false;
	o->in_flight = false;
	sgl_geom_reset(&o->last_dyn);
}

static void take_down(struct sgl_out *o)
{
	for (uint32_t i = 0; i < o->n_slots; i++)
		spindle_layer_destroy(o->slots[i].layer);
	spindle_layer_destroy(o->dyn_layer);
	spindle_list_destroy(o->dyn_list);
	objects -= o->n_slots + (o->dyn_layer != NULL) + (o->dyn_list != NULL);
	check(spindle_commit(sp));
}

void sgl_out_destroy(struct sgl_out *o)
{
	if (!o)
		return;
	pthread_mutex_lock(&lock);
	for (struct sgl_out **p = &outs; *p; p = &(*p)->next) {
		if (*p == o) {
			*p = o->next;
			break;
		}
	}
	if (sp && o->gen == gen)
		take_down(o);
	pthread_mutex_unlock(&lock);
	free(o->slots);
	sgl_geom_free(&o->last_dyn);
	free(o);
}

enum sgl_send sgl_out_poll(struct sgl_out *o, float *h)
{
	pthread_mutex_lock(&lock);
	try_connect();
	if (sp) {
		int r = spindle_dispatch(sp);
		if (r >= 0)
			r = spindle_flush(sp);
		check(r);
	}
	sync_gen(o);
	*h = half_height;
	enum sgl_send st = !sp ? SGL_OFFLINE : o->in_flight ? SGL_DROPPED : SGL_SENT;
	o->frames++;
	if (st == SGL_DROPPED)
		o->dropped++;
	else if (st == SGL_OFFLINE)
		o->offline++;
	pthread_mutex_unlock(&lock);
	return st;
}

/* ---- retained lists of segments ---- */

static const enum spindle_mode modes[SGL_KINDS] = { SPINDLE_POINTS, SPINDLE_LINES, SPINDLE_TRIANGLES };

static int draw_geom(struct spindle_list *l, struct spindle_buffer *b, const struct sgl_geom *g, size_t *offset)
{
	int r = 0;
	for (int k = 0; k < SGL_KINDS && r >= 0; k++) {
		if (!g->n[k])
			continue;
		r = spindle_list_draw(l, modes[k], b, *offset, g->n[k], sizeof(struct sgl_vertex));
		*offset += (size_t)g->n[k] * sizeof(struct sgl_vertex);
	}
	return r;
}

/* One buffer of a then b, drawn into l (b's vertices in colour rgba). */
static int fill_list(struct spindle_list *l, const struct sgl_geom *a, const struct sgl_geom *b, uint32_t rgba)
{
	size_t n = (size_t)sgl_geom_count(a) + (b ? sgl_geom_count(b) : 0), at = 0;
	struct sgl_vertex *data = malloc(n * sizeof(*data));
	if (!data)
		return -ENOMEM;
	const struct sgl_geom *parts[2] = { a, b };
	for (int p = 0; p < 2; p++) {
		for (int k = 0; k < SGL_KINDS && parts[p]; k++) {
			if (parts[p]->n[k])
				memcpy(data + at, parts[p]->v[k], parts[p]->n[k] * sizeof(*data));
			at += parts[p]->n[k];
		}
	}
	struct spindle_buffer *buf = spindle_buffer_create(sp, data, n * sizeof(*data));
	free(data);
	if (!buf)
		return -errno;
	size_t offset = 0;
	int r = spindle_list_set_vertex_format(l, SPINDLE_XYZ_RGBA8);
	if (r >= 0)
		r = draw_geom(l, buf, a, &offset);
	if (r >= 0 && b && !sgl_geom_empty(b)) {
		r = spindle_list_set_vertex_format(l, SPINDLE_XYZ);
		if (r >= 0)
			r = spindle_list_set_color(l, rgba >> 24, (rgba >> 16) & 255, (rgba >> 8) & 255, rgba & 255);
		if (r >= 0)
			r = draw_geom(l, buf, b, &offset);
	}
	spindle_buffer_destroy(buf);
	return r;
}

static uint32_t pack(const uint8_t c[4])
{
	return (uint32_t)c[0] << 24 | (uint32_t)c[1] << 16 | (uint32_t)c[2] << 8 | c[3];
}

/* The retained list showing seg with inherited colour rgba: made once. NULL
 * with *ok true: over the object budget (send it as geometry). */
static struct sgl_variant *variant(const struct sgl_call *call, bool *ok)
{
	struct sgl_seg *seg = call->seg;
	struct sgl_seg_out *so = &seg->out;
	uint32_t key = sgl_geom_empty(&seg->inherit) ? 0 : pack(call->rgba);
	if (so->gen != gen)
		*so = (struct sgl_seg_out){ .gen = gen };
	struct sgl_variant *v = &so->var[0];
	for (int i = 0; i < SGL_VARIANTS; i++) {
		if (so->var[i].serial && so->var[i].rgba == key) {
			so->var[i].used = ++ticks;
			return &so->var[i];
		}
		if (so->var[i].used < v->used)
			v = &so->var[i]; /* the least recently used, or a free one */
	}
	uint32_t n = sgl_geom_count(&seg->own) + sgl_geom_count(&seg->inherit);
	if (objects >= MAX_OBJECTS || vertices + n > MAX_VERTICES) {
		sgl_warn_once("objects", "more display lists than the display's quotas: the rest are sent as "
					 "geometry each frame");
		return NULL;
	}
	if (v->list) {
		spindle_list_destroy(v->list);
		objects--;
		vertices -= v->vertices;
	}
	*v = (struct sgl_variant){ 0 };
	struct spindle_list *l = spindle_list_create(sp);
	int r = l ? fill_list(l, &seg->own, &seg->inherit, key) : -errno;
	if (!(*ok = check(r)))
		return NULL;
	objects++;
	vertices += n;
	*v = (struct sgl_variant){ .list = l, .serial = ++serials, .rgba = key, .vertices = n, .used = ++ticks };
	sgl_trace("upload list %u segment %u own %u inherit %u colour %08x", call->list->name, seg->index,
		  sgl_geom_count(&seg->own), sgl_geom_count(&seg->inherit), key);
	return v;
}

void sgl_out_seg_release(struct sgl_seg *seg)
{
	pthread_mutex_lock(&lock);
	for (int i = 0; sp && seg->out.gen == gen && i < SGL_VARIANTS; i++) {
		if (seg->out.var[i].list) {
			spindle_list_destroy(seg->out.var[i].list);
			objects--;
			vertices -= seg->out.var[i].vertices;
		}
	}
	seg->out = (struct sgl_seg_out){ 0 };
	pthread_mutex_unlock(&lock);
}

/* ---- a frame ---- */

static struct spindle_layer *new_layer(struct spindle_list *list)
{
	struct spindle_layer *y = spindle_layer_create(sp);
	if (!check(y ? 0 : -errno))
		return NULL;
	objects++;
	if (list && !check(spindle_layer_set_list(y, list)))
		return NULL;
	return y;
}

static bool set_transform(struct spindle_layer *y, float have[16], bool *has, const float m[16])
{
	if (*has && sgl_mat_equal(have, m))
		return true;
	memcpy(have, m, 16 * sizeof(float));
	*has = true;
	return check(spindle_layer_set_transform(y, m));
}

/* Layer i shows the list of serial with transform m. */
static bool show_slot(struct sgl_out *o, uint32_t i, const struct sgl_variant *v, const float m[16])
{
	if (i == o->n_slots) {
		struct sgl_slot *slots = realloc(o->slots, (i + 1) * sizeof(*slots));
		if (!slots)
			return false;
		o->slots = slots;
		slots[i] = (struct sgl_slot){ .layer = new_layer(NULL) };
		if (!slots[i].layer)
			return false;
		o->n_slots++;
	}
	struct sgl_slot *s = &o->slots[i];
	if (s->serial != v->serial) {
		s->serial = v->serial;
		if (!check(spindle_layer_set_list(s->layer, v->list)))
			return false;
	}
	return set_transform(s->layer, s->m, &s->has_m, m);
}

static bool hide_slots(struct sgl_out *o, uint32_t from)
{
	for (uint32_t i = from; i < o->n_slots; i++) {
		if (o->slots[i].serial && !check(spindle_layer_set_list(o->slots[i].layer, NULL)))
			return false;
		o->slots[i].serial = 0;
	}
	return true;
}

/* The immediate geometry (and calls not shown by reference): sent again
 * only when it changed. */
static bool send_dyn(struct sgl_out *o, const struct sgl_geom *g, const float map[16])
{
	if (!o->dyn_list) {
		o->dyn_list = spindle_list_create(sp);
		if (!check(o->dyn_list ? 0 : -errno))
			return false;
		objects++;
		sgl_geom_reset(&o->last_dyn);
		if (!(o->dyn_layer = new_layer(o->dyn_list)))
			return false;
	}
	if (!sgl_geom_equal(g, &o->last_dyn)) {
		int r = spindle_list_clear(o->dyn_list);
		if (r >= 0 && !sgl_geom_empty(g))
			r = fill_list(o->dyn_list, g, NULL, 0);
		if (!check(r))
			return false;
		sgl_geom_copy(&o->last_dyn, g);
	}
	return set_transform(o->dyn_layer, o->dyn_m, &o->dyn_has_m, map);
}

static bool send_calls(struct sgl_out *o, struct sgl_frame *f, const float map[16], uint32_t *used)
{
	for (uint32_t i = 0; i < f->n_calls; i++) {
		const struct sgl_call *c = &f->calls[i];
		float m[16];
		sgl_mat_mul(m, map, c->s);
		bool ok = true;
		struct sgl_variant *v = NULL;
		bool layer = *used < o->n_slots || objects < MAX_OBJECTS; /* one there, or room for one */
		if (sgl_mat_is_affine(m) && *used < sgl_config()->max_layers && layer)
			v = variant(c, &ok);
		if (!ok)
			return false;
		if (v && !show_slot(o, (*used)++, v, m))
			return false;
		if (!v) {
			sgl_geom_append(&f->imm, &c->seg->own, c->s, NULL);
			sgl_geom_append(&f->imm, &c->seg->inherit, c->s, c->rgba);
		}
	}
	return true;
}

enum sgl_send sgl_out_send(struct sgl_out *o, struct sgl_frame *f, const float map[16])
{
	pthread_mutex_lock(&lock);
	sync_gen(o);
	uint32_t used = 0;
	bool ok = sp && send_calls(o, f, map, &used);
	ok = ok && send_dyn(o, &f->imm, map) && hide_slots(o, used);
	ok = ok && check(spindle_request_frame(sp, on_frame, (void *)(uintptr_t)o->ctx_id));
	ok = ok && check(spindle_commit(sp));
	if (ok) {
		o->in_flight = true;
		o->sent++;
	} else {
		o->offline++;
	}
	sgl_trace("sent ctx %u layers %u dynamic %u ok %d", o->ctx_id, used, sgl_geom_count(&f->imm), ok);
	pthread_mutex_unlock(&lock);
	return ok ? SGL_SENT : SGL_OFFLINE;
}
