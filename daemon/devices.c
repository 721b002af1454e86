#include "devices.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <systemd/sd-event.h>

#include "config.h"
#include "log.h"
#include "projector.h"
#include "sim_rotor.h"
#include "sync.h"
#include "sync_estimator.h"

struct devices {
	struct sd_event *event;
	const struct config *cfg;
	struct geometry geom;
	char name[64];
	const struct devices_listener *listener;
	void *data;
	struct sim_rotor *rotor;
	struct sync_source *sync;
	struct sync_estimator *est;
	struct projector *proj;
	sd_event_source *sync_source, *proj_source, *check_timer, *rate_timer;
	sd_event_source *half_timer; /* the half-turn start after a revolution start */
	int64_t half_ns;             /* when it fires */
	bool blanked;
	bool present;                     /* a projector is attached: gone() and arrived() say */
	int64_t max_err_ns;               /* the estimator's fit error the projector is lit at */
	uint64_t rate_bytes, upload_rate; /* bytes_sent at the last sample; bytes/s */
};

static void set_blank(struct devices *dev, bool blank)
{
	if (blank == dev->blanked)
		return;
	int r = dev->proj->impl->blank(dev->proj, blank);
	if (r < 0) {
		log_error("cannot %s the projector: %s", blank ? "blank" : "light", strerror(-r));
		if (!blank)
			return;
	}
	dev->blanked = blank;
	log_info("projector %s", blank ? "blanked" : "lit");
	dev->listener->state_changed(dev->data);
}

static void log_lock(const struct sync_state *st)
{
	static const char *const why[] = { "never locked", "no index pulse in time", "speed out of band",
					   "pulse train makes no sense" };
	if (st->locked)
		log_info("sync locked: %.1f rpm, jitter %.1f us", st->rpm, st->jitter_ns / 1e3);
	else
		log_warn("sync lost: %s", why[st->unlock_reason]);
}

/* Lit only while locked (a stopped screen under a projector is a hazard),
 * and once the estimator places revolution starts to a sixteenth of a
 * slice. time_ns: the edge or check that decided it. */
static void update_light(struct devices *dev, int64_t time_ns)
{
	const struct sync_state *st = sync_estimator_state(dev->est);
	bool lit = dev->present && st->locked && sync_estimator_settled(dev->est, dev->max_err_ns);
	if (lit != dev->blanked)
		return;
	set_blank(dev, !lit);
	if (!dev->blanked)
		dev->listener->lit(dev->data, time_ns);
}

static void arm_check(struct devices *dev)
{
	int64_t deadline = sync_estimator_deadline(dev->est);
	if (deadline == INT64_MAX) {
		sd_event_source_set_enabled(dev->check_timer, SD_EVENT_OFF);
		return;
	}
	sd_event_source_set_time(dev->check_timer, (uint64_t)(deadline > 0 ? deadline : 1) / 1000 + 1);
	sd_event_source_set_enabled(dev->check_timer, SD_EVENT_ONESHOT);
}

static int on_check(sd_event_source *s, uint64_t usec, void *data)
{
	struct devices *dev = data;
	int64_t now = now_ns();
	if (sync_estimator_check(dev->est, now)) {
		log_lock(sync_estimator_state(dev->est));
		dev->listener->state_changed(dev->data);
		update_light(dev, now);
	}
	arm_check(dev);
	return 0;
}

static void arm_half_turn(struct devices *dev, int64_t edge_ns);

static int on_sync(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	struct devices *dev = data;
	int64_t ts[32];
	int n = sync_read_edges(dev->sync, ts, 32);
	if (n == -ENODEV || n == -EBADF) {
		/* The line is gone (its chip removed): stop polling a hung-up
		 * fd; no edges come, so the check timer unlocks and blanks. */
		log_error("sync source gone: %s; the projector stays dark", strerror(-n));
		sd_event_source_set_enabled(s, SD_EVENT_OFF);
		return 0;
	}
	if (n < 0) {
		log_warn("sync source: %s", strerror(-n));
		return 0;
	}
	const struct sync_state *st = sync_estimator_state(dev->est);
	for (int i = 0; i < n; i++) {
		if (sync_estimator_feed(dev->est, ts[i])) {
			log_lock(st);
			dev->listener->state_changed(dev->data);
			update_light(dev, ts[i]);
		}
		/* An accepted edge starts a revolution; a glitch does not. */
		if (!dev->blanked && st->edge_ns == ts[i]) {
			dev->listener->revolution(dev->data, ts[i]);
			arm_half_turn(dev, ts[i]);
		}
	}
	if (n > 0) {
		/* The timing first: a device lit without it places slices
		 * at an unknown phase. */
		if (st->period_ns > 0)
			dev->proj->impl->set_timing(dev->proj, st->period_ns, st->phase_ns);
		update_light(dev, ts[n - 1]);
		if (!dev->blanked)
			dev->listener->synced(dev->data);
	}
	arm_check(dev);
	return 0;
}

static int on_half_turn(sd_event_source *s, uint64_t usec, void *data)
{
	struct devices *dev = data;
	if (!dev->blanked && sync_estimator_state(dev->est)->locked && dev->listener->half_turn)
		dev->listener->half_turn(dev->data, dev->half_ns);
	return 0;
}

bool devices_half_turns(const struct devices *dev)
{
	struct projector_info info;
	return dev->cfg->half_turn_swaps && dev->present && dev->proj->impl->get_info(dev->proj, &info) == 0 &&
	       info.half_turn_swaps;
}

/* With half-turn swaps, the half-turn start of the revolution that started
 * at edge_ns is a boundary too: the estimator's prediction of it (the
 * projector's own clock comes from the same timing). */
static void arm_half_turn(struct devices *dev, int64_t edge_ns)
{
	const struct sync_state *st = sync_estimator_state(dev->est);
	if (!dev->half_timer || st->period_ns <= 0 || !devices_half_turns(dev))
		return;
	int64_t half = st->period_ns / 2, first = st->phase_ns + half;
	int64_t k = edge_ns > first ? (edge_ns - first + st->period_ns - 1) / st->period_ns : 0;
	dev->half_ns = first + k * st->period_ns;
	sd_event_source_set_time(dev->half_timer, (uint64_t)dev->half_ns / 1000);
	sd_event_source_set_enabled(dev->half_timer, SD_EVENT_ONESHOT);
}

static void on_swapped(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	struct devices *dev = data;
	dev->listener->swapped(dev->data, buffer, time_ns, seq);
}

static void on_error(void *data, uint32_t buffer, int err)
{
	struct devices *dev = data;
	dev->listener->buffer_error(dev->data, buffer, err);
}

static void on_gone(void *data, int err)
{
	struct devices *dev = data;
	log_error("projector gone: %s", strerror(-err));
	dev->present = false;
	dev->blanked = true; /* a missing projector emits no light */
	dev->listener->gone(dev->data);
	dev->listener->state_changed(dev->data);
}

/* A (re)attached projector is dark and empty: give it the timing, light it
 * if the rotor is locked, and send it the newest volume. */
static void on_arrived(void *data)
{
	struct devices *dev = data;
	const struct sync_state *st = sync_estimator_state(dev->est);
	log_info("projector attached");
	dev->present = true;
	dev->blanked = true;
	if (st->period_ns > 0)
		dev->proj->impl->set_timing(dev->proj, st->period_ns, st->phase_ns);
	dev->listener->arrived(dev->data);
	dev->listener->state_changed(dev->data);
	update_light(dev, now_ns());
}

static const struct projector_listener proj_listener = {
	.swapped = on_swapped,
	.error = on_error,
	.gone = on_gone,
	.arrived = on_arrived,
};

static int on_projector(sd_event_source *s, int fd, uint32_t revents, void *data)
{
	struct devices *dev = data;
	int r = dev->proj->impl->dispatch(dev->proj);
	if (r < 0)
		log_warn("projector: %s", strerror(-r));
	return 0;
}

static int open_sim(struct devices *dev)
{
	const struct config *cfg = dev->cfg;
	struct sim_faults faults;
	int r = sim_faults_parse(cfg->sim_faults, &faults);
	if (r < 0)
		return r; /* config_set checked it already */
	dev->rotor = sim_rotor_create(dev->geom.rpm);
	if (!dev->rotor)
		return -errno;
	if ((r = sim_rotor_apply_faults(dev->rotor, &faults)) < 0)
		return r;
	if (*cfg->sim_faults)
		log_info("simulated faults: %s", cfg->sim_faults);
	dev->sync = sync_sim_create_faults(dev->rotor, &faults);
	if (!dev->sync)
		return -errno;
	struct proj_sim_config pc = {
		.geom = dev->geom,
		.buffers = cfg->projector_buffers,
		.link_bytes_per_sec = cfg->sim_link_bytes_per_sec,
		.faults = &faults,
	};
	dev->proj = proj_sim_create(dev->rotor, &pc, &proj_listener, dev);
	if (!dev->proj)
		return -errno;
	snprintf(dev->name, sizeof(dev->name), "simulated %s", cfg->profile);
	return 0;
}

/* Once a second: the upload rate over the last second. */
static int on_rate(sd_event_source *s, uint64_t usec, void *data)
{
	struct devices *dev = data;
	struct projector_stats ps;
	dev->proj->impl->get_stats(dev->proj, &ps);
	dev->upload_rate = ps.bytes_sent >= dev->rate_bytes ? ps.bytes_sent - dev->rate_bytes : 0;
	dev->rate_bytes = ps.bytes_sent;
	sd_event_source_set_time(s, usec + 1000000);
	return 0;
}

static void usb_config(const struct config *cfg, const struct geometry *geom, struct proj_usb_config *out)
{
	*out = (struct proj_usb_config){
		.vid = cfg->projector_vid,
		.pid = cfg->projector_pid,
		.geom = *geom,
	};
	snprintf(out->bus_path, sizeof(out->bus_path), "%s", cfg->projector_path);
}

/* The real devices. A missing projector is fine (it is set up when it is
 * plugged in); a missing sync line is not: the projector could never be
 * lit, and the config is wrong. */
static int open_hw(struct devices *dev)
{
	const struct config *cfg = dev->cfg;
	struct sync_gpiod_config sc = { .active_low = cfg->sync_active_low };
	snprintf(sc.chip, sizeof(sc.chip), "%s", cfg->sync_chip);
	snprintf(sc.line, sizeof(sc.line), "%s", cfg->sync_line);
	dev->sync = sync_gpiod_create(&sc);
	if (!dev->sync)
		return -errno;
	struct proj_usb_config pc;
	usb_config(cfg, &dev->geom, &pc);
	dev->proj = proj_usb_create(&pc, &proj_listener, dev);
	if (!dev->proj)
		return -errno;
	struct projector_stats ps;
	dev->proj->impl->get_stats(dev->proj, &ps);
	if (!ps.present)
		log_warn("no projector attached yet; waiting for one");
	snprintf(dev->name, sizeof(dev->name), "%.20s:%.20s + usb projector", cfg->sync_chip, cfg->sync_line);
	return 0;
}

int devices_blank(const struct config *cfg)
{
	if (strcmp(cfg->device, "hw") != 0) {
		log_info("device '%s': no projector outside the daemon, nothing to blank", cfg->device);
		return 0;
	}
	struct geometry geom;
	if (geometry_from_profile(cfg->profile, &geom) < 0) {
		log_error("unknown profile '%s'", cfg->profile);
		return -EINVAL;
	}
	struct proj_usb_config pc;
	usb_config(cfg, &geom, &pc);
	struct projector *p = proj_usb_create(&pc, NULL, NULL);
	if (!p) {
		log_error("cannot open USB: %s", strerror(errno));
		return -errno;
	}
	struct projector_stats ps;
	p->impl->get_stats(p, &ps);
	/* Set-up darkened it already; say it once more for the log. */
	int r = ps.present ? p->impl->blank(p, true) : 0;
	log_info(ps.present ? "projector blanked" : "no projector attached: nothing to blank");
	p->impl->destroy(p);
	return r;
}

static int add_sources(struct devices *dev)
{
	sd_event *e = dev->event;
	int r = sd_event_add_io(e, &dev->sync_source, sync_get_fd(dev->sync), EPOLLIN, on_sync, dev);
	if (r < 0)
		return r;
	/* Sync edges first: a swap report at the same revolution start must
	 * not be seen before the edge that explains it. */
	sd_event_source_set_priority(dev->sync_source, SD_EVENT_PRIORITY_IMPORTANT);
	int pfd = dev->proj->impl->get_fd(dev->proj);
	if (pfd >= 0 && (r = sd_event_add_io(e, &dev->proj_source, pfd, EPOLLIN, on_projector, dev)) < 0)
		return r;
	r = sd_event_add_time(e, &dev->check_timer, CLOCK_MONOTONIC, 0, 1000, on_check, dev);
	if (r < 0 || (r = sd_event_source_set_enabled(dev->check_timer, SD_EVENT_OFF)) < 0)
		return r;
	r = sd_event_add_time(e, &dev->half_timer, CLOCK_MONOTONIC, 0, 100, on_half_turn, dev);
	if (r < 0 || (r = sd_event_source_set_enabled(dev->half_timer, SD_EVENT_OFF)) < 0)
		return r;
	sd_event_source_set_priority(dev->half_timer, SD_EVENT_PRIORITY_IMPORTANT);
	r = sd_event_add_time_relative(e, &dev->rate_timer, CLOCK_MONOTONIC, 1000000, 10000, on_rate, dev);
	if (r < 0)
		return r;
	return sd_event_source_set_enabled(dev->rate_timer, SD_EVENT_ON);
}

struct devices *devices_create(struct sd_event *event, const struct config *cfg, const struct geometry *geom,
			       const struct devices_listener *listener, void *data)
{
	struct devices *dev = calloc(1, sizeof(*dev));
	if (!dev)
		return NULL;
	dev->event = event;
	dev->cfg = cfg;
	dev->geom = *geom;
	dev->listener = listener;
	dev->data = data;
	dev->blanked = true; /* the projector starts dark */
	int64_t period = llround(60e9 / geom->rpm);
	dev->max_err_ns = sync_light_max_err(period, geom->images_per_rev);
	struct sync_estimator_config ec;
	sync_estimator_config_default(&ec, geom->rpm);
	int r = -ENOMEM;
	dev->est = sync_estimator_create(&ec);
	if (!dev->est)
		goto err;
	r = strcmp(cfg->device, "hw") ? open_sim(dev) : open_hw(dev);
	if (r < 0)
		goto err;
	r = add_sources(dev);
	if (r < 0)
		goto err;
	struct projector_stats ps;
	dev->proj->impl->get_stats(dev->proj, &ps);
	dev->present = ps.present;
	return dev;
err:
	devices_destroy(dev);
	errno = -r;
	return NULL;
}

/* The simulated projector's safety record, measured against the true
 * rotor: for the log, and for the tests that read it there. */
static void log_sim_safety(struct devices *dev)
{
	struct proj_sim_stats ss;
	proj_sim_get_stats(dev->proj, &ss);
	double period = 60e9 / dev->geom.rpm;
	log_info("simulated projector: %llu stalls, dark at most %.2f periods after the last true index "
		 "pulse, lit %.1f ms while stopped and %.1f ms without timing, %llu watchdog blanks; slice "
		 "angle error p50 %.3f p99 %.3f max %.3f",
		 (unsigned long long)ss.stalls, (double)ss.max_dark_delay_ns / period, ss.lit_stopped_ns / 1e6,
		 ss.lit_untimed_ns / 1e6, (unsigned long long)ss.watchdog_blanks, ss.angle_err_p50, ss.angle_err_p99,
		 ss.angle_err_max);
}

void devices_destroy(struct devices *dev)
{
	if (!dev)
		return;
	if (dev->proj && dev->rotor)
		log_sim_safety(dev);
	if (dev->proj) {
		dev->proj->impl->blank(dev->proj, true);
		dev->proj->impl->destroy(dev->proj);
	}
	sd_event_source_disable_unref(dev->sync_source);
	sd_event_source_disable_unref(dev->proj_source);
	sd_event_source_disable_unref(dev->check_timer);
	sd_event_source_disable_unref(dev->rate_timer);
	sd_event_source_disable_unref(dev->half_timer);
	sync_destroy(dev->sync);
	sim_rotor_destroy(dev->rotor);
	sync_estimator_destroy(dev->est);
	free(dev);
}

bool devices_lit(const struct devices *dev)
{
	return !dev->blanked;
}

int64_t devices_next_boundary(const struct devices *dev, int64_t now, int64_t *period_ns)
{
	int64_t next = devices_next_revolution(dev, now, period_ns);
	if (!next || !devices_half_turns(dev))
		return next;
	int64_t half = *period_ns / 2;
	*period_ns = half;
	return next - half > now ? next - half : next;
}

int64_t devices_next_revolution(const struct devices *dev, int64_t now, int64_t *period_ns)
{
	const struct sync_state *st = sync_estimator_state(dev->est);
	if (dev->blanked || !st->locked || st->period_ns <= 0 || st->phase_ns <= 0)
		return 0;
	*period_ns = st->period_ns;
	if (now < st->phase_ns)
		return st->phase_ns;
	return st->phase_ns + ((now - st->phase_ns) / st->period_ns + 1) * st->period_ns;
}

const char *devices_name(const struct devices *dev)
{
	return dev->name;
}

struct projector *devices_projector(struct devices *dev)
{
	return dev->proj;
}

const struct volume *devices_shown(struct devices *dev)
{
	return dev->proj->impl->shown ? dev->proj->impl->shown(dev->proj) : NULL;
}

void devices_get_status(struct devices *dev, struct devices_status *out)
{
	const struct sync_state *st = sync_estimator_state(dev->est);
	struct projector_stats ps;
	dev->proj->impl->get_stats(dev->proj, &ps);
	*out = (struct devices_status){
		.rpm = st->locked ? (float)st->rpm : 0.0f,
		.locked = st->locked,
		.blanked = dev->blanked,
		.projector_present = ps.present,
		.underruns = ps.underruns,
		.jitter_us = (float)(st->jitter_ns / 1e3),
		.missed_pulses = st->missed + st->glitches,
		.index_error_us = (float)(st->phase_err_ns / 1e3),
		.upload_rate = dev->upload_rate,
		.angle_error_p99 = (float)ps.angle_err_p99,
		.angle_error_max = (float)ps.angle_err_max,
	};
}
