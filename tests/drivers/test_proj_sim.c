/* The simulated projector, host half and device model, in real time at
 * 1800 rpm (33 ms revolutions). Waits are bounded and generous; outcomes are
 * checked against the rotor's true revolution starts, which do not depend on
 * how late the test gets to run. */
#include <errno.h>
#include <poll.h>
#include <stdlib.h>

#include "check.h"
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
	CHECK(p->impl->upload(p, 0, r.vol, NULL) > 0);
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
	CHECK_EQ(p->impl->upload(p, 0, r.vol, NULL), -EBUSY);
	random_volume(r.vol, 5, 2);
	CHECK(p->impl->upload(p, 1, r.vol, NULL) > 0);
	CHECK_EQ(p->impl->swap(p, 1), 0);
	CHECK_EQ(p->impl->upload(p, 1, r.vol, NULL), -EBUSY);
	CHECK_EQ(p->impl->swap(p, 2), -EBUSY); /* one swap at a time */
	CHECK_EQ(p->impl->swap(p, 7), -EINVAL);
	wait_swapped(p, &r.ev);
	CHECK_EQ(r.ev.buffer, 1);
	CHECK(volumes_equal(p->impl->shown(p), r.vol));
	CHECK_EQ(p->impl->swap(p, 1), -EBUSY);         /* already shown */
	CHECK(p->impl->upload(p, 0, r.vol, NULL) > 0); /* free again */

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
	CHECK(r0.p->impl->upload(r0.p, 0, r0.vol, NULL) > 0);
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
	CHECK(p->impl->upload(p, 2, vol, NULL) > 0);
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

int main(void)
{
	int fds = count_fds();
	test_info();
	test_upload_swap();
	test_underrun();
	test_device_rejects_corrupt_volume();
	CHECK_EQ(count_fds(), fds);
	return 0;
}
