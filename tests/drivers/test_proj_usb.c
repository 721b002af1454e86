/* The USB projector (proj_usb.c) through libusb's real code paths against
 * the device model, with umockdev standing in for the kernel (usb_emul;
 * the rig in proj_usb_rig.h). Exits 77 (skipped) when not run under
 * umockdev's preload library. As root, it also runs itself again to
 * re-plug the device after the privilege drop (test_proj_usb_drop.c). */
#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "log.h"
#include "proj_usb_rig.h"
#include "projwire.h"
#include "sim_rotor.h"
#include "volume_util.h"

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
