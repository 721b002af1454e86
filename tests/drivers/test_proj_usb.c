/* The USB projector (proj_usb.c) through libusb's real code paths against
 * the device model, with umockdev standing in for the kernel (usb_emul).
 * Exits 77 (skipped) when not run under umockdev's preload library. Under
 * umockdev the device node always polls ready, so the loops below poll
 * with a short timeout and dispatch each time round. As root, it also
 * runs itself again to re-plug the device after the privilege drop
 * (test_hotplug_after_drop). */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "log.h"
#include "privilege.h"
#include "proj_usb_priv.h"
#include "projector.h"
#include "projwire.h"
#include "sim_rotor.h"
#include "usb_emul.h"
#include "volume_util.h"

static const struct geometry geom = {
	.width = 96,
	.height = 64,
	.images_per_rev = 16,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
};

/* Large enough that one volume takes several 256 KiB bulk transfers. */
static const struct geometry big = {
	.width = 512,
	.height = 512,
	.images_per_rev = 64,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
};

struct events {
	int swaps, errors, gone, arrived;
	uint32_t buffer, err_buffer;
	int64_t time_ns;
	uint64_t seq;
	int err, gone_err;
	bool half; /* swapped_at()'s half_turn */
};

static void on_swapped(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	struct events *ev = data;
	ev->swaps++;
	ev->buffer = buffer;
	ev->time_ns = time_ns;
	ev->seq = seq;
}

static void on_error(void *data, uint32_t buffer, int err)
{
	struct events *ev = data;
	ev->errors++;
	ev->err_buffer = buffer;
	ev->err = err;
}

static void on_gone(void *data, int err)
{
	struct events *ev = data;
	ev->gone++;
	ev->gone_err = err;
}

static void on_arrived(void *data)
{
	((struct events *)data)->arrived++;
}

static const struct projector_listener listener = {
	.swapped = on_swapped,
	.error = on_error,
	.gone = on_gone,
	.arrived = on_arrived,
};

static void on_swapped_at(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq, bool half_turn)
{
	on_swapped(data, buffer, time_ns, seq);
	((struct events *)data)->half = half_turn;
}

/* The same, told which boundary each swap took. */
static const struct projector_listener half_listener = {
	.swapped_at = on_swapped_at,
	.error = on_error,
	.gone = on_gone,
	.arrived = on_arrived,
};

struct rig {
	struct usb_emul *emul;
	struct projector *p;
	struct events ev;
	struct proj_usb_config cfg;
	int fds; /* before the projector: umockdev's own come and go apart */
};

static void rig_init_with(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor,
			  const struct projector_listener *l)
{
	*r = (struct rig){ .cfg = { .geom = *g } };
	r->emul = usb_emul_create();
	CHECK(r->emul);
	if (dev_geom)
		CHECK_EQ(usb_emul_plug(r->emul, dev_geom, 3, minor), 0);
	r->fds = count_fds();
	r->p = proj_usb_create(&r->cfg, l, &r->ev);
	CHECK(r->p);
}

static void rig_init(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor)
{
	rig_init_with(r, g, dev_geom, minor, &listener);
}

static void rig_finish(struct rig *r)
{
	r->p->impl->destroy(r->p);
	/* umockdev's thread closes its end of the node after the driver closed
	 * its own; the count is the driver's only once that is done. */
	CHECK_EQ(usb_emul_wait_closed(r->emul, 2000), 0);
	CHECK_EQ(count_fds(), r->fds); /* nothing of the driver's left open */
	usb_emul_destroy(r->emul);
}

/* One turn of the daemon's loop. */
static void turn(struct projector *p)
{
	struct pollfd pfd = { .fd = p->impl->get_fd(p), .events = POLLIN };
	CHECK(poll(&pfd, 1, 5) >= 0);
	CHECK_EQ(p->impl->dispatch(p), 0);
}

/* Dispatches until *count moves past before (at most ms milliseconds);
 * returns the milliseconds it took. */
static int64_t wait_for(struct projector *p, const int *count, int before, int ms)
{
	int64_t t0 = now_ns(), deadline = t0 + (int64_t)ms * 1000000;
	while (*count == before) {
		CHECK_MSG(now_ns() < deadline, "no event in %d ms", ms);
		turn(p);
	}
	return (now_ns() - t0) / 1000000;
}

static void run_for(struct projector *p, int ms)
{
	int64_t deadline = now_ns() + (int64_t)ms * 1000000;
	while (now_ns() < deadline)
		turn(p);
}

static void upload_and_show(struct rig *r, uint32_t buffer, const struct volume *vol)
{
	struct projector *p = r->p;
	int before = r->ev.swaps;
	CHECK(p->impl->upload(p, buffer, vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, buffer), 0);
	wait_for(p, &r->ev.swaps, before, 2000);
	CHECK_EQ(r->ev.buffer, buffer);
	CHECK_EQ(r->ev.seq, vol->seq);
	CHECK_EQ(p->impl->blank(p, false), 0);
	CHECK(usb_emul_shows(r->emul, vol));
}

static void test_open(void)
{
	struct rig r;
	rig_init(&r, &geom, &geom, 0);
	struct projector *p = r.p;
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK_EQ(info.geom.width, geom.width);
	CHECK_EQ(info.geom.height, geom.height);
	CHECK_EQ(info.geom.images_per_rev, geom.images_per_rev);
	CHECK(info.geom.mirrored);
	CHECK_EQ(info.buffers, 3);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK(st.present);
	CHECK_EQ(st.arrivals, 1);
	CHECK(st.angle_err_max < 0);
	CHECK(!usb_emul_lit(r.emul)); /* set up dark */
	CHECK(!p->impl->shown(p));
	struct usb_emul_stats es;
	usb_emul_get_stats(r.emul, &es);
	CHECK(es.controls >= 3); /* RESET_STREAM, GET_INFO, SET_BLANK */
	CHECK_EQ(es.unknown_ioctls, 0);
	CHECK_EQ(p->impl->set_timing(p, 33333333, now_ns()), 0);
	CHECK_EQ(p->impl->set_timing(p, 0, 0), -EINVAL);
	CHECK_EQ(r.ev.arrived, 0); /* present at creation: not reported */
	rig_finish(&r);
}

static void test_refuse_geometry(void)
{
	struct rig r;
	struct geometry other = geom;
	other.width = 128;
	rig_init(&r, &geom, &other, 0);
	struct projector *p = r.p;
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), -ENODEV);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK(!st.present);
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	CHECK_EQ(p->impl->upload(p, 0, vol, NULL, NULL), -ENODEV);
	CHECK_EQ(p->impl->blank(p, true), -ENODEV);
	run_for(p, 700); /* a rescan passes by: still refused, never arrived */
	CHECK_EQ(r.ev.arrived, 0);
	volume_destroy(vol);
	rig_finish(&r);
}

static void test_upload_swap(void)
{
	struct rig r;
	rig_init(&r, &geom, &geom, 0);
	struct projector *p = r.p;
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 3, 11);
	CHECK_EQ(p->impl->swap(p, 2), -ENODATA); /* never written: a stall, told why */
	upload_and_show(&r, 0, vol);
	CHECK_EQ(p->impl->upload(p, 0, vol, NULL, NULL), -EBUSY); /* shown */
	random_volume(vol, 5, 12);
	CHECK(p->impl->upload(p, 1, vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, 1), 0);
	CHECK_EQ(p->impl->upload(p, 1, vol, NULL, NULL), -EBUSY); /* awaiting a swap */
	CHECK_EQ(p->impl->swap(p, 2), -EBUSY);                    /* one swap at a time */
	CHECK_EQ(p->impl->swap(p, 7), -EINVAL);
	wait_for(p, &r.ev.swaps, 1, 2000);
	CHECK_EQ(r.ev.buffer, 1);
	CHECK_EQ(r.ev.seq, 12);
	CHECK(usb_emul_shows(r.emul, vol));
	CHECK(p->impl->upload(p, 0, vol, NULL, NULL) > 0); /* free again */
	run_for(p, 1100);                                  /* a keepalive GET_STATUS refreshes the stats */
	struct projector_stats st;
	struct usb_emul_stats es;
	p->impl->get_stats(p, &st);
	usb_emul_get_stats(r.emul, &es);
	CHECK_EQ(st.swaps, 2);
	CHECK(st.revolutions >= 1);
	CHECK_EQ(st.bytes_sent, es.bulk_bytes);
	CHECK(st.bytes_sent > 2 * projwire_volume_size(vol) / 2);
	CHECK_EQ(r.ev.errors, 0);
	volume_destroy(vol);
	rig_finish(&r);
}

static void test_in_flight(struct volume *large)
{
	struct rig r;
	rig_init(&r, &big, &big, 0);
	struct projector *p = r.p;
	size_t size = projwire_volume_size(large);
	CHECK(size > 4 * 256 * 1024); /* more than the transfers in flight hold */
	upload_and_show(&r, 0, large);
	struct proj_usb_debug dbg;
	struct usb_emul_stats es;
	proj_usb_get_debug(p, &dbg);
	usb_emul_get_stats(r.emul, &es);
	CHECK(dbg.usb.max_out_in_flight >= 2);
	CHECK(es.max_out_in_flight >= 2); /* the device saw them at once too */
	CHECK_EQ(es.bulk_bytes, size);
	rig_finish(&r);
}

/* Bytes one upload puts on the wire. */
static uint64_t upload_bytes(struct rig *r, uint32_t buffer, const struct volume *vol, const struct volume *base)
{
	struct projector_stats st0, st;
	r->p->impl->get_stats(r->p, &st0);
	CHECK(r->p->impl->upload(r->p, buffer, vol, base, NULL) > 0);
	run_for(r->p, 50);
	r->p->impl->get_stats(r->p, &st);
	return st.bytes_sent - st0.bytes_sent;
}

static void check_delta(uint8_t minor)
{
	struct rig r;
	rig_init(&r, &geom, &geom, minor);
	struct volume *a = volume_create(&geom), *b = volume_create(&geom), *a2 = volume_create(&geom);
	CHECK(a && b && a2);
	random_volume(a, 4, 21);
	random_volume(b, 4, 22);
	upload_and_show(&r, 0, a);
	upload_and_show(&r, 1, b); /* buffer 0 holds a, free again */
	CHECK_EQ(volume_copy(a2, a), 0);
	a2->seq = 23;
	uint64_t sent = upload_bytes(&r, 0, a2, a);
	/* a2 is a's content: to a 1.1 device, a delta of no tiles at all. */
	if (minor >= 1)
		CHECK_EQ(sent, PROJWIRE_DELTA_BEGIN_SIZE + PROJWIRE_END_SIZE);
	else
		CHECK_EQ(sent, projwire_volume_size(a2)); /* a 1.0 device gets it whole */
	CHECK_EQ(r.p->impl->swap(r.p, 0), 0);
	wait_for(r.p, &r.ev.swaps, 2, 2000);
	CHECK_EQ(r.ev.seq, 23);
	CHECK(usb_emul_shows(r.emul, a2));
	volume_destroy(a);
	volume_destroy(b);
	volume_destroy(a2);
	rig_finish(&r);
}

static void test_delta(void)
{
	check_delta(1);
	check_delta(0);
}

/* ---- Half-turn swaps (1.2) ---- */

/* Turns the loop until the emulated rotor is between from and to
 * (fractions of a revolution) past a revolution start. */
static void wait_phase(struct projector *p, const struct sim_rotor *rotor, double from, double to)
{
	int64_t period = sim_rotor_period_ns(rotor), deadline = now_ns() + 2000000000LL;
	for (;;) {
		int64_t t = now_ns();
		CHECK(t < deadline);
		int64_t start = sim_rotor_index_time(rotor, sim_rotor_revolution(rotor, t));
		double f = (double)(t - start) / (double)period;
		if (f >= from && f < to)
			return;
		turn(p);
	}
}

/* The boundary a swap asked at t takes on the emulated device, its data
 * being through: the next half-turn start, or revolution start. */
static int64_t boundary_after(const struct sim_rotor *rotor, int64_t t, bool half)
{
	return half ? sim_rotor_next_half_turn(rotor, t, NULL) : sim_rotor_next_index(rotor, t);
}

/* swap_half() to a device of version 1.minor, mirrored or not: SWAP_HALF
 * and swaps at half-turn starts from a 1.2 mirrored device; to any other
 * SWAP and revolution starts only, SWAP_HALF never sent. Requests are made
 * just past a revolution start (where the two differ: the middle comes
 * first) and just past a middle. */
static void check_half_turns(uint8_t minor, bool mirrored)
{
	struct geometry g = geom;
	g.mirrored = mirrored;
	struct rig r;
	rig_init_with(&r, &g, &g, minor, &half_listener);
	struct projector *p = r.p;
	const struct sim_rotor *rotor = usb_emul_rotor(r.emul);
	bool want = minor >= 2 && mirrored;
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK_EQ(info.half_turn_swaps, want);
	CHECK_EQ(p->impl->blank(p, false), 0);
	struct volume *vol[3];
	for (int i = 0; i < 3; i++) {
		vol[i] = volume_create(&g);
		CHECK(vol[i]);
		random_volume(vol[i], 2, 300 + (uint64_t)i);
	}
	int pinned = 0, middles = 0, rounds = 8;
	struct usb_emul_stats es;
	for (int i = 0; i < rounds; i++) {
		uint32_t b = (uint32_t)i % 3;
		struct volume *v = vol[b];
		v->seq = 300 + (uint64_t)i;
		wait_phase(p, rotor, i % 2 ? 0.55 : 0.05, i % 2 ? 0.65 : 0.15);
		usb_emul_get_stats(r.emul, &es);
		uint64_t requests = es.swaps + es.swap_halves;
		int swaps = r.ev.swaps;
		int64_t asked = now_ns();
		CHECK(p->impl->upload(p, b, v, NULL, NULL) > 0);
		CHECK_EQ(p->impl->swap_half(p, b), 0);
		/* The request goes out once VOLUME_BEGIN is through, which for
		 * a volume of one bulk transfer is all of it: no underrun. */
		for (int64_t deadline = asked + 1000000000LL; es.swaps + es.swap_halves == requests;) {
			CHECK(now_ns() < deadline);
			turn(p);
			usb_emul_get_stats(r.emul, &es);
		}
		int64_t sent = now_ns();
		wait_for(p, &r.ev.swaps, swaps, 2000);
		int64_t t = r.ev.time_ns, lo = boundary_after(rotor, asked, want),
			hi = boundary_after(rotor, sent, want);
		CHECK_EQ(r.ev.buffer, b);
		CHECK_EQ(r.ev.seq, v->seq);
		CHECK_MSG(t >= lo && t <= hi, "swap at %lld, first boundary after the request %lld, after it went %lld",
			  (long long)t, (long long)lo, (long long)hi);
		bool second;
		CHECK_EQ(sim_rotor_next_half_turn(rotor, t, &second), t);
		CHECK_EQ(r.ev.half, second);
		CHECK(want || !second);
		pinned += lo == hi;
		middles += second;
		CHECK(usb_emul_shows(r.emul, v));
	}
	usb_emul_get_stats(r.emul, &es);
	CHECK_EQ(es.swap_halves, want ? (uint64_t)rounds : 0); /* a 1.1 device never gets it */
	CHECK_EQ(es.swaps, want ? 0 : (uint64_t)rounds);
	CHECK_EQ(es.stalls, 0);
	CHECK_EQ(r.ev.errors, 0);
	run_for(p, 600); /* a keepalive GET_STATUS: the device's counters */
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK_EQ(st.swaps, (uint64_t)rounds);
	CHECK_EQ(st.underruns, 0);
	printf("half-turn swaps, device 1.%u%s: %d swaps, %d at the middle of a revolution, %d pinned to the "
	       "first boundary after the request\n",
	       (unsigned)minor, mirrored ? " mirrored" : " not mirrored", rounds, middles, pinned);
	for (int i = 0; i < 3; i++)
		volume_destroy(vol[i]);
	rig_finish(&r);
}

/* A device that says 1.2 and mirrored but stalls SWAP_HALF as unknown:
 * the driver swaps at the revolution start instead, and from then on. */
static void test_half_turn_refused(void)
{
	struct rig r;
	rig_init_with(&r, &geom, &geom, 2, &half_listener);
	struct projector *p = r.p;
	const struct sim_rotor *rotor = usb_emul_rotor(r.emul);
	usb_emul_set_minor(r.emul, 1);
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK(info.half_turn_swaps);
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 2, 401);
	CHECK(p->impl->upload(p, 0, vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 0), 0);
	wait_for(p, &r.ev.swaps, 0, 2000);
	CHECK_EQ(r.ev.buffer, 0);
	CHECK(!r.ev.half);
	CHECK_EQ(sim_rotor_next_index(rotor, r.ev.time_ns), r.ev.time_ns);
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK(!info.half_turn_swaps);
	random_volume(vol, 2, 402);
	CHECK(p->impl->upload(p, 1, vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 1), 0);
	wait_for(p, &r.ev.swaps, 1, 2000);
	CHECK_EQ(r.ev.seq, 402);
	CHECK(!r.ev.half);
	struct usb_emul_stats es;
	usb_emul_get_stats(r.emul, &es);
	CHECK_EQ(es.swap_halves, 1); /* asked once, refused, never again */
	CHECK_EQ(es.stalls, 1);
	CHECK_EQ(es.swaps, 2);
	CHECK_EQ(r.ev.errors, 0);
	volume_destroy(vol);
	rig_finish(&r);
}

static void test_half_turns(void)
{
	check_half_turns(2, true);
	check_half_turns(1, true);
	check_half_turns(2, false);
	test_half_turn_refused();
}

static void test_error_events(void)
{
	struct rig r;
	rig_init(&r, &geom, &geom, 0);
	struct projector *p = r.p;
	uint8_t buf[PROJWIRE_EVENT_MAX];
	struct projwire_event ev = { .type = PROJWIRE_EV_ERROR, .buffer = 1, .error = PROJWIRE_ERR_CRC, .seq = 5 };
	usb_emul_inject_event(r.emul, buf, projwire_event_encode(&ev, buf));
	wait_for(p, &r.ev.errors, 0, 1000);
	CHECK_EQ(r.ev.err_buffer, 1);
	CHECK_EQ(r.ev.err, -EILSEQ);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK_EQ(st.device_errors, 1);

	/* Nonsense on the events endpoint: a device fault. The device is
	 * dropped (gone) and, still plugged, set up again by the rescan. */
	static const uint8_t junk[8] = { 'X', 'Y', 0x81, 0, 0, 0, 0, 0 };
	usb_emul_inject_event(r.emul, junk, sizeof(junk));
	wait_for(p, &r.ev.gone, 0, 1000);
	CHECK_EQ(r.ev.gone_err, -ENODEV);
	wait_for(p, &r.ev.arrived, 0, 2000);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(p, &dbg);
	CHECK_EQ(dbg.usb.rescan_opens, 1); /* no uevent: the periodic rescan found it */
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 2, 31);
	upload_and_show(&r, 2, vol);
	volume_destroy(vol);
	rig_finish(&r);
}

static void test_keepalive(void)
{
	struct rig r;
	rig_init(&r, &geom, &geom, 0);
	struct projector *p = r.p;
	CHECK_EQ(p->impl->blank(p, false), 0);
	CHECK(usb_emul_lit(r.emul));
	run_for(p, 3000);
	struct usb_emul_stats es;
	usb_emul_get_stats(r.emul, &es);
	CHECK(usb_emul_lit(r.emul));
	CHECK_EQ(es.watchdog_darkened, 0);
	CHECK_MSG(es.max_ctrl_gap_ns <= 1000000000LL, "EP0 silent for %lld ms",
		  (long long)es.max_ctrl_gap_ns / 1000000);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK(st.revolutions >= 60); /* 1800 rpm for 3 s, from GET_STATUS */
	rig_finish(&r);
	CHECK_EQ(r.ev.gone, 0);
}

/* Pulls the device mid-upload: gone() once, after every transfer's
 * callback; then every call says -ENODEV. */
static void unplug_mid_upload(struct rig *r, const struct volume *vol)
{
	struct projector *p = r->p;
	int gone = r->ev.gone;
	CHECK(p->impl->upload(p, 0, vol, NULL, NULL) > 0);
	usb_emul_unplug(r->emul);
	wait_for(p, &r->ev.gone, gone, 2000);
	run_for(p, 20);
	CHECK_EQ(r->ev.gone, gone + 1);
	CHECK_EQ(r->ev.gone_err, -ENODEV);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(p, &dbg);
	CHECK_EQ(dbg.usb.live_transfers, 0);
	CHECK_EQ(dbg.usb.allocated_transfers, 0);
	struct usb_emul_stats es;
	usb_emul_get_stats(r->emul, &es);
	CHECK_EQ(es.urbs_outstanding, 0); /* every URB reaped */
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), -ENODEV);
	CHECK_EQ(p->impl->upload(p, 1, vol, NULL, NULL), -ENODEV);
	CHECK_EQ(p->impl->swap(p, 1), -ENODEV);
	CHECK_EQ(p->impl->blank(p, true), -ENODEV);
	CHECK_EQ(p->impl->set_timing(p, 33333333, now_ns()), -ENODEV);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK(!st.present);
}

static int64_t replug(struct rig *r, const struct geometry *g)
{
	int arrived = r->ev.arrived;
	CHECK_EQ(usb_emul_plug(r->emul, g, 3, 0), 0);
	int64_t ms = wait_for(r->p, &r->ev.arrived, arrived, 2000);
	CHECK_EQ(r->ev.arrived, arrived + 1);
	struct projector_stats st;
	r->p->impl->get_stats(r->p, &st);
	CHECK(st.present);
	CHECK(!usb_emul_lit(r->emul));
	return ms;
}

static void test_hotplug(struct volume *large)
{
	struct rig r;
	rig_init(&r, &big, &big, 0);
	struct projector *p = r.p;
	unplug_mid_upload(&r, large);
	int64_t ms = replug(&r, &big);
	large->seq = 41;
	upload_and_show(&r, 1, large);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(p, &dbg);
	printf("hot-plug: libusb events %s; re-plug found in %lld ms; arrivals seen %llu, removals %llu, "
	       "found by rescan %llu\n",
	       dbg.usb.hotplug ? "on" : "off", (long long)ms, (unsigned long long)dbg.usb.hotplug_arrivals,
	       (unsigned long long)dbg.usb.hotplug_removals, (unsigned long long)dbg.usb.rescan_opens);
	struct projector_stats st;
	p->impl->get_stats(p, &st);
	CHECK_EQ(st.arrivals, 2);
	rig_finish(&r);
}

/* A duplicate arrival for the device already held changes nothing: no
 * arrived(), no gone(), the device keeps working. */
static void test_duplicate_arrival(void)
{
	struct rig r;
	rig_init(&r, &geom, &geom, 0);
	struct proj_usb_debug before, after;
	proj_usb_get_debug(r.p, &before);
	for (int i = 0; i < 3; i++) {
		usb_emul_announce_again(r.emul);
		run_for(r.p, 100);
	}
	proj_usb_get_debug(r.p, &after);
	printf("duplicate arrivals: %llu hot-plug events reached the driver\n",
	       (unsigned long long)(after.usb.hotplug_arrivals - before.usb.hotplug_arrivals));
	CHECK_EQ(r.ev.arrived, 0);
	CHECK_EQ(r.ev.gone, 0);
	struct projector_stats st;
	r.p->impl->get_stats(r.p, &st);
	CHECK(st.present && st.arrivals == 1);
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 3, 61);
	upload_and_show(&r, 0, vol);
	volume_destroy(vol);
	rig_finish(&r);
}

static void test_cycles(struct volume *large)
{
	struct rig r;
	rig_init(&r, &big, &big, 0);
	int fds = count_fds();
	for (int i = 0; i < 20; i++) {
		unplug_mid_upload(&r, large);
		replug(&r, &big);
	}
	CHECK_EQ(count_fds(), fds);
	CHECK_EQ(r.ev.gone, 20);
	CHECK_EQ(r.ev.arrived, 20);
	large->seq = 51;
	upload_and_show(&r, 2, large);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(r.p, &dbg);
	CHECK_EQ(dbg.gone, 20);
	rig_finish(&r);
}

/* ---- Hot-plug after the privilege drop ----
 *
 * spindled opens its devices as root and then becomes its user
 * (privilege_drop(): no capabilities, no_new_privs); the projector may be
 * unplugged and plugged again after that, and the udev rule gives its node
 * to a group the daemon's user is in (root:G 0660). The test plays that in
 * a process of its own, this program run again with AFTER_DROP_ARG: it
 * cannot come back to root, and a mere fork of this process could not
 * safely use GLib (umockdev's), whose threads a fork leaves behind.
 *
 * The parent stays root and plays udev: each time the device is plugged,
 * the child (playing the kernel as well as running the driver) asks it
 * over a socket to apply the rule to the node; the child waits for the
 * answer before it returns from the plug, so the node has its owner, group
 * and mode before the driver can try it, as udev applies a rule before
 * libudev's listeners hear of the device. The child's user is nobody, its
 * group nobody's own (the group a real rule names is a supplementary one,
 * which privilege_drop() sets through initgroups() as it does the primary:
 * unit-privilege checks them). */
#define AFTER_DROP_ARG "--after-drop"

struct rule_request {
	char path[PATH_MAX];
	uint32_t gid, mode; /* the owner is root */
};

/* The child's end: usb_emul's node rule. */
struct udev_link {
	int fd;
	gid_t gid;
	mode_t mode;
};

static int ask_udev(void *data, const char *path)
{
	const struct udev_link *u = data;
	struct rule_request q = { .gid = u->gid, .mode = u->mode };
	snprintf(q.path, sizeof(q.path), "%s", path);
	if (send(u->fd, &q, sizeof(q), MSG_NOSIGNAL) != (ssize_t)sizeof(q))
		return -EIO;
	int r;
	if (recv(u->fd, &r, sizeof(r), 0) != (ssize_t)sizeof(r))
		return -EIO;
	return r;
}

/* The parent's end, until the child closes its own (it is done). */
static int serve_udev(int fd)
{
	struct rule_request q;
	ssize_t n;
	int served = 0;
	while ((n = recv(fd, &q, sizeof(q), 0)) == (ssize_t)sizeof(q)) {
		q.path[sizeof(q.path) - 1] = '\0';
		int r = 0;
		if (lchown(q.path, 0, q.gid) < 0 || chmod(q.path, q.mode) < 0)
			r = -errno;
		CHECK(send(fd, &r, sizeof(r), MSG_NOSIGNAL) == (ssize_t)sizeof(r));
		served++;
	}
	CHECK_EQ(n, 0);
	return served;
}

/* The environment for the child: this one, with no testbed and without
 * LeakSanitizer, which cannot stop the world of a process that gave up
 * root (no longer dumpable, it may not ptrace its own threads); so does
 * tests/conformance/test_service.py for spindled. */
static char **child_env(char **opt_out)
{
	extern char **environ;
	size_t n = 0;
	while (environ[n])
		n++;
	char **env = calloc(n + 2, sizeof(*env));
	CHECK(env);
	const char *asan = getenv("ASAN_OPTIONS");
	char *opt = malloc(strlen("ASAN_OPTIONS=") + (asan ? strlen(asan) : 0) + strlen(":detect_leaks=0") + 1);
	CHECK(opt);
	sprintf(opt, "ASAN_OPTIONS=%s%sdetect_leaks=0", asan ? asan : "", asan && *asan ? ":" : "");
	size_t k = 0;
	for (size_t i = 0; i < n; i++) {
		if (strncmp(environ[i], "ASAN_OPTIONS=", 13) && strncmp(environ[i], "UMOCKDEV_DIR=", 13))
			env[k++] = environ[i];
	}
	env[k] = opt;
	*opt_out = opt;
	return env;
}

/* A number of /proc/self/status, the value of "Key:" in base. */
static unsigned long long status_number(const char *key, int base)
{
	char line[512];
	size_t n = strlen(key);
	FILE *f = fopen("/proc/self/status", "re");
	CHECK(f);
	unsigned long long v = 0;
	bool found = false;
	while (!found && fgets(line, sizeof(line), f)) {
		if (!strncmp(line, key, n) && line[n] == ':') {
			v = strtoull(line + n + 1, NULL, base);
			found = true;
		}
	}
	fclose(f);
	CHECK_MSG(found, "no %s in /proc/self/status", key);
	return v;
}

/* The node as the rule left it: root's, group gid, mode; and whether this
 * process may open it. */
static bool check_node(struct usb_emul *e, gid_t gid, mode_t mode)
{
	struct stat st;
	const char *node = usb_emul_node_path(e);
	CHECK_MSG(stat(node, &st) == 0, "%s: %s", node, strerror(errno));
	CHECK_EQ(st.st_uid, 0);
	CHECK_EQ(st.st_gid, gid);
	CHECK_EQ(st.st_mode & 07777, mode);
	return access(node, R_OK | W_OK) == 0;
}

/* The child, as root at first: the driver open and showing, then the drop,
 * then the device out and in again, twice. Its CHECKs exit it with 1. */
static int after_drop(int udev_fd)
{
	setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the driver's log */
	const struct passwd *pw = getpwnam("nobody");
	CHECK(pw);
	const uid_t uid = pw->pw_uid;
	const gid_t gid = pw->pw_gid;
	CHECK(uid != 0 && gid != 0);
	struct volume *large = volume_create(&big);
	CHECK(large);
	random_volume(large, 8, 1);
	struct udev_link udev = { .fd = udev_fd, .gid = gid, .mode = 0660 };

	/* As root, as spindled at its start: the projector found (its node
	 * given the group by udev at boot) and showing. */
	struct rig r;
	rig_init(&r, &big, &big, 0);
	usb_emul_set_node_rule(r.emul, ask_udev, &udev);
	CHECK_EQ(usb_emul_apply_node_rule(r.emul), 0);
	large->seq = 70;
	upload_and_show(&r, 2, large); /* unplug_mid_upload() uploads to 0 */
	/* This process goes on playing the kernel for the testbed (see
	 * usb_emul_chown_testbed()); only the node is left to udev. */
	CHECK_EQ(usb_emul_chown_testbed(r.emul, uid, gid), 0);

	CHECK_EQ(privilege_drop("nobody"), 0);
	CHECK_EQ(getuid(), uid);
	CHECK_EQ(geteuid(), uid);
	CHECK_EQ(getgid(), gid);
	CHECK_EQ(status_number("CapEff", 16), 0);
	CHECK_EQ(status_number("NoNewPrivs", 10), 1);
	CHECK(setuid(0) < 0);
	CHECK(check_node(r.emul, gid, 0660)); /* through the group: not the owner */
	printf("after the drop: uid %u gid %u, CapEff 0, no_new_privs; node root:%u 0660\n", (unsigned)getuid(),
	       (unsigned)getgid(), (unsigned)gid);

	/* Out mid-upload and in again: a new node, which udev gives the group. */
	struct proj_usb_debug dbg;
	proj_usb_get_debug(r.p, &dbg);
	uint64_t events = dbg.usb.hotplug_arrivals;
	unplug_mid_upload(&r, large);
	int64_t ms = replug(&r, &big);
	CHECK(check_node(r.emul, gid, 0660));
	large->seq = 71;
	upload_and_show(&r, 1, large);
	proj_usb_get_debug(r.p, &dbg);
	if (dbg.usb.hotplug) /* the uevent reached the unprivileged driver (it or a rescan opened the device) */
		CHECK(dbg.usb.hotplug_arrivals > events);
	printf("hot-plug after the drop: libusb events %s; re-plug found in %lld ms; arrivals seen %llu, "
	       "removals %llu, found by rescan %llu\n",
	       dbg.usb.hotplug ? "on" : "off", (long long)ms, (unsigned long long)dbg.usb.hotplug_arrivals,
	       (unsigned long long)dbg.usb.hotplug_removals, (unsigned long long)dbg.usb.rescan_opens);

	/* The control: a node only root may open is announced and rescanned,
	 * and stays absent; once udev gives it the group, a rescan opens it. */
	unplug_mid_upload(&r, large);
	CHECK_EQ(usb_emul_wait_closed(r.emul, 2000), 0); /* the driver holds nothing of it */
	int arrived = r.ev.arrived;
	udev.gid = 0;
	udev.mode = 0600;
	CHECK_EQ(usb_emul_plug(r.emul, &big, 3, 0), 0);
	/* libusb's hot-plug thread reads the new device's sysfs files: let it
	 * (the driver tries nothing until run_for() below), then count the
	 * fds, the device model's included. */
	struct timespec settle = { .tv_nsec = 100000000 };
	nanosleep(&settle, NULL);
	int fds = count_fds();
	CHECK(!check_node(r.emul, 0, 0600));
	CHECK_EQ(errno, EACCES);
	proj_usb_get_debug(r.p, &dbg);
	events = dbg.usb.hotplug_arrivals;
	run_for(r.p, 1200); /* the hot-plug event and two rescans */
	CHECK_EQ(r.ev.arrived, arrived);
	proj_usb_get_debug(r.p, &dbg);
	if (dbg.usb.hotplug)
		CHECK(dbg.usb.hotplug_arrivals > events); /* announced, and still refused */
	/* Each refused open left a socket of the preload library's (see
	 * usb_emul_close_stray_sockets()), none of the driver's. */
	int refused = usb_emul_close_stray_sockets(r.emul);
	CHECK(refused >= 1);
	CHECK_EQ(usb_emul_wait_closed(r.emul, 2000), 0);
	CHECK_EQ(count_fds(), fds);
	struct projector_stats st;
	r.p->impl->get_stats(r.p, &st);
	CHECK(!st.present);
	struct projector_info info;
	CHECK_EQ(r.p->impl->get_info(r.p, &info), -ENODEV);
	CHECK_EQ(r.p->impl->upload(r.p, 2, large, NULL, NULL), -ENODEV);
	udev.gid = gid;
	udev.mode = 0660;
	CHECK_EQ(usb_emul_apply_node_rule(r.emul), 0);
	CHECK(check_node(r.emul, gid, 0660));
	ms = wait_for(r.p, &r.ev.arrived, arrived, 2000);
	large->seq = 72;
	upload_and_show(&r, 2, large);
	proj_usb_get_debug(r.p, &dbg);
	printf("root-only node after the drop: absent through 1200 ms of hot-plug and rescans (%d opens refused); "
	       "given the group, found in %lld ms (found by rescan %llu)\n",
	       refused, (long long)ms, (unsigned long long)dbg.usb.rescan_opens);
	r.p->impl->get_stats(r.p, &st);
	CHECK_EQ(st.arrivals, 3); /* at the start, after the drop, given the group */
	CHECK_EQ(r.ev.arrived, 2);
	CHECK_EQ(r.ev.gone, 2);

	rig_finish(&r);
	volume_destroy(large);
	close(udev_fd);
	printf("after the drop: ");
	return check_done();
}

static void test_hotplug_after_drop(const char *self)
{
	if (geteuid() != 0 || !getpwnam("nobody")) {
		printf("hot-plug after the privilege drop: skipped (needs root and a user nobody)\n");
		return;
	}
	int sv[2];
	CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) == 0);
	char fd_arg[16];
	snprintf(fd_arg, sizeof(fd_arg), "%d", sv[1]);
	char *argv[] = { (char *)self, AFTER_DROP_ARG, fd_arg, NULL };
	char *asan_opt;
	char **env = child_env(&asan_opt);
	fflush(NULL);
	pid_t pid = fork();
	CHECK(pid >= 0);
	if (pid == 0) {
		/* Only async-signal-safe calls between fork and exec. */
		if (fcntl(sv[1], F_SETFD, 0) == 0)
			execve(self, argv, env);
		_exit(127);
	}
	close(sv[1]);
	free(asan_opt);
	free(env);
	int served = serve_udev(sv[0]);
	close(sv[0]);
	int status;
	CHECK_EQ(waitpid(pid, &status, 0), pid);
	CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the child that dropped root: status 0x%x", status);
	CHECK_EQ(served, 4); /* at the start, at each of the two plugs after the drop, and the fix */
}

int main(int argc, char **argv)
{
	if (argc == 3 && !strcmp(argv[1], AFTER_DROP_ARG)) /* the child of test_hotplug_after_drop() */
		return after_drop(atoi(argv[2]));
	struct usb_emul *e = usb_emul_create();
	if (!e) {
		printf("SKIP: not running under umockdev (LD_PRELOAD=libumockdev-preload.so.0)\n");
		return 77;
	}
	usb_emul_destroy(e);
	struct volume *large = volume_create(&big);
	CHECK(large);
	random_volume(large, 8, 1);
	test_open();
	test_refuse_geometry();
	test_upload_swap();
	test_in_flight(large);
	test_delta();
	test_half_turns();
	test_error_events();
	test_keepalive();
	test_duplicate_arrival();
	test_hotplug(large);
	test_cycles(large);
	test_hotplug_after_drop(strchr(argv[0], '/') ? argv[0] : "/proc/self/exe");
	volume_destroy(large);
	return check_done();
}
