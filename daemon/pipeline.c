#include "pipeline.h"

#include <errno.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "cache.h"
#include "devices.h"
#include "log.h"
#include "pool.h"
#include "projector.h"
#include "render.h"
#include "snapshot.h"
#include "tile_set.h"
#include "volume.h"

#define MAX_BUFFERS 3

struct pipeline {
	struct pipeline_config cfg;
	const struct pipeline_listener *listener;
	void *data;
	struct renderer *renderer;
	struct projector *proj;
	uint32_t buffers;
	/* What the daemon wrote into each projector buffer, and whether the
	 * device is known to hold it (no error since): deltas build on that. */
	struct volume *content[MAX_BUFFERS];
	bool known[MAX_BUFFERS];
	int shown, pending, uploaded; /* buffer indices, -1 for none */
	int latest;                   /* the buffer holding the newest volume sent, -1 for none */
	int resend;                   /* a buffer whose volume the device lost, to send again */
	int failures;                 /* device errors since the last swap */
	/* The render target; holds a finished volume while ready is set. */
	struct volume *work;
	bool dirty, busy, ready;
	uint64_t next_seq, work_seq;
	/* building: the scene being compared or rendered; last: the scene of
	 * the last volume rendered (seq last_seq), kept with its references
	 * to vertex data until it is replaced, so that an identical scene is
	 * recognised by pointer identity (snapshot_same()). */
	struct snapshot snaps[2];
	struct snapshot *building, *last;
	uint32_t layers_left_out; /* by the last scene built, for the log */
	bool have_last;
	uint64_t last_seq;
	struct pipeline_stats stats;

	/* The render thread: takes a job when job is set, reports on done_fd. */
	pthread_t thread;
	pthread_mutex_t lock;
	pthread_cond_t cond;
	bool job, quit;
	const struct scene *job_scene;
	int result;
	int64_t started_ns;
	int done_fd;
	sd_event_source *done_source;
	sd_event_source *start_timer; /* a render put off (render_start_time()) */
	/* The object cache, or NULL (off), and the threads it composes on. */
	struct cache *cache;
	struct pool *pool;
	struct tile_set differ; /* an upload's tiles that may differ from its base (cache_may_differ()) */
	/* The calibration (calibration.h): its transform goes into each
	 * scene built; its axis offset moves each volume. The object cache
	 * moves what it renders itself (cache_set_offset()), so that it
	 * composes and hands out moved volumes as it does unmoved ones;
	 * without it, a render to be moved by the job's offset (job_u, job_v,
	 * the render thread's copy) is made in unshifted (NULL with the
	 * cache) and moved into work.
	 * A scene is the last one rendered only under the same calibration:
	 * building_cal is the one of building, last_cal of last. */
	struct calibration calibration, building_cal, last_cal;
	int32_t job_u, job_v;
	struct volume *unshifted;
};

/* The scene rendered into p->work, moved by the calibration's axis
 * offset (du, dv) when there is one: by the cache (given the offset with
 * the plan), else rendered into p->unshifted first. On the render
 * thread. */
static int render_job(struct pipeline *p, const struct scene *scene, int32_t du, int32_t dv)
{
	if (p->cache)
		return cache_render(p->cache, p->renderer, scene, p->work);
	return render_volume_moved(p->renderer, scene, p->unshifted, p->work, du, dv);
}

static void *render_thread(void *data)
{
	struct pipeline *p = data;
	pthread_mutex_lock(&p->lock);
	for (;;) {
		while (!p->job && !p->quit)
			pthread_cond_wait(&p->cond, &p->lock);
		if (p->quit)
			break;
		const struct scene *scene = p->job_scene;
		int32_t du = p->job_u, dv = p->job_v;
		pthread_mutex_unlock(&p->lock);
		int r = render_job(p, scene, du, dv);
		pthread_mutex_lock(&p->lock);
		p->result = r;
		p->job = false;
		uint64_t one = 1;
		if (write(p->done_fd, &one, sizeof(one)) < 0)
			log_error("render thread: cannot notify: %s", strerror(errno));
	}
	pthread_mutex_unlock(&p->lock);
	return NULL;
}

static void pipeline_kick(struct pipeline *p);

static bool buffer_available(const struct pipeline *p, int b)
{
	return b != p->shown && b != p->pending && b != p->uploaded;
}

/* The tiles where vol may differ from base, when the cache made both
 * (cache_may_differ()); NULL: any may. Between renders only. */
static const uint8_t *upload_differ(struct pipeline *p, const struct volume *vol, const struct volume *base)
{
	if (!p->cache || !base || p->busy)
		return NULL;
	return cache_may_differ(p->cache, base, vol, &p->differ) ? p->differ.mask : NULL;
}

/* Sends content[b] into buffer b: a delta against what b held (old),
 * when the device is known to hold that. */
static int upload_buffer(struct pipeline *p, int b, const struct volume *old)
{
	const struct volume *base = p->known[b] ? old : NULL;
	const uint8_t *differ = upload_differ(p, p->content[b], base);
	int r = p->proj->impl->upload(p->proj, (uint32_t)b, p->content[b], base, differ);
	if (differ)
		tile_set_clear(&p->differ);
	if (r < 0) {
		p->known[b] = false;
		if (r != -ENODEV)
			log_warn("projector upload failed: %s", strerror(-r));
		return r;
	}
	p->known[b] = true; /* until the device reports an error on it */
	p->stats.last_upload_bytes = (uint64_t)r;
	p->stats.bytes_uploaded += (uint64_t)r;
	p->stats.volumes_uploaded++;
	p->uploaded = p->latest = b;
	return 0;
}

/* The free buffer holding the newest volume the device is known to have:
 * the delta against it is the smallest. -1 if none is free. */
static int pick_buffer(const struct pipeline *p)
{
	int best = -1;
	uint64_t best_seq = 0;
	for (int b = 0; b < (int)p->buffers; b++) {
		uint64_t seq = p->known[b] ? p->content[b]->seq + 1 : 0;
		if (buffer_available(p, b) && (best < 0 || seq > best_seq)) {
			best = b;
			best_seq = seq;
		}
	}
	return best;
}

static void upload_ready(struct pipeline *p)
{
	int b = pick_buffer(p);
	if (b < 0)
		return;
	struct volume *old = p->content[b];
	p->content[b] = p->work;
	if (upload_buffer(p, b, old) < 0) {
		p->content[b] = old; /* keep the rendered volume for later */
		return;
	}
	p->work = old;
	p->ready = false;
}

/* The device lost buffer resend's volume (an error, or a re-plug): that
 * volume goes again, whole, unless a newer one is on its way. */
static void resend_lost(struct pipeline *p)
{
	int b = p->resend;
	p->resend = -1;
	if (p->ready || b == p->shown || p->failures > 3)
		return;
	upload_buffer(p, b, NULL);
}

/* The scene being built is the one last rendered: the volume of that
 * render (shown already, or on its way) shows these commits too. */
static void skip_unchanged(struct pipeline *p)
{
	snapshot_release(p->building);
	p->stats.volumes_skipped++;
	p->listener->scene_taken(p->data, p->last_seq, true);
}

static void start_render(struct pipeline *p)
{
	float pre[16];
	bool calibrated = calibration_has_transform(&p->calibration);
	if (calibrated)
		calibration_transform(&p->calibration, pre);
	if (snapshot_build(p->building, p->cfg.stage, p->cfg.max_scene_primitives,
			   p->renderer->impl->render_canvas ? &p->renderer->geom : NULL, calibrated ? pre : NULL) < 0) {
		log_error("out of memory building the scene; retrying with the next change");
		return;
	}
	p->dirty = false;
	if (p->building->layers_left_out != p->layers_left_out) {
		p->layers_left_out = p->building->layers_left_out;
		log_info("%u layers left out of the scene: over max-scene-primitives (%llu)", p->layers_left_out,
			 (unsigned long long)p->cfg.max_scene_primitives);
	}
	p->building_cal = p->calibration;
	if (p->have_last && snapshot_same(p->building, p->last) &&
	    !memcmp(&p->building_cal, &p->last_cal, sizeof(p->last_cal))) {
		skip_unchanged(p);
		return;
	}
	if (p->cache)
		cache_set_offset(p->cache, p->building_cal.axis_u, p->building_cal.axis_v);
	if (p->cache && cache_plan(p->cache, p->building) < 0)
		log_warn("object cache: out of memory planning volume %llu; rendering it whole",
			 (unsigned long long)p->next_seq);
	uint64_t seq = p->next_seq++;
	p->listener->scene_taken(p->data, seq, false);
	p->busy = true;
	p->work_seq = seq;
	pthread_mutex_lock(&p->lock);
	p->started_ns = now_ns();
	p->job_scene = &p->building->scene;
	p->job_u = p->building_cal.axis_u;
	p->job_v = p->building_cal.axis_v;
	p->job = true;
	pthread_cond_signal(&p->cond);
	pthread_mutex_unlock(&p->lock);
}

/* The scene just rendered becomes the one to compare with. */
static void keep_rendered(struct pipeline *p)
{
	struct snapshot *old = p->last;
	snapshot_release(old);
	p->last = p->building;
	p->building = old;
	p->last_cal = p->building_cal;
	p->have_last = true;
	p->last_seq = p->work_seq;
}

/* When the next render may start: now (0), at a time (ns), or not
 * before the volume on its way is swapped in (INT64_MAX).
 *
 * A scene that renders well within a revolution is rendered once the
 * volume before it is on display, and as late as it can be while its
 * volume still makes the next revolution start: the commits that came
 * meanwhile are all in it, and none waits behind a queue of volumes. A
 * commit is then shown within about a revolution and a lead. A slow
 * scene is rendered back to back instead, for throughput; so is every
 * scene while the projector is dark. */
static int64_t render_start_time(struct pipeline *p, int64_t now)
{
	int64_t period = 0;
	int64_t next = devices_next_boundary(p->cfg.devices, now, &period);
	if (!next)
		return 0;
	int64_t render = (int64_t)p->stats.last_render_us * 1000;
	int64_t lead = 2 * render + period / 8 + 4000000; /* render, upload, and slack */
	if (lead >= period / 2)
		return 0;
	if (p->uploaded >= 0 || p->pending >= 0)
		return INT64_MAX; /* kicked again at the swap */
	int64_t start = next - lead;
	return start <= now ? 0 : start;
}

static int on_start_timer(sd_event_source *s, uint64_t usec, void *data)
{
	pipeline_kick(data);
	return 0;
}

static void arm_start_timer(struct pipeline *p, int64_t at_ns)
{
	uint64_t usec = (uint64_t)at_ns / 1000;
	if (!p->start_timer) {
		if (sd_event_add_time(p->cfg.event, &p->start_timer, CLOCK_MONOTONIC, usec, 100, on_start_timer, p) <
		    0) {
			start_render(p); /* no timer: render now rather than never */
			return;
		}
	} else {
		sd_event_source_set_time(p->start_timer, usec);
	}
	sd_event_source_set_enabled(p->start_timer, SD_EVENT_ONESHOT);
}

static void pipeline_kick(struct pipeline *p)
{
	if (p->resend >= 0 && p->uploaded < 0 && p->pending < 0)
		resend_lost(p);
	if (p->ready && p->uploaded < 0)
		upload_ready(p);
	if (p->uploaded >= 0 && p->pending < 0) {
		/* At the next half-turn start where the device can
		 * (devices_half_turns()), else the next revolution start. */
		int r = devices_half_turns(p->cfg.devices) ? p->proj->impl->swap_half(p->proj, (uint32_t)p->uploaded)
							   : p->proj->impl->swap(p->proj, (uint32_t)p->uploaded);
		if (r == 0) {
			p->pending = p->uploaded;
			p->uploaded = -1;
		} else {
			log_warn("projector swap failed: %s", strerror(-r));
		}
	}
	if (p->dirty && !p->busy && !p->ready) {
		int64_t at = render_start_time(p, now_ns());
		if (at == 0)
			start_render(p);
		else if (at != INT64_MAX)
			arm_start_timer(p, at);
	}
}

static int render_done(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	struct pipeline *p = data;
	uint64_t n;
	if (read(fd, &n, sizeof(n)) < 0)
		return 0;
	pthread_mutex_lock(&p->lock);
	int r = p->result;
	int64_t ns = now_ns() - p->started_ns;
	pthread_mutex_unlock(&p->lock);
	p->busy = false;
	if (p->cache)
		cache_done(p->cache, r);
	if (r < 0) {
		log_error("render failed: %s", strerror(-r));
		snapshot_release(p->building);
		/* Render the scene again, even if it equals the last one
		 * rendered: frames tied to this volume wait for a newer one. */
		snapshot_release(p->last);
		p->have_last = false;
		p->dirty = true;
	} else {
		keep_rendered(p);
		if (p->cache) /* the scene before is gone: what only the cache holds goes too */
			cache_forget_orphans(p->cache);
		p->work->seq = p->work_seq; /* rendering cleared it */
		p->ready = true;
		p->stats.volumes_rendered++;
		p->stats.last_render_us = ns / 1000 > UINT32_MAX ? UINT32_MAX : (uint32_t)(ns / 1000);
		log_debug("volume %llu rendered in %.1f ms, %llu tiles", (unsigned long long)p->work->seq, ns / 1e6,
			  (unsigned long long)volume_tile_count(p->work));
	}
	pipeline_kick(p);
	return 0;
}

int64_t pipeline_render_started(struct pipeline *p)
{
	return p && p->busy ? p->started_ns : 0; /* both the loop's */
}

void pipeline_set_calibration(struct pipeline *p, const struct calibration *cal)
{
	p->calibration = *cal;
	pipeline_mark_dirty(p);
}

void pipeline_mark_dirty(struct pipeline *p)
{
	p->dirty = true;
	pipeline_kick(p);
}

void pipeline_swapped(struct pipeline *p, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	if (buffer >= p->buffers || (int)buffer != p->pending || p->content[buffer]->seq != seq) {
		log_warn("projector swapped to unexpected buffer %u (volume %llu)", buffer, (unsigned long long)seq);
		return;
	}
	p->shown = (int)buffer;
	p->pending = -1;
	p->failures = 0;
	struct volume *v = p->content[buffer];
	v->shown_ns = (uint64_t)time_ns;
	p->stats.volumes_shown++;
	p->listener->shown(p->data, v->seq, time_ns);
	pipeline_kick(p);
}

void pipeline_device_error(struct pipeline *p, uint32_t buffer, int err)
{
	if (buffer >= p->buffers)
		return; /* about no buffer: nothing the daemon holds is affected */
	int b = (int)buffer;
	p->known[b] = false;
	if (b != p->pending && b != p->uploaded)
		return;
	/* The device dropped the swap along with the volume. */
	if (b == p->pending)
		p->pending = -1;
	else
		p->uploaded = -1;
	p->failures++;
	if (p->failures > 3)
		log_error("projector keeps refusing volume %llu: %s; waiting for the next scene",
			  (unsigned long long)p->content[b]->seq, strerror(-err));
	p->resend = b;
	pipeline_kick(p);
}

void pipeline_projector_gone(struct pipeline *p)
{
	p->shown = p->pending = p->uploaded = p->resend = -1;
	for (uint32_t b = 0; b < MAX_BUFFERS; b++)
		p->known[b] = false;
}

/* How many buffers to use: as many as the device has, up to three. */
static uint32_t buffers_of(struct projector *proj)
{
	struct projector_info info;
	if (proj->impl->get_info(proj, &info) < 0 || info.buffers < 2)
		return 2; /* none attached yet: any projector has two */
	return info.buffers > MAX_BUFFERS ? MAX_BUFFERS : info.buffers;
}

void pipeline_projector_arrived(struct pipeline *p)
{
	pipeline_projector_gone(p); /* a new device holds nothing */
	p->buffers = buffers_of(p->proj);
	if (p->latest >= (int)p->buffers)
		p->latest = -1; /* that buffer does not exist on this device */
	p->failures = 0;
	p->resend = p->latest;
	pipeline_kick(p);
}

bool pipeline_swap_pending(const struct pipeline *p)
{
	return p->pending >= 0;
}

const struct volume *pipeline_shown(const struct pipeline *p)
{
	return p->shown >= 0 ? p->content[p->shown] : NULL;
}

void pipeline_get_stats(const struct pipeline *p, struct pipeline_stats *out)
{
	*out = p->stats;
}

void pipeline_set_cache_budget(struct pipeline *p, uint64_t bytes)
{
	if (p->cache)
		cache_set_budget(p->cache, bytes);
}

bool pipeline_get_cache_stats(const struct pipeline *p, struct cache_stats *out)
{
	if (!p->cache)
		return false;
	cache_get_stats(p->cache, out);
	return true;
}

static int create_cache(struct pipeline *p, const struct geometry *g)
{
	unsigned threads = p->cfg.threads;
	if (!threads) {
		long n = sysconf(_SC_NPROCESSORS_ONLN);
		threads = n > 0 ? (unsigned)n : 1;
	}
	p->pool = pool_create(threads);
	if (!p->pool)
		return -errno;
	p->cache = cache_create(g, p->cfg.cache_budget, p->pool, p->renderer->impl->render_canvas != NULL);
	if (!p->cache)
		return -errno;
	return tile_set_init(&p->differ, geometry_images_per_volume(g), volume_geometry_tiles(g));
}

static int create_volumes(struct pipeline *p, const struct geometry *g)
{
	p->work = volume_create(g);
	/* With the cache, it moves what it renders itself (render_job()). */
	p->unshifted = p->cfg.cache ? NULL : volume_create(g);
	if (!p->work || (!p->cfg.cache && !p->unshifted))
		return -ENOMEM;
	for (uint32_t b = 0; b < MAX_BUFFERS; b++) {
		p->content[b] = volume_create(g);
		if (!p->content[b])
			return -ENOMEM;
	}
	return 0;
}

/* p's fields for cfg, renderer and listener: nothing made yet. */
static void pipeline_init(struct pipeline *p, const struct pipeline_config *cfg, struct renderer *renderer,
			  const struct pipeline_listener *listener, void *data)
{
	p->cfg = *cfg;
	p->calibration = cfg->calibration;
	p->listener = listener;
	p->data = data;
	p->renderer = renderer;
	p->proj = devices_projector(cfg->devices);
	/* With no projector attached yet, arrived() says how many. */
	p->buffers = buffers_of(p->proj);
	p->shown = p->pending = p->uploaded = p->latest = p->resend = -1;
	p->next_seq = 1;
	p->building = &p->snaps[0];
	p->last = &p->snaps[1];
	p->done_fd = -1;
	pthread_mutex_init(&p->lock, NULL);
	pthread_cond_init(&p->cond, NULL);
}

/* p's volumes, cache, done eventfd and its source, and render thread.
 * 0 or -errno (what was made is freed by pipeline_destroy()). */
static int pipeline_start(struct pipeline *p)
{
	const struct geometry *g = &p->renderer->geom;
	int r = create_volumes(p, g);
	if (r < 0 || (p->cfg.cache && (r = create_cache(p, g)) < 0))
		return r;
	p->done_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
	if (p->done_fd < 0)
		return -errno;
	r = sd_event_add_io(p->cfg.event, &p->done_source, p->done_fd, EPOLLIN, render_done, p);
	if (r < 0)
		return r;
	return -pthread_create(&p->thread, NULL, render_thread, p);
}

struct pipeline *pipeline_create(const struct pipeline_config *cfg, struct renderer *renderer,
				 const struct pipeline_listener *listener, void *data)
{
	struct pipeline *p = calloc(1, sizeof(*p));
	if (!p) {
		render_destroy(renderer);
		return NULL;
	}
	pipeline_init(p, cfg, renderer, listener, data);
	int r = pipeline_start(p);
	if (r == 0)
		return p;
	sd_event_source_disable_unref(p->done_source);
	p->done_source = NULL;
	pipeline_destroy(p);
	errno = -r;
	return NULL;
}

void pipeline_destroy(struct pipeline *p)
{
	if (!p)
		return;
	if (p->done_source) {
		pthread_mutex_lock(&p->lock);
		p->quit = true;
		pthread_cond_signal(&p->cond);
		pthread_mutex_unlock(&p->lock);
		pthread_join(p->thread, NULL);
		sd_event_source_disable_unref(p->done_source);
	}
	sd_event_source_disable_unref(p->start_timer);
	if (p->done_fd >= 0)
		close(p->done_fd);
	snapshot_finish(&p->snaps[0]);
	snapshot_finish(&p->snaps[1]);
	for (uint32_t b = 0; b < MAX_BUFFERS; b++)
		volume_destroy(p->content[b]);
	volume_destroy(p->work);
	volume_destroy(p->unshifted);
	cache_destroy(p->cache);
	tile_set_finish(&p->differ);
	pool_destroy(p->pool);
	render_destroy(p->renderer);
	pthread_mutex_destroy(&p->lock);
	pthread_cond_destroy(&p->cond);
	free(p);
}
