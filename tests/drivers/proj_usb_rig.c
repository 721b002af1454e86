/* The USB projector's test rig (proj_usb_rig.h). */
#include "proj_usb_rig.h"

#include <errno.h>
#include <poll.h>

#include "check.h"
#include "log.h"
#include "volume_util.h"

const struct geometry geom = {
	.width = 96,
	.height = 64,
	.images_per_rev = 16,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
};

/* Large enough that one volume takes several 256 KiB bulk transfers. */
const struct geometry big = {
	.width = 512,
	.height = 512,
	.images_per_rev = 64,
	.mirrored = true,
	.half_height = 1.0f,
	.rpm = 1800.0f,
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

const struct projector_listener listener = {
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

const struct projector_listener half_listener = {
	.swapped_at = on_swapped_at,
	.error = on_error,
	.gone = on_gone,
	.arrived = on_arrived,
};

void rig_init_with(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor,
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

void rig_init(struct rig *r, const struct geometry *g, const struct geometry *dev_geom, uint8_t minor)
{
	rig_init_with(r, g, dev_geom, minor, &listener);
}

void rig_finish(struct rig *r)
{
	r->p->impl->destroy(r->p);
	/* umockdev's thread closes its end of the node after the driver closed
	 * its own; the count is the driver's only once that is done. */
	CHECK_EQ(usb_emul_wait_closed(r->emul, 2000), 0);
	CHECK_EQ(count_fds(), r->fds); /* nothing of the driver's left open */
	usb_emul_destroy(r->emul);
}

void turn(struct projector *p)
{
	struct pollfd pfd = { .fd = p->impl->get_fd(p), .events = POLLIN };
	CHECK(poll(&pfd, 1, 5) >= 0);
	CHECK_EQ(p->impl->dispatch(p), 0);
}

int64_t wait_for(struct projector *p, const int *count, int before, int ms)
{
	int64_t t0 = now_ns(), deadline = t0 + (int64_t)ms * 1000000;
	while (*count == before) {
		CHECK_MSG(now_ns() < deadline, "no event in %d ms", ms);
		turn(p);
	}
	return (now_ns() - t0) / 1000000;
}

void run_for(struct projector *p, int ms)
{
	int64_t deadline = now_ns() + (int64_t)ms * 1000000;
	while (now_ns() < deadline)
		turn(p);
}

void upload_and_show(struct rig *r, uint32_t buffer, const struct volume *vol)
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

void unplug_mid_upload(struct rig *r, const struct volume *vol)
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

int64_t replug(struct rig *r, const struct geometry *g)
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
