/* The simulated projector, host half and device model, in real time at
 * 1800 rpm (33 ms revolutions). Waits are bounded and generous; outcomes are
 * checked against the rotor's true revolution starts, which do not depend on
 * how late the test gets to run. The half-turn swaps (protocol 1.2) run on
 * the rotor's simulated clock instead, stepped to each boundary and either
 * side of it. */
#include <errno.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "le.h"
#include "log.h"
#include "proj_sim_dev.h"
#include "projector.h"
#include "sim_rotor.h"
#include "volume_util.h"

static const struct geometry geom = {
	.width = 96,
	.height = 64,
	.images_per_rev = 16,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
};

struct events {
	int swaps;
	uint32_t buffer;
	int64_t time_ns;
};

static void on_swapped(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	struct events *ev = data;
	ev->swaps++;
	ev->buffer = buffer;
	ev->time_ns = time_ns;
}

static void on_gone(void *data, int err)
{
	CHECK(!"gone");
}

static const struct projector_listener listener = { .swapped = on_swapped, .gone = on_gone };

/* Dispatches until a swap is reported (at most 2 s). */
static void wait_swapped(struct projector *p, struct events *ev)
{
	int before = ev->swaps;
	int64_t deadline = now_ns() + 2000000000LL;
	while (ev->swaps == before) {
		CHECK(now_ns() < deadline);
		struct pollfd pfd = { .fd = p->impl->get_fd(p), .events = POLLIN };
		CHECK(poll(&pfd, 1, 100) >= 0);
		CHECK_EQ(p->impl->dispatch(p), 0);
	}
	CHECK_EQ(ev->swaps, before + 1);
}

struct rig {
	struct sim_rotor *rotor;
	struct projector *p;
	struct volume *vol;
	struct events ev;
};

static void rig_init(struct rig *r, uint64_t link)
{
	r->ev = (struct events){ 0 };
	r->rotor = sim_rotor_create(geom.rpm);
	CHECK(r->rotor);
	struct proj_sim_config cfg = { .geom = geom, .buffers = 3, .link_bytes_per_sec = link };
	r->p = proj_sim_create(r->rotor, &cfg, &listener, &r->ev);
	CHECK(r->p);
	r->vol = volume_create(&geom);
	CHECK(r->vol);
}

static void rig_finish(struct rig *r)
{
	volume_destroy(r->vol);
	r->p->impl->destroy(r->p);
	sim_rotor_destroy(r->rotor);
}

static void test_info(void)
{
	struct rig r;
	rig_init(&r, 12345678);
	struct projector_info info;
	CHECK_EQ(r.p->impl->get_info(r.p, &info), 0);
	CHECK_EQ(info.geom.width, geom.width);
	CHECK_EQ(info.geom.height, geom.height);
	CHECK_EQ(info.geom.images_per_rev, geom.images_per_rev);
	CHECK(info.geom.mirrored);
	CHECK(info.geom.half_height == geom.half_height && info.geom.rpm == geom.rpm);
	CHECK_EQ(info.buffers, 3);
	CHECK_EQ(info.link_bytes_per_sec, 12345678);
	CHECK_EQ(r.p->impl->set_timing(r.p, sim_rotor_period_ns(r.rotor), now_ns()), 0);
	CHECK_EQ(r.p->impl->set_timing(r.p, 0, 0), -EINVAL);
	rig_finish(&r);
}

static void test_upload_swap(void)
{
	struct rig r;
	rig_init(&r, 0);
	struct projector *p = r.p;
	int64_t period = sim_rotor_period_ns(r.rotor);
	random_volume(r.vol, 3, 1);
	CHECK(p->impl->upload(p, 0, r.vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, 2), -ENODATA); /* never written */
	int64_t asked = now_ns();
	CHECK_EQ(p->impl->swap(p, 0), 0);
	int64_t answered = now_ns();
	wait_swapped(p, &r.ev);
	CHECK_EQ(r.ev.buffer, 0);
	/* Shown from the first true revolution start after the request (which
	 * the device saw somewhere between asked and answered). */
	CHECK_EQ(sim_rotor_next_index(r.rotor, r.ev.time_ns), r.ev.time_ns);
	CHECK(r.ev.time_ns >= sim_rotor_next_index(r.rotor, asked));
	CHECK(r.ev.time_ns <= sim_rotor_next_index(r.rotor, answered));
	CHECK(r.ev.time_ns - asked <= period || answered - asked > 1000000);
	CHECK(!p->impl->shown(p)); /* still blanked */
	CHECK_EQ(p->impl->blank(p, false), 0);
	const struct volume *shown = p->impl->shown(p);
	CHECK(shown && volumes_equal(shown, r.vol));
	CHECK_EQ(shown->shown_ns, (uint64_t)r.ev.time_ns);

	/* The shown buffer and one awaiting a swap are not writable. */
	CHECK_EQ(p->impl->upload(p, 0, r.vol, NULL, NULL), -EBUSY);
	random_volume(r.vol, 5, 2);
	CHECK(p->impl->upload(p, 1, r.vol, NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, 1), 0);
	CHECK_EQ(p->impl->upload(p, 1, r.vol, NULL, NULL), -EBUSY);
	CHECK_EQ(p->impl->swap(p, 2), -EBUSY); /* one swap at a time */
	CHECK_EQ(p->impl->swap(p, 7), -EINVAL);
	wait_swapped(p, &r.ev);
	CHECK_EQ(r.ev.buffer, 1);
	CHECK(volumes_equal(p->impl->shown(p), r.vol));
	CHECK_EQ(p->impl->swap(p, 1), -EBUSY);               /* already shown */
	CHECK(p->impl->upload(p, 0, r.vol, NULL, NULL) > 0); /* free again */

	struct proj_sim_stats st;
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.swaps, 2);
	CHECK_EQ(st.underruns, 0);
	CHECK(st.revolutions >= 1);
	CHECK(st.bytes > volume_sparse_bytes(r.vol));
	CHECK_EQ(p->impl->blank(p, true), 0);
	CHECK(!p->impl->shown(p));
	rig_finish(&r);
}

static void test_underrun(void)
{
	/* The link takes 4 revolutions for this volume: its swap must miss
	 * the next revolution start and show, whole, at the first one after
	 * the last byte is through. */
	struct rig r0;
	rig_init(&r0, 0);
	random_volume(r0.vol, 8, 3); /* every tile of 3/4 of the images */
	CHECK(r0.p->impl->upload(r0.p, 0, r0.vol, NULL, NULL) > 0);
	struct proj_sim_stats st0;
	proj_sim_get_stats(r0.p, &st0);
	uint64_t bytes = st0.bytes; /* the wire size of this upload */
	struct volume *vol = volume_create(&geom);
	CHECK(vol && volume_copy(vol, r0.vol) == 0);
	rig_finish(&r0);

	struct rig r;
	int64_t period = 33333333;
	uint64_t rate = (uint64_t)((double)bytes * 1e9 / (4.0 * (double)period));
	rig_init(&r, rate);
	struct projector *p = r.p;
	CHECK_EQ(p->impl->blank(p, false), 0);
	int64_t t0 = now_ns();
	CHECK(p->impl->upload(p, 2, vol, NULL, NULL) > 0);
	int64_t asked = now_ns();
	CHECK_EQ(p->impl->swap(p, 2), 0);
	int64_t first_start = sim_rotor_next_index(r.rotor, asked);
	wait_swapped(p, &r.ev);
	CHECK_EQ(r.ev.buffer, 2);
	CHECK_EQ(sim_rotor_next_index(r.rotor, r.ev.time_ns), r.ev.time_ns);
	CHECK(r.ev.time_ns >= t0 + 4 * period - 1000000); /* not before the data */
	CHECK(r.ev.time_ns >= first_start + period);      /* a revolution late at least */
	CHECK(r.ev.time_ns <= now_ns());
	struct proj_sim_stats st;
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.underruns, 1);
	CHECK_EQ(st.swaps, 1);
	CHECK(volumes_equal(p->impl->shown(p), vol));
	volume_destroy(vol);
	rig_finish(&r);
}

/* Raw wire traffic to the device model: a volume whose CRC is wrong is
 * marked invalid, reported, and a swap to it refused. */
static void test_device_rejects_corrupt_volume(void)
{
	struct sim_rotor *rotor = sim_rotor_create(geom.rpm);
	CHECK(rotor);
	struct proj_simdev *dev = proj_simdev_create(rotor, &geom, 2, 0);
	CHECK(dev);
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 4, 9);
	size_t size = projwire_volume_size(vol);
	uint8_t *wire = malloc(size);
	CHECK(wire);
	CHECK_EQ(projwire_volume_encode(vol, 1, wire), size);
	wire[size - 1] ^= 0x40; /* the CRC */
	proj_simdev_bulk_out(dev, wire, size);

	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX], in[64];
	struct projwire_ctrl swap = { .request = PROJWIRE_REQ_SWAP, .buffer = 1 };
	size_t len = projwire_ctrl_encode(&swap, 0, setup, data);
	CHECK_EQ(proj_simdev_control(dev, setup, data, len, in, sizeof(in)), -EPIPE);
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	projwire_ctrl_encode(&get, 0, setup, data);
	int r = proj_simdev_control(dev, setup, NULL, 0, in, sizeof(in));
	CHECK_EQ(r, PROJWIRE_STATUS_SIZE);
	struct projwire_status st;
	CHECK_EQ(projwire_status_decode(in, (size_t)r, &st), 0);
	CHECK_EQ(st.buffer_state[1], PROJWIRE_BUF_INVALID);
	CHECK_EQ(st.last_error, PROJWIRE_ERR_NOT_READY);
	CHECK_EQ(st.shown, PROJWIRE_NO_BUFFER);
	CHECK(st.flags & PROJWIRE_STATUS_BLANKED);
	CHECK_EQ(st.bytes, size);

	/* The error event came out on the IN side, fd readable. */
	struct pollfd pfd = { .fd = proj_simdev_get_fd(dev), .events = POLLIN };
	CHECK_EQ(poll(&pfd, 1, 1000), 1);
	CHECK_EQ(proj_simdev_dispatch(dev), 0);
	uint8_t evbuf[4 * PROJWIRE_EVENT_MAX];
	size_t n = proj_simdev_bulk_in(dev, evbuf, sizeof(evbuf));
	struct projwire_event ev;
	CHECK_EQ(projwire_event_decode(evbuf, n, &ev), (int)n);
	CHECK_EQ(ev.type, PROJWIRE_EV_ERROR);
	CHECK_EQ(ev.error, PROJWIRE_ERR_CRC);
	CHECK_EQ(ev.buffer, 1);
	CHECK(!proj_simdev_shown(dev));

	/* Garbage control requests stall; the device carries on. */
	memset(setup, 0xff, sizeof(setup));
	CHECK_EQ(proj_simdev_control(dev, setup, NULL, 0, in, sizeof(in)), -EPIPE);
	/* Rewritten correctly, the buffer is accepted. */
	wire[size - 1] ^= 0x40;
	proj_simdev_bulk_out(dev, wire, size);
	len = projwire_ctrl_encode(&swap, 0, setup, data);
	CHECK_EQ(proj_simdev_control(dev, setup, data, len, in, sizeof(in)), 0);
	free(wire);
	volume_destroy(vol);
	proj_simdev_destroy(dev);
	sim_rotor_destroy(rotor);
}

/* ---- Half-turn swaps (1.2), on the rotor's simulated clock ---- */

struct half_events {
	int swaps;
	uint32_t buffer;
	int64_t time_ns;
	uint64_t seq;
	bool half;
};

static void on_swapped_at(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq, bool half_turn)
{
	struct half_events *ev = data;
	ev->swaps++;
	ev->buffer = buffer;
	ev->time_ns = time_ns;
	ev->seq = seq;
	ev->half = half_turn;
}

static void on_swapped_not(void *data, uint32_t buffer, int64_t time_ns, uint64_t seq)
{
	CHECK(!"swapped() called although swapped_at() is set");
}

static const struct projector_listener half_listener = {
	.swapped = on_swapped_not,
	.swapped_at = on_swapped_at,
	.gone = on_gone,
};

struct half_rig {
	struct sim_rotor *rotor;
	struct projector *p;
	struct half_events ev;
	int64_t period, rev; /* the rotor's; a revolution start to count from */
	struct volume *vol[4];
};

/* A projector lit, its timing exactly the rotor's, and the simulated clock
 * a tenth of a revolution past revolution start r->rev. The link takes
 * link_revs revolutions for r->vol[0] whole (0: no time). */
static void half_rig_init(struct half_rig *r, const struct geometry *g, double link_revs, uint8_t minor)
{
	*r = (struct half_rig){ 0 };
	for (int i = 0; i < 4; i++) {
		r->vol[i] = volume_create(g);
		CHECK(r->vol[i]);
		random_volume(r->vol[i], 3, 100 + (uint64_t)i);
	}
	r->rotor = sim_rotor_create(g->rpm);
	CHECK(r->rotor);
	sim_rotor_set_now(r->rotor, now_ns()); /* simulated from here on */
	r->period = sim_rotor_period_ns(r->rotor);
	uint64_t link = 0;
	if (link_revs > 0)
		link = (uint64_t)((double)projwire_volume_size(r->vol[0]) * 1e9 / (link_revs * (double)r->period));
	struct proj_sim_config cfg = { .geom = *g, .buffers = 3, .link_bytes_per_sec = link, .version_minor = minor };
	r->p = proj_sim_create(r->rotor, &cfg, &half_listener, &r->ev);
	CHECK(r->p);
	CHECK_EQ(r->p->impl->set_timing(r->p, r->period, sim_rotor_start(r->rotor)), 0);
	CHECK_EQ(r->p->impl->blank(r->p, false), 0);
	r->rev = sim_rotor_next_index(r->rotor, sim_rotor_now(r->rotor) + 1);
	sim_rotor_set_now(r->rotor, r->rev + r->period / 10);
}

static void half_rig_finish(struct half_rig *r)
{
	for (int i = 0; i < 4; i++)
		volume_destroy(r->vol[i]);
	r->p->impl->destroy(r->p);
	sim_rotor_destroy(r->rotor);
}

/* The simulated clock to t, and a turn of the event loop. */
static void half_at(struct half_rig *r, int64_t t)
{
	sim_rotor_set_now(r->rotor, t);
	CHECK_EQ(r->p->impl->dispatch(r->p), 0);
}

/* Shown from exactly t on and not a nanosecond before: the swap event (its
 * time and boundary) and the content the device lights. */
static void check_switch(struct half_rig *r, int64_t t, bool half, uint32_t buffer, const struct volume *vol)
{
	struct projector *p = r->p;
	int before = r->ev.swaps;
	const struct volume *was = p->impl->shown(p);
	uint64_t was_seq = was ? was->seq : 0;
	half_at(r, t - 1);
	CHECK_EQ(r->ev.swaps, before);
	was = p->impl->shown(p);
	CHECK(was_seq ? was && was->seq == was_seq : !was);
	half_at(r, t);
	CHECK_EQ(r->ev.swaps, before + 1);
	CHECK_EQ(r->ev.time_ns, t);
	CHECK_EQ(r->ev.half, half);
	CHECK_EQ(r->ev.buffer, buffer);
	CHECK_EQ(r->ev.seq, vol->seq);
	const struct volume *shown = p->impl->shown(p);
	CHECK(shown && volumes_equal(shown, vol));
	CHECK_EQ(shown->shown_ns, (uint64_t)t);
	/* Where the host's timing (period, index given to set_timing) puts
	 * that boundary: index + j * period / 2, to the nanosecond the true
	 * rotor rounds it to. */
	int64_t j = (t - sim_rotor_start(r->rotor)) * 2 / r->period;
	int64_t predicted = sim_rotor_start(r->rotor) + j * r->period / 2;
	CHECK_MSG(llabs(t - predicted) <= 1, "boundary %lld ns off the timing", (long long)(t - predicted));
	CHECK_EQ(j % 2 == 1, half);
}

static void test_half_turn_swaps(void)
{
	struct half_rig r;
	half_rig_init(&r, &geom, 0, 0);
	struct projector *p = r.p;
	int64_t P = r.period, R = r.rev, half = (P + 1) / 2;
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK(info.half_turn_swaps);

	/* A tenth into a revolution: the next half-turn start is its middle,
	 * the start of image N/2. */
	CHECK(p->impl->upload(p, 0, r.vol[0], NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 0), 0);
	CHECK_EQ(p->impl->swap_half(p, 1), -EBUSY); /* one swap at a time */
	CHECK_EQ(p->impl->swap(p, 1), -EBUSY);
	CHECK_EQ(p->impl->upload(p, 0, r.vol[0], NULL, NULL), -EBUSY);
	CHECK_EQ(p->impl->swap_half(p, 7), -EINVAL);
	bool second;
	CHECK_EQ(sim_rotor_next_half_turn(r.rotor, R + P / 10, &second), R + half);
	CHECK(second);
	check_switch(&r, R + half, true, 0, r.vol[0]);

	/* Past the middle: the next one is the revolution start. */
	half_at(&r, R + half + P / 10);
	CHECK(p->impl->upload(p, 1, r.vol[1], NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 1), 0);
	check_switch(&r, R + P, false, 1, r.vol[1]);

	/* Right after it: the next middle. Three volumes in one revolution. */
	half_at(&r, R + P + 1);
	CHECK(p->impl->upload(p, 0, r.vol[2], NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 0), 0);
	check_switch(&r, R + P + half, true, 0, r.vol[2]);

	/* swap() keeps its meaning on a 1.2 device: the revolution start, not
	 * the middle that comes first. */
	half_at(&r, R + 2 * P + P / 10);
	CHECK(p->impl->upload(p, 1, r.vol[3], NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, 1), 0);
	half_at(&r, R + 2 * P + half);
	CHECK_EQ(r.ev.swaps, 3);
	check_switch(&r, R + 3 * P, false, 1, r.vol[3]);

	/* The device's counters and its angle-error meter: lit with exact
	 * timing since the start, every slice where it belongs. */
	struct proj_sim_stats st;
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.swaps, 4);
	CHECK_EQ(st.underruns, 0);
	CHECK(st.revolutions >= 3);
	CHECK(st.angle_err_max >= 0 && st.angle_err_max < 0.01);
	CHECK(st.angle_err_p99 >= 0 && st.angle_err_p99 <= 0.001);
	CHECK_EQ(st.lit_untimed_ns, 0);
	half_rig_finish(&r);
}

/* Data late for a half-turn start: the swap waits for the next one it can
 * make, one underrun however many it misses. */
static void test_half_turn_underrun(void)
{
	struct half_rig r;
	half_rig_init(&r, &geom, 0.6, 0); /* r.vol[0] takes 0.6 revolutions on the link */
	struct projector *p = r.p;
	int64_t P = r.period, R = r.rev, half = (P + 1) / 2;
	size_t size = projwire_volume_size(r.vol[0]);
	/* Asked at R + 0.1 P, through at R + 0.7 P: the middle (R + 0.5 P) is
	 * missed, the revolution start R + P taken. */
	CHECK_EQ(p->impl->upload(p, 0, r.vol[0], NULL, NULL), (int)size);
	CHECK_EQ(p->impl->swap_half(p, 0), 0);
	half_at(&r, R + half);
	CHECK_EQ(r.ev.swaps, 0);
	check_switch(&r, R + P, false, 0, r.vol[0]);
	struct proj_sim_stats st;
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.underruns, 1);

	/* Behind another upload of the same size: 1.2 revolutions from
	 * R + 1.1 P, through at R + 2.3 P; R + 1.5 P and R + 2 P missed,
	 * R + 2.5 P taken. */
	CHECK_EQ(volume_copy(r.vol[1], r.vol[0]), 0);
	r.vol[1]->seq = 201;
	half_at(&r, R + P + P / 10);
	CHECK_EQ(p->impl->upload(p, 1, r.vol[0], NULL, NULL), (int)size);
	CHECK_EQ(p->impl->upload(p, 2, r.vol[1], NULL, NULL), (int)size);
	CHECK_EQ(p->impl->swap_half(p, 2), 0);
	half_at(&r, R + 2 * P);
	CHECK_EQ(r.ev.swaps, 1);
	check_switch(&r, R + 2 * P + half, true, 2, r.vol[1]);
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.underruns, 2);
	CHECK_EQ(st.swaps, 2);
	half_rig_finish(&r);
}

/* Where half-turn swaps are not to be had, swap_half() is swap(): a 1.1
 * device (which would stall SWAP_HALF: the request never reaches it, or
 * the call would fail) and one that is not mirrored. */
static void check_revolution_fallback(const struct geometry *g, uint8_t minor)
{
	struct half_rig r;
	half_rig_init(&r, g, 0, minor);
	struct projector *p = r.p;
	struct projector_info info;
	CHECK_EQ(p->impl->get_info(p, &info), 0);
	CHECK(!info.half_turn_swaps);
	CHECK(p->impl->upload(p, 0, r.vol[0], NULL, NULL) > 0);
	CHECK_EQ(p->impl->swap_half(p, 0), 0);
	half_at(&r, r.rev + r.period / 2 + 1);
	CHECK_EQ(r.ev.swaps, 0);
	check_switch(&r, r.rev + r.period, false, 0, r.vol[0]);
	struct proj_sim_stats st;
	proj_sim_get_stats(p, &st);
	CHECK_EQ(st.swaps, 1);
	CHECK_EQ(st.underruns, 0);
	half_rig_finish(&r);
}

static void test_half_turn_fallback(void)
{
	check_revolution_fallback(&geom, 1);
	struct geometry flat = geom;
	flat.mirrored = false;
	check_revolution_fallback(&flat, 0);
	/* No such version. */
	struct sim_rotor *rotor = sim_rotor_create(geom.rpm);
	CHECK(rotor);
	struct proj_sim_config cfg = { .geom = geom, .buffers = 3, .version_minor = PROJWIRE_VERSION_MINOR + 1 };
	CHECK(!proj_sim_create(rotor, &cfg, &half_listener, NULL));
	CHECK_EQ(errno, EINVAL);
	sim_rotor_destroy(rotor);
}

/* One control request to the device model: its result, the reply in in. */
static int dev_control(struct proj_simdev *dev, const struct projwire_ctrl *c, uint8_t in[64])
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX];
	size_t len = projwire_ctrl_encode(c, 0, setup, data);
	return proj_simdev_control(dev, setup, data, len, in, 64);
}

static struct projwire_status dev_status(struct proj_simdev *dev)
{
	uint8_t in[64];
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	CHECK_EQ(dev_control(dev, &get, in), PROJWIRE_STATUS_SIZE);
	CHECK_EQ(projwire_status_decode(in, PROJWIRE_STATUS_SIZE, &st), 0);
	return st;
}

/* The device model byte for byte: GET_INFO's minor, SWAP_HALF taken or
 * stalled as unknown, the status flag, SWAPPED's boundary field. */
static void test_device_half_turn(void)
{
	struct sim_rotor *rotor = sim_rotor_create(geom.rpm);
	CHECK(rotor);
	sim_rotor_set_now(rotor, now_ns());
	struct proj_simdev *dev = proj_simdev_create(rotor, &geom, 3, 0);
	CHECK(dev);
	struct volume *vol = volume_create(&geom);
	CHECK(vol);
	random_volume(vol, 4, 9);
	size_t size = projwire_volume_size(vol);
	uint8_t *wire = malloc(size), in[64];
	CHECK(wire);
	CHECK_EQ(projwire_volume_encode(vol, 1, wire), size);
	proj_simdev_bulk_out(dev, wire, size);

	struct projwire_ctrl info = { .request = PROJWIRE_REQ_GET_INFO };
	CHECK_EQ(dev_control(dev, &info, in), PROJWIRE_INFO_SIZE);
	CHECK_EQ(in[1], 2);
	struct projwire_ctrl half = { .request = PROJWIRE_REQ_SWAP_HALF, .buffer = 1 };
	struct projwire_ctrl swap = { .request = PROJWIRE_REQ_SWAP, .buffer = 1 };

	/* As a 1.1 device: GET_INFO says so and SWAP_HALF is unknown. */
	proj_simdev_set_minor(dev, 1);
	CHECK_EQ(dev_control(dev, &info, in), PROJWIRE_INFO_SIZE);
	CHECK_EQ(in[1], 1);
	CHECK_EQ(dev_control(dev, &half, in), -EPIPE);
	struct projwire_status st = dev_status(dev);
	CHECK_EQ(st.last_error, PROJWIRE_ERR_UNSUPPORTED);
	CHECK(!(st.flags & PROJWIRE_STATUS_PENDING));
	/* Unknown however it is formed; to a 1.2 device a bad buffer is a
	 * malformed request. */
	uint8_t setup[PROJWIRE_SETUP_SIZE];
	struct projwire_setup bad = { PROJWIRE_RT_OUT, PROJWIRE_REQ_SWAP_HALF, 9, 0, 0 };
	projwire_setup_encode(&bad, setup);
	CHECK_EQ(proj_simdev_control(dev, setup, NULL, 0, in, sizeof(in)), -EPIPE);
	CHECK_EQ(dev_status(dev).last_error, PROJWIRE_ERR_UNSUPPORTED);
	proj_simdev_set_minor(dev, PROJWIRE_VERSION_MINOR);
	CHECK_EQ(proj_simdev_control(dev, setup, NULL, 0, in, sizeof(in)), -EPIPE);
	CHECK_EQ(dev_status(dev).last_error, PROJWIRE_ERR_REQUEST);

	int64_t t = sim_rotor_now(rotor);
	CHECK_EQ(dev_control(dev, &half, in), 0);
	st = dev_status(dev);
	CHECK_EQ(st.flags & (PROJWIRE_STATUS_PENDING | PROJWIRE_STATUS_PENDING_HALF),
		 PROJWIRE_STATUS_PENDING | PROJWIRE_STATUS_PENDING_HALF);
	CHECK_EQ(st.pending, 1);
	CHECK_EQ(dev_control(dev, &swap, in), -EPIPE); /* a swap is pending */
	CHECK_EQ(dev_status(dev).last_error, PROJWIRE_ERR_BUSY);
	bool second;
	int64_t at = sim_rotor_next_half_turn(rotor, t, &second);
	sim_rotor_set_now(rotor, at);
	CHECK_EQ(proj_simdev_dispatch(dev), 0);
	uint8_t evbuf[4 * PROJWIRE_EVENT_MAX];
	size_t n = proj_simdev_bulk_in(dev, evbuf, sizeof(evbuf));
	CHECK_EQ(n, 32);
	CHECK_EQ(evbuf[2], PROJWIRE_EV_SWAPPED);
	CHECK_EQ(le_get32(evbuf + 8), 1);
	CHECK_EQ(le_get32(evbuf + 12), second ? PROJWIRE_SWAPPED_HALF_TURN : 0);
	CHECK_EQ((int64_t)le_get64(evbuf + 16), at);
	CHECK_EQ(le_get64(evbuf + 24), vol->seq);
	st = dev_status(dev);
	CHECK_EQ(st.shown, 1);
	CHECK(!(st.flags & (PROJWIRE_STATUS_PENDING | PROJWIRE_STATUS_PENDING_HALF)));
	CHECK_EQ(st.swaps, 1);
	CHECK_EQ(st.underruns, 0);
	CHECK_EQ(dev_control(dev, &half, in), -EPIPE); /* already shown */
	CHECK_EQ(dev_status(dev).last_error, PROJWIRE_ERR_BUSY);
	proj_simdev_destroy(dev);

	/* Without a mirrored half turn there is nothing to swap at. */
	struct geometry flat = geom;
	flat.mirrored = false;
	dev = proj_simdev_create(rotor, &flat, 3, 0);
	CHECK(dev);
	struct volume *fv = volume_create(&flat);
	CHECK(fv);
	random_volume(fv, 4, 10);
	uint8_t *fw = malloc(projwire_volume_size(fv));
	CHECK(fw);
	proj_simdev_bulk_out(dev, fw, projwire_volume_encode(fv, 1, fw));
	CHECK_EQ(dev_control(dev, &half, in), -EPIPE);
	CHECK_EQ(dev_status(dev).last_error, PROJWIRE_ERR_UNSUPPORTED);
	CHECK_EQ(dev_control(dev, &swap, in), 0);
	free(fw);
	volume_destroy(fv);
	proj_simdev_destroy(dev);
	free(wire);
	volume_destroy(vol);
	sim_rotor_destroy(rotor);
}

int main(void)
{
	int fds = count_fds();
	test_info();
	test_upload_swap();
	test_underrun();
	test_device_rejects_corrupt_volume();
	test_half_turn_swaps();
	test_half_turn_underrun();
	test_half_turn_fallback();
	test_device_half_turn();
	CHECK_EQ(count_fds(), fds);
	return 0;
}
