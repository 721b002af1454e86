/* The emulated USB projector (see usb_emul.h): usbdevfs answered by the
 * device model. A URB's memory is the client's own (umockdev's handler
 * runs in this process), so the handler reads and completes URBs in place
 * while libusb waits in its ioctl for the answer. */
#include "usb_emul.h"

#include <dirent.h>
#include <errno.h>
#include <ftw.h>
#include <gio/gio.h>
#include <limits.h>
#include <linux/usbdevice_fs.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <umockdev.h>
#include <unistd.h>

#include "log.h"
#include "proj_sim_dev.h"
#include "projwire.h"
#include "sim_rotor.h"

#define MAX_URBS 64
#define SYS_PATH "/sys/devices/pci0000:00/usb1/1-2"
#define DEV_PATH "/dev/bus/usb/001/002"
#define WATCHDOG_NS 2000000000LL
#define EP_OUT 0x01
#define EP_IN 0x81

struct urb_fifo {
	struct usbdevfs_urb *urb[MAX_URBS];
	int n;
};

struct usb_emul {
	UMockdevTestbed *testbed;
	UMockdevIoctlBase *handler;
	pthread_mutex_t lock;
	GPtrArray *clients; /* device node opens umockdev may still serve */
	struct sim_rotor *rotor;
	struct proj_simdev *dev; /* NULL: unplugged */
	bool lit, attached;
	int64_t last_ctrl;
	struct urb_fifo out, in, done; /* bulk OUT and IN waiting; completed, to reap */
	uint8_t inject[256];
	size_t inject_len;
	struct usb_emul_stats st;
	usb_emul_node_rule *rule;
	void *rule_data;
	char node[PATH_MAX]; /* the node's file in the testbed */
};

static void fifo_push(struct urb_fifo *f, struct usbdevfs_urb *urb)
{
	if (f->n == MAX_URBS)
		abort(); /* the test's bug: more URBs than any driver should have */
	f->urb[f->n++] = urb;
}

static struct usbdevfs_urb *fifo_pop(struct urb_fifo *f)
{
	if (!f->n)
		return NULL;
	struct usbdevfs_urb *urb = f->urb[0];
	memmove(f->urb, f->urb + 1, (size_t)--f->n * sizeof(f->urb[0]));
	return urb;
}

static bool fifo_remove(struct urb_fifo *f, struct usbdevfs_urb *urb)
{
	for (int i = 0; i < f->n; i++) {
		if (f->urb[i] != urb)
			continue;
		memmove(f->urb + i, f->urb + i + 1, (size_t)(f->n - i - 1) * sizeof(f->urb[0]));
		f->n--;
		return true;
	}
	return false;
}

static void complete(struct usb_emul *e, struct usbdevfs_urb *urb, int status, int actual)
{
	urb->status = status;
	urb->actual_length = actual;
	fifo_push(&e->done, urb);
}

/* The firmware's 2 s watchdog, which the device model leaves out. */
static void watchdog(struct usb_emul *e, int64_t now, bool control)
{
	if (e->lit && now - e->last_ctrl > e->st.max_ctrl_gap_ns)
		e->st.max_ctrl_gap_ns = now - e->last_ctrl;
	if (e->lit && now - e->last_ctrl > WATCHDOG_NS) {
		uint8_t setup[PROJWIRE_SETUP_SIZE], data[PROJWIRE_CTRL_DATA_MAX], in[64];
		struct projwire_ctrl c = { .request = PROJWIRE_REQ_SET_BLANK, .blank = true };
		projwire_ctrl_encode(&c, 0, setup, data);
		proj_simdev_control(e->dev, setup, data, 0, in, sizeof(in));
		e->lit = false;
		e->st.watchdog_darkened++;
	}
	if (control)
		e->last_ctrl = now;
}

static void control_urb(struct usb_emul *e, struct usbdevfs_urb *urb)
{
	uint8_t *setup = urb->buffer;
	struct projwire_setup s;
	projwire_setup_decode(setup, &s);
	bool in = s.request_type & 0x80;
	watchdog(e, now_ns(), true);
	e->st.controls++;
	if (s.request == PROJWIRE_REQ_SWAP)
		e->st.swaps++;
	if (s.request == PROJWIRE_REQ_SWAP_HALF)
		e->st.swap_halves++;
	int r = proj_simdev_control(e->dev, setup, setup + 8, in ? 0 : s.length, setup + 8, s.length);
	if (r == -EPIPE) {
		e->st.stalls++;
		complete(e, urb, -EPIPE, 0);
		return;
	}
	if (s.request == PROJWIRE_REQ_SET_BLANK && s.request_type == PROJWIRE_RT_OUT && r >= 0)
		e->lit = s.value == 0;
	complete(e, urb, r < 0 ? -EPROTO : 0, r < 0 ? 0 : in ? r : s.length);
}

/* Work the device does between the host's reaps: one bulk OUT URB
 * through, revolution starts, events into waiting IN URBs. */
static void service(struct usb_emul *e)
{
	if (!e->dev)
		return;
	watchdog(e, now_ns(), false);
	struct usbdevfs_urb *urb;
	if (!e->done.n && (urb = fifo_pop(&e->out))) {
		proj_simdev_bulk_out(e->dev, urb->buffer, (size_t)urb->buffer_length);
		e->st.bulk_bytes += (uint64_t)urb->buffer_length;
		complete(e, urb, 0, urb->buffer_length);
	}
	proj_simdev_dispatch(e->dev);
	while (e->in.n) {
		urb = e->in.urb[0];
		size_t n = 0;
		if (e->inject_len && e->inject_len <= (size_t)urb->buffer_length) {
			memcpy(urb->buffer, e->inject, e->inject_len);
			n = e->inject_len;
			e->inject_len = 0;
		} else {
			n = proj_simdev_bulk_in(e->dev, urb->buffer, (size_t)urb->buffer_length);
		}
		if (!n)
			break;
		complete(e, fifo_pop(&e->in), 0, (int)n);
	}
}

static int submit(struct usb_emul *e, struct usbdevfs_urb *urb)
{
	if (!e->dev)
		return -ENODEV;
	if (urb->type == USBDEVFS_URB_TYPE_CONTROL && urb->buffer_length >= 8) {
		control_urb(e, urb);
	} else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == EP_OUT) {
		fifo_push(&e->out, urb);
		if (e->out.n > e->st.max_out_in_flight)
			e->st.max_out_in_flight = e->out.n;
	} else if ((urb->type == USBDEVFS_URB_TYPE_BULK || urb->type == USBDEVFS_URB_TYPE_INTERRUPT) &&
		   urb->endpoint == EP_IN) {
		fifo_push(&e->in, urb);
	} else {
		return -EINVAL;
	}
	e->st.urbs_outstanding++;
	return 0;
}

static int reap(struct usb_emul *e, struct usbdevfs_urb **where)
{
	service(e);
	struct usbdevfs_urb *urb = fifo_pop(&e->done);
	if (!urb)
		return e->dev ? -EAGAIN : -ENODEV;
	e->st.urbs_outstanding--;
	*where = urb;
	return 0;
}

static int discard(struct usb_emul *e, struct usbdevfs_urb *urb)
{
	/* Like the kernel: only a URB not yet completed can be unlinked. */
	if (!fifo_remove(&e->in, urb) && !fifo_remove(&e->out, urb))
		return -EINVAL;
	complete(e, urb, -ENOENT, 0);
	return 0;
}

static int usbdevfs(struct usb_emul *e, unsigned long request, void *arg)
{
	switch (request) {
	case USBDEVFS_GET_CAPABILITIES:
		*(uint32_t *)arg = USBDEVFS_CAP_ZERO_PACKET | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
				   USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
		return 0;
	case USBDEVFS_SUBMITURB:
		return submit(e, arg);
	case USBDEVFS_REAPURB:
	case USBDEVFS_REAPURBNDELAY:
		return reap(e, arg);
	case USBDEVFS_DISCARDURB:
		return discard(e, arg);
	case USBDEVFS_GETDRIVER:
	case USBDEVFS_IOCTL:
		return -ENODATA; /* no kernel driver bound */
	case USBDEVFS_CLAIMINTERFACE:
	case USBDEVFS_RELEASEINTERFACE:
	case USBDEVFS_DISCONNECT_CLAIM:
	case USBDEVFS_CLEAR_HALT:
	case USBDEVFS_RESETEP:
	case USBDEVFS_SETINTERFACE:
		return e->dev ? 0 : -ENODEV;
	}
	e->st.unknown_ioctls++;
	fprintf(stderr, "usb_emul: unhandled ioctl 0x%lx\n", request);
	return -ENOTTY;
}

static gboolean handle_ioctl(UMockdevIoctlBase *handler, UMockdevIoctlClient *client, gpointer data)
{
	struct usb_emul *e = data;
	UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
	void *ptr = *(void **)arg->data; /* the client's pointer: same address space */
	pthread_mutex_lock(&e->lock);
	int r = usbdevfs(e, umockdev_ioctl_client_get_request(client), ptr);
	pthread_mutex_unlock(&e->lock);
	if (r < 0)
		umockdev_ioctl_client_complete(client, -1, -r);
	else
		umockdev_ioctl_client_complete(client, r, 0);
	return TRUE;
}

/* umockdev serves each open of the device node on a socket of its own, in
 * its worker thread, and closes its end some time after the client closed
 * the node (the client then reads as not connected): these are the opens
 * it has served, until they are seen closed. */
static void on_client_connected(UMockdevIoctlBase *handler, UMockdevIoctlClient *client, gpointer data)
{
	struct usb_emul *e = data;
	pthread_mutex_lock(&e->lock);
	g_ptr_array_add(e->clients, g_object_ref(client));
	pthread_mutex_unlock(&e->lock);
}

/* Forgets the clients umockdev has closed; returns how many are left. */
static unsigned drop_closed(struct usb_emul *e)
{
	pthread_mutex_lock(&e->lock);
	for (unsigned i = e->clients->len; i-- > 0;) {
		if (!umockdev_ioctl_client_get_connected(g_ptr_array_index(e->clients, i)))
			g_ptr_array_remove_index_fast(e->clients, i);
	}
	unsigned left = e->clients->len;
	pthread_mutex_unlock(&e->lock);
	return left;
}

int usb_emul_wait_closed(struct usb_emul *e, int ms)
{
	int64_t deadline = now_ns() + (int64_t)ms * 1000000;
	unsigned left;
	while ((left = drop_closed(e)) > 0 && now_ns() < deadline) {
		struct timespec ts = { .tv_nsec = 1000000 };
		nanosleep(&ts, NULL);
	}
	return (int)left;
}

struct usb_emul *usb_emul_create(void)
{
	/* umockdev_in_mock_environment() says no under a plain LD_PRELOAD. */
	const char *preload = getenv("LD_PRELOAD");
	if (!preload || !strstr(preload, "umockdev-preload"))
		return NULL;
	struct usb_emul *e = calloc(1, sizeof(*e));
	if (!e)
		return NULL;
	pthread_mutex_init(&e->lock, NULL);
	e->clients = g_ptr_array_new_with_free_func(g_object_unref);
	e->rotor = sim_rotor_create(1800.0);
	/* GLib makes its worker context (an eventfd, which stays, and its thread
	 * "gmain") with the process's first GTask, and umockdev's worker thread
	 * makes one at its first accept on a node's socket, at a time of its
	 * own: perhaps after a test counted this process's fds with the
	 * testbed in place, which would then see one fd more at the end (one
	 * nobody leaked). Make it now, in this thread, before the testbed. */
	g_type_ensure(G_TYPE_TASK);
	e->testbed = umockdev_testbed_new();
	char *root = umockdev_testbed_get_root_dir(e->testbed);
	snprintf(e->node, sizeof(e->node), "%s%s", root, DEV_PATH);
	g_free(root);
	e->handler = umockdev_ioctl_base_new();
	g_signal_connect(e->handler, "handle-ioctl", G_CALLBACK(handle_ioctl), e);
	g_signal_connect(e->handler, "client-connected", G_CALLBACK(on_client_connected), e);
	return e;
}

void usb_emul_destroy(struct usb_emul *e)
{
	if (!e)
		return;
	usb_emul_unplug(e);
	g_object_unref(e->handler);
	g_object_unref(e->testbed);
	sim_rotor_destroy(e->rotor);
	pthread_mutex_destroy(&e->lock);
	g_ptr_array_unref(e->clients);
	free(e);
}

/* Device, configuration, interface (ff/53/01), bulk OUT 0x01, bulk IN 0x81;
 * VID 0x1209, PID 0x5350. */
static const char device_text[] =
	"P: /devices/pci0000:00/usb1/1-2\n"
	"N: bus/usb/001/002\n"
	"E: SUBSYSTEM=usb\n"
	"E: DEVTYPE=usb_device\n"
	"E: DRIVER=usb\n"
	"E: BUSNUM=001\n"
	"E: DEVNUM=002\n"
	"E: DEVNAME=" DEV_PATH "\n"
	"A: busnum=1\\n\n"
	"A: devnum=2\\n\n"
	"A: speed=480\\n\n"
	"A: bConfigurationValue=1\\n\n"
	"H: descriptors=12010002000000400912505300010000000109022000010100c032"
	"0904000002ff530100070501020002000705810200020000\n";

int usb_emul_plug(struct usb_emul *e, const struct geometry *geom, uint32_t buffers, uint8_t minor)
{
	struct proj_simdev *dev = proj_simdev_create(e->rotor, geom, buffers, 0);
	if (!dev)
		return -errno;
	proj_simdev_set_minor(dev, minor);
	pthread_mutex_lock(&e->lock);
	e->dev = dev;
	e->lit = false;
	e->inject_len = 0;
	e->st = (struct usb_emul_stats){ .urbs_outstanding = e->st.urbs_outstanding };
	pthread_mutex_unlock(&e->lock);
	/* The node answers ioctls before the add uevent announces it. */
	if (!e->attached && !umockdev_testbed_attach_ioctl(e->testbed, DEV_PATH, e->handler, NULL))
		return -EIO;
	e->attached = true;
	if (!umockdev_testbed_add_from_string(e->testbed, device_text, NULL))
		return -EIO;
	return e->rule ? usb_emul_apply_node_rule(e) : 0;
}

void usb_emul_unplug(struct usb_emul *e)
{
	struct usbdevfs_urb *urb;
	pthread_mutex_lock(&e->lock);
	struct proj_simdev *dev = e->dev;
	e->dev = NULL;
	while ((urb = fifo_pop(&e->out)))
		complete(e, urb, -ENODEV, 0);
	while ((urb = fifo_pop(&e->in)))
		complete(e, urb, -ENODEV, 0);
	pthread_mutex_unlock(&e->lock);
	if (!dev)
		return;
	proj_simdev_destroy(dev);
	umockdev_testbed_uevent(e->testbed, SYS_PATH, "remove");
	umockdev_testbed_remove_device(e->testbed, SYS_PATH);
}

void usb_emul_announce_again(struct usb_emul *e)
{
	umockdev_testbed_uevent(e->testbed, SYS_PATH, "add");
}

bool usb_emul_shows(struct usb_emul *e, const struct volume *vol)
{
	pthread_mutex_lock(&e->lock);
	const struct volume *shown = e->dev ? proj_simdev_shown(e->dev) : NULL;
	bool same = shown && shown->image_count == vol->image_count && shown->seq == vol->seq;
	for (uint32_t k = 0; same && k < vol->image_count; k++) {
		const struct volume_image *a = &shown->images[k], *b = &vol->images[k];
		same = a->tile_count == b->tile_count && !memcmp(a->mask, b->mask, vol->mask_bytes) &&
		       (!a->tile_count || !memcmp(a->tiles, b->tiles, (size_t)a->tile_count * VOLUME_TILE_BYTES));
	}
	pthread_mutex_unlock(&e->lock);
	return same;
}

bool usb_emul_lit(struct usb_emul *e)
{
	pthread_mutex_lock(&e->lock);
	bool lit = e->dev && e->lit;
	pthread_mutex_unlock(&e->lock);
	return lit;
}

void usb_emul_inject_event(struct usb_emul *e, const uint8_t *bytes, size_t len)
{
	pthread_mutex_lock(&e->lock);
	if (len <= sizeof(e->inject)) {
		memcpy(e->inject, bytes, len);
		e->inject_len = len;
	}
	pthread_mutex_unlock(&e->lock);
}

void usb_emul_set_minor(struct usb_emul *e, uint8_t minor)
{
	pthread_mutex_lock(&e->lock);
	if (e->dev)
		proj_simdev_set_minor(e->dev, minor);
	pthread_mutex_unlock(&e->lock);
}

const struct sim_rotor *usb_emul_rotor(const struct usb_emul *e)
{
	return e->rotor;
}

void usb_emul_get_stats(struct usb_emul *e, struct usb_emul_stats *out)
{
	pthread_mutex_lock(&e->lock);
	*out = e->st;
	pthread_mutex_unlock(&e->lock);
}

void usb_emul_set_node_rule(struct usb_emul *e, usb_emul_node_rule *rule, void *data)
{
	e->rule = rule;
	e->rule_data = data;
}

int usb_emul_apply_node_rule(struct usb_emul *e)
{
	pthread_mutex_lock(&e->lock);
	bool plugged = e->dev;
	pthread_mutex_unlock(&e->lock);
	if (!plugged)
		return -ENODEV;
	return e->rule ? e->rule(e->rule_data, e->node) : 0;
}

const char *usb_emul_node_path(const struct usb_emul *e)
{
	return e->node;
}

/* What chown_one() needs, as nftw() passes its callback no data: set for
 * the time of one walk. */
static struct {
	const struct usb_emul *e;
	uid_t uid;
	gid_t gid;
} chown_walk;

static int chown_one(const char *path, const struct stat *st, int type, struct FTW *ftw)
{
	if (!strcmp(path, chown_walk.e->node))
		return 0;
	return lchown(path, chown_walk.uid, chown_walk.gid) < 0 ? -errno : 0;
}

int usb_emul_chown_testbed(struct usb_emul *e, uid_t uid, gid_t gid)
{
	char *root = umockdev_testbed_get_root_dir(e->testbed);
	chown_walk.e = e;
	chown_walk.uid = uid;
	chown_walk.gid = gid;
	int r = nftw(root, chown_one, 16, FTW_PHYS);
	g_free(root);
	return r < 0 ? -errno : r;
}

/* Whether fd is a socket connected to the node's ioctl socket, which is
 * <root>/ioctl/dev/... (the preload library may double the slash). */
static bool ioctl_client(const struct usb_emul *e, int fd)
{
	struct sockaddr_un addr;
	socklen_t len = sizeof(addr);
	if (getpeername(fd, (struct sockaddr *)&addr, &len) < 0 || addr.sun_family != AF_UNIX ||
	    len <= offsetof(struct sockaddr_un, sun_path))
		return false;
	size_t n = strnlen(addr.sun_path, len - offsetof(struct sockaddr_un, sun_path));
	size_t root = strlen(e->node) - strlen(DEV_PATH), dev = strlen(DEV_PATH);
	return n > root + dev && !strncmp(addr.sun_path, e->node, root) &&
	       !strncmp(addr.sun_path + root, "/ioctl/", 7) && !memcmp(addr.sun_path + n - dev, DEV_PATH, dev);
}

int usb_emul_close_stray_sockets(struct usb_emul *e)
{
	DIR *d = opendir("/proc/self/fd");
	if (!d)
		return -errno;
	int stray[64], n = 0;
	struct dirent *de;
	while ((de = readdir(d)) && n < 64) {
		char *end;
		long fd = strtol(de->d_name, &end, 10);
		if (*end || end == de->d_name || fd == dirfd(d))
			continue;
		if (ioctl_client(e, (int)fd))
			stray[n++] = (int)fd;
	}
	closedir(d);
	for (int i = 0; i < n; i++)
		close(stray[i]);
	return n;
}
