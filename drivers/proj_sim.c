/* The simulated projector, host side: the projector vtable implemented the
 * way the USB driver will, by encoding control requests and bulk records
 * with projwire, except that the bytes go to the in-process device model of
 * proj_sim_dev.c instead of libusb. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "log.h"
#include "proj_sim_dev.h"
#include "projector.h"
#include "projwire.h"

/* Bulk OUT transfer size: what the USB driver will submit per transfer. */
#define BULK_CHUNK (64 * 1024)

struct proj_sim {
	struct projector base;
	struct proj_simdev *dev;
	struct projwire_info info;
	uint8_t *wire; /* encode buffer, grown as needed */
	size_t wire_cap;
	uint64_t bytes_sent, device_errors;
};

static const struct projector_impl sim_impl;

/* One control transfer; a stalled request is turned back into the errno
 * the device gives in GET_STATUS.last_error. */
static int control(struct proj_sim *s, const struct projwire_ctrl *c, uint8_t *reply)
{
	uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX], in[PROJWIRE_CTRL_DATA_MAX];
	size_t len = projwire_ctrl_encode(c, 0, setup, data);
	int r = proj_simdev_control(s->dev, setup, data, len, reply ? reply : in, sizeof(in));
	if (r != -EPIPE)
		return r;
	struct projwire_ctrl get = { .request = PROJWIRE_REQ_GET_STATUS };
	struct projwire_status st;
	projwire_ctrl_encode(&get, 0, setup, data);
	r = proj_simdev_control(s->dev, setup, NULL, 0, in, sizeof(in));
	if (r < 0 || projwire_status_decode(in, (size_t)r, &st) < 0)
		return -EIO;
	return projwire_error_to_errno(st.last_error);
}

static int get_status(struct proj_sim *s, struct projwire_status *st)
{
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_STATUS };
	int r = control(s, &c, in);
	if (r < 0)
		return r;
	return projwire_status_decode(in, (size_t)r, st);
}

static int sim_get_info(struct projector *p, struct projector_info *out)
{
	struct proj_sim *s = (struct proj_sim *)p;
	memset(out, 0, sizeof(*out));
	strcpy(out->name, "sim");
	projwire_info_to_geometry(&s->info, &out->geom);
	out->buffers = s->info.buffers;
	out->link_bytes_per_sec = s->info.link_bytes_per_sec;
	return 0;
}

static int sim_blank(struct projector *p, bool blank)
{
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_BLANK, .blank = blank };
	return control((struct proj_sim *)p, &c, NULL);
}

static int sim_set_timing(struct projector *p, int64_t period_ns, int64_t index_ns)
{
	if (period_ns <= 0)
		return -EINVAL;
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_TIMING };
	c.timing = (struct projwire_timing){ (uint64_t)period_ns, index_ns, now_ns() };
	return control((struct proj_sim *)p, &c, NULL);
}

static bool volume_fits(const struct proj_sim *s, const struct volume *vol)
{
	struct geometry g;
	projwire_info_to_geometry(&s->info, &g);
	return vol->geom.width == g.width && vol->geom.height == g.height &&
	       vol->image_count == s->info.images_per_volume;
}

static int sim_upload(struct projector *p, uint32_t buffer, const struct volume *vol,
		      const struct volume *base)
{
	struct proj_sim *s = (struct proj_sim *)p;
	struct projwire_status st;
	if (buffer >= s->info.buffers || !volume_fits(s, vol))
		return -EINVAL;
	/* The device would refuse too, but only by an event after the bytes
	 * went out; asking first gives the caller a synchronous answer. */
	int r = get_status(s, &st);
	if (r < 0)
		return r;
	if (buffer == st.shown || buffer == st.pending)
		return -EBUSY;
	size_t size = projwire_upload_size(vol, base);
	if (size > s->wire_cap) {
		uint8_t *w = realloc(s->wire, size);
		if (!w)
			return -ENOMEM;
		s->wire = w;
		s->wire_cap = size;
	}
	size_t len = projwire_upload_encode(vol, base, buffer, s->wire);
	for (size_t off = 0; off < len; off += BULK_CHUNK)
		proj_simdev_bulk_out(s->dev, s->wire + off, len - off < BULK_CHUNK ? len - off : BULK_CHUNK);
	s->bytes_sent += len;
	return (int)len;
}

static int sim_swap(struct projector *p, uint32_t buffer)
{
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_SWAP, .buffer = buffer };
	if (buffer >= ((struct proj_sim *)p)->info.buffers)
		return -EINVAL;
	return control((struct proj_sim *)p, &c, NULL);
}

static int sim_get_fd(struct projector *p)
{
	return proj_simdev_get_fd(((struct proj_sim *)p)->dev);
}

static void handle_event(struct proj_sim *s, const struct projwire_event *ev)
{
	const struct projector_listener *l = s->base.listener;
	if (ev->type == PROJWIRE_EV_SWAPPED) {
		if (l && l->swapped)
			l->swapped(s->base.listener_data, ev->buffer, ev->time_ns, ev->seq);
		return;
	}
	s->device_errors++;
	if (l && l->error)
		l->error(s->base.listener_data, ev->buffer, projwire_error_to_errno(ev->error));
	log_warn("sim projector: device error %u on buffer %d (volume %llu)", (unsigned)ev->error,
		 ev->buffer == PROJWIRE_NO_BUFFER ? -1 : (int)ev->buffer, (unsigned long long)ev->seq);
}

static int sim_dispatch(struct projector *p)
{
	struct proj_sim *s = (struct proj_sim *)p;
	int r = proj_simdev_dispatch(s->dev);
	if (r < 0)
		return r;
	uint8_t in[16 * PROJWIRE_EVENT_MAX];
	size_t len;
	/* Like an IN transfer completing: several whole events at a time. */
	while ((len = proj_simdev_bulk_in(s->dev, in, sizeof(in))) > 0) {
		size_t off = 0;
		struct projwire_event ev;
		while (off < len && (r = projwire_event_decode(in + off, len - off, &ev)) > 0) {
			handle_event(s, &ev);
			off += (size_t)r;
		}
		if (off != len)
			return -EPROTO; /* a device speaking nonsense */
	}
	return 0;
}

static const struct volume *sim_shown(struct projector *p)
{
	return proj_simdev_shown(((struct proj_sim *)p)->dev);
}

static void sim_get_stats(struct projector *p, struct projector_stats *out)
{
	struct proj_sim *s = (struct proj_sim *)p;
	struct projwire_status st;
	*out = (struct projector_stats){
		.present = true,
		.bytes_sent = s->bytes_sent,
		.device_errors = s->device_errors,
		.arrivals = 1,
	};
	struct proj_simdev_stats ds;
	proj_simdev_get_stats(s->dev, &ds);
	out->angle_err_p50 = ds.angle_err_p50;
	out->angle_err_p99 = ds.angle_err_p99;
	out->angle_err_max = ds.angle_err_max;
	if (get_status(s, &st) < 0)
		return;
	out->revolutions = st.revolutions;
	out->swaps = st.swaps;
	out->underruns = st.underruns;
}

static void sim_destroy(struct projector *p)
{
	struct proj_sim *s = (struct proj_sim *)p;
	sim_blank(p, true); /* dark on every exit */
	proj_simdev_destroy(s->dev);
	free(s->wire);
	free(s);
}

static const struct projector_impl sim_impl = {
	.name = "sim",
	.get_info = sim_get_info,
	.blank = sim_blank,
	.set_timing = sim_set_timing,
	.upload = sim_upload,
	.swap = sim_swap,
	.get_fd = sim_get_fd,
	.dispatch = sim_dispatch,
	.shown = sim_shown,
	.get_stats = sim_get_stats,
	.destroy = sim_destroy,
};

struct projector *proj_sim_create(struct sim_rotor *rotor, const struct proj_sim_config *cfg,
				  const struct projector_listener *listener, void *data)
{
	struct proj_sim *s = calloc(1, sizeof(*s));
	if (!s)
		return NULL;
	s->base.impl = &sim_impl;
	s->base.listener = listener;
	s->base.listener_data = data;
	s->dev = proj_simdev_create(rotor, &cfg->geom, cfg->buffers, cfg->link_bytes_per_sec);
	if (!s->dev)
		goto err_free;
	/* Learn the device as the USB driver will: from GET_INFO. */
	uint8_t in[PROJWIRE_CTRL_DATA_MAX];
	struct projwire_ctrl c = { .request = PROJWIRE_REQ_GET_INFO };
	int r = control(s, &c, in);
	if (r >= 0)
		r = projwire_info_decode(in, (size_t)r, &s->info);
	if (r < 0) {
		errno = -r;
		goto err_dev;
	}
	return &s->base;

err_dev:
	proj_simdev_destroy(s->dev);
err_free:
	free(s); /* keeps errno */
	return NULL;
}

void proj_sim_get_stats(struct projector *p, struct proj_sim_stats *out)
{
	struct projwire_status st;
	memset(out, 0, sizeof(*out));
	if (p->impl != &sim_impl || get_status((struct proj_sim *)p, &st) < 0)
		return;
	out->revolutions = st.revolutions;
	out->swaps = st.swaps;
	out->underruns = st.underruns;
	out->bytes = st.bytes;
	struct proj_simdev_stats ds;
	proj_simdev_get_stats(((struct proj_sim *)p)->dev, &ds);
	out->angle_err_p50 = ds.angle_err_p50;
	out->angle_err_p99 = ds.angle_err_p99;
	out->angle_err_max = ds.angle_err_max;
	out->stalls = ds.stalls;
	out->max_dark_delay_ns = ds.max_dark_delay_ns;
	out->lit_stopped_ns = ds.lit_stopped_ns;
	out->lit_untimed_ns = ds.lit_untimed_ns;
	out->watchdog_blanks = ds.watchdog_blanks;
}
