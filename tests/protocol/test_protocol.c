/* The protocol test suite: spindled on the simulated device at the small
 * profile, driven through libspindle and raw sockets. Every expectation is
 * computed here from docs/design.md section 3. Usage: test-protocol NAME. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "harness.h"
#include "scenes.h"

/* ---- checks ---- */

static void check_disk(const struct volume *vol, double r, double y, int c)
{
	double inner = r * cos(M_PI / 64) - 0.01;
	for (uint32_t k = 0; k < NV; k++) {
		for (int u = col(-inner); u <= col(inner); u++)
			CHECK(lit_near(vol, k, u, row(y), c, 1));
		for (int v = 0; v < H; v++)
			for (int u = 0; u < W; u++)
				if (volume_pixel(vol, k, (uint32_t)u, (uint32_t)v, c))
					CHECK(abs(v - row(y)) <= 1 && u >= col(-r) - 1 && u <= col(r) + 1);
	}
}

static void test_device_info(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	const struct spindle_device_info *info = spindle_get_device_info(sp);
	CHECK(info->width == W && info->height == H && info->images_per_rev == 128 && info->mirrored);
	CHECK(info->half_height == 1.0f && info->rpm == 1800.0f);
	CHECK(spindle_get_version(sp) == SPINDLE_PROTOCOL_VERSION);
	/* The library run is the one built with these headers. */
	CHECK(strcmp(spindle_library_version(), SPINDLE_VERSION) == 0);
	char ver[32];
	snprintf(ver, sizeof(ver), "%d.%d.%d", SPINDLE_VERSION_MAJOR, SPINDLE_VERSION_MINOR, SPINDLE_VERSION_MICRO);
	CHECK(strcmp(ver, SPINDLE_VERSION) == 0);
	struct spindle_status st;
	CHECK(spindle_get_status(sp, &st) == 0);
	CHECK(st.clients == 1 && st.projector_present);
	CHECK(spindle_roundtrip(sp) == 0);
	/* Version 2 pushes the state at welcome. */
	struct spindle_state state;
	CHECK(spindle_get_state(sp, &state) == 0 && state.projector_present);
	/* An older client gets the older version, and no state. */
	struct spindle *old = spindle_connect_version(d.socket, 1);
	CHECK(old && spindle_get_version(old) == 1);
	CHECK(spindle_get_state(old, &state) == -ENOTSUP);
	CHECK(spindle_roundtrip(old) == 0);
	spindle_disconnect(old);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void test_axis_line(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	float v[6];
	show_vertices(sp, 1, v, axis_line(v), 255, 255, 255);
	check_shows_axis_line(sp);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void test_disk(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	float v[64 * 9];
	show_vertices(sp, 2, v, disk(v, 0.7, 0.3, 64), 255, 255, 255);
	struct volume *vol = capture_volume(sp);
	check_disk(vol, 0.7, 0.3, 1);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A sphere centred on the axis is edge-on to every image: each image must
 * show its full section circle anyway. */
static void test_sphere(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	const double r = 0.6, voxel = 2.0 / W, scale = test_calibration()->vertical_scale;
	static float v[48 * 24 * 18];
	show_vertices(sp, 2, v, sphere(v, r, 48, 24), 0, 0, 255);
	struct volume *vol = capture_volume(sp);
	for (uint32_t k = 0; k < NV; k++) {
		for (int i = 0; i < 720; i++) {
			double a = 2 * M_PI * i / 720;
			CHECK(lit_near(vol, k, col(r * cos(a)), row(r * sin(a)), 2, 1));
		}
		for (int y = 0; y < H; y++)
			for (int u = 0; u < W; u++) {
				if (!volume_pixel(vol, k, (uint32_t)u, (uint32_t)y, 2))
					continue;
				/* The distance in volume space, heights unscaled. */
				CHECK(fabs(hypot(col_s(u), row_y(y)) - r) <= 2.5 * voxel / fmin(scale, 1.0));
			}
	}
	CHECK(!lit_near(vol, 0, col(0), row(0), 0, 3)); /* red stays dark */
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A wall in the plane z = 0 lies in image 0's slice: filled there, only its
 * axis edge elsewhere. */
static void test_wall(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	const float a = 0.5f, b = 0.4f;
	float v[] = { -a, -b, 0, a, -b, 0, a, b, 0, -a, -b, 0, a, b, 0, -a, b, 0 };
	show_vertices(sp, 2, v, 6, 255, 255, 255);
	struct volume *vol = capture_volume(sp);
	for (int y = row(b); y <= row(-b); y++)
		for (int u = col(-a); u <= col(a); u++)
			CHECK(lit_near(vol, 0, u, y, 0, 1));
	for (uint32_t k = 2; k < NV - 1; k++)
		for (int y = 0; y < H; y++)
			for (int u = 0; u < W; u++)
				if (volume_pixel(vol, k, (uint32_t)u, (uint32_t)y, 0))
					CHECK(abs(u - col(0)) <= 1 && y >= row(b) - 1 && y <= row(-b) + 1);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* True when p is well inside its voxel and its image's wedge, so that the
 * expected voxel does not depend on rounding. */
static bool point_unambiguous(const struct geometry *g, double x, double y, double z)
{
	double p[3]; /* where the calibration puts it */
	calibrated_point(x, y, z, p);
	struct voxel e = expected_point(g, x, y, z);
	x = p[0], y = p[1], z = p[2];
	double phi = atan2(z, x), d = 2 * M_PI / g->images_per_rev;
	double f = phi / d - floor(phi / d);
	if (fabs(f - 0.5) < 0.05)
		return false;
	double th = geometry_image_angle(g, e.k);
	double s = x * cos(th) + z * sin(th);
	double fu = (s + 1) / 2 * g->width, fv = (1 - y) / 2 * g->height;
	return fabs(fu - round(fu)) > 0.05 && fabs(fv - round(fv)) > 0.05;
}

static void test_points(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct geometry g = small();
	enum { N = 400 };
	static float v[3 * N];
	static struct voxel e[N];
	srand(7);
	for (int i = 0; i < N;) {
		double r = 0.9 * sqrt(rand() / (double)RAND_MAX), a = 2 * M_PI * rand() / (double)RAND_MAX;
		double x = r * cos(a), z = r * sin(a), y = 1.8 * rand() / (double)RAND_MAX - 0.9;
		if (!point_unambiguous(&g, (float)x, (float)y, (float)z))
			continue;
		v[3 * i] = (float)x, v[3 * i + 1] = (float)y, v[3 * i + 2] = (float)z;
		e[i] = expected_point(&g, v[3 * i], v[3 * i + 1], v[3 * i + 2]);
		i++;
	}
	show_vertices(sp, 0, v, N, 0, 255, 0);
	struct volume *vol = capture_volume(sp);
	for (int i = 0; i < N; i++)
		CHECK(volume_pixel(vol, e[i].k, e[i].u, e[i].v, 1));
	/* Nothing else: each lit voxel is some point's voxel. */
	uint64_t lit = 0, distinct = 0;
	for (uint32_t k = 0; k < NV; k++)
		for (uint32_t y = 0; y < H; y++)
			for (uint32_t u = 0; u < W; u++)
				lit += volume_pixel(vol, k, u, y, 1);
	for (int i = 0; i < N; i++) {
		bool dup = false;
		for (int j = 0; j < i && !dup; j++)
			dup = !memcmp(&e[i], &e[j], sizeof(e[i]));
		distinct += !dup;
	}
	CHECK(lit == distinct);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void show_pair(struct daemon *d, struct spindle **a, struct spindle **b)
{
	static float line[6], fan[64 * 9];
	*a = client_connect(d);
	*b = client_connect(d);
	show_vertices(*a, 1, line, axis_line(line), 255, 0, 0);
	show_vertices(*b, 2, fan, disk(fan, 0.7, 0.3, 64), 0, 255, 0);
}

static void test_two_clients(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *a, *b;
	show_pair(&d, &a, &b);
	struct volume *vol = capture_volume(b);
	check_axis_line(vol, 0);
	check_disk(vol, 0.7, 0.3, 1);
	CHECK(!lit_near(vol, 5, col(0), row(0.3), 2, 3)); /* no blue anywhere */
	volume_destroy(vol);
	spindle_disconnect(a);
	spindle_disconnect(b);
	daemon_stop(&d);
}

/* Waits for a volume without red, i.e. without the departed client. */
static struct volume *capture_until_no_red(struct spindle *sp)
{
	for (int i = 0; i < 100; i++) {
		struct volume *vol = capture_volume(sp);
		if (count_lit(vol, 0) == 0)
			return vol;
		volume_destroy(vol);
	}
	return NULL;
}

static void test_client_leaves(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *a, *b;
	show_pair(&d, &a, &b);
	struct volume *before = capture_volume(b);
	CHECK(count_lit(before, 0) > 0);
	spindle_disconnect(a);
	struct volume *after = capture_until_no_red(b);
	CHECK(after != NULL);
	CHECK(count_lit(after, 1) == count_lit(before, 1));
	check_disk(after, 0.7, 0.3, 1);
	struct spindle_status st;
	CHECK(spindle_get_status(b, &st) == 0 && st.clients == 1);
	volume_destroy(before);
	volume_destroy(after);
	spindle_disconnect(b);
	daemon_stop(&d);
}

/* A bad client is cut off with an error; the good one never notices. */
static void test_garbage(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *good = client_connect(&d);
	float fan[64 * 9];
	show_vertices(good, 2, fan, disk(fan, 0.7, 0.3, 64), 0, 255, 0);
	int fds_before = daemon_fd_count(&d);

	int fd = raw_connect(&d);
	uint8_t junk[64];
	for (size_t i = 0; i < sizeof(junk); i++)
		junk[i] = (uint8_t)(i * 37 + 11);
	CHECK(send(fd, junk, sizeof(junk), MSG_NOSIGNAL) == sizeof(junk));
	CHECK(raw_expect_error_and_close(fd, 0));
	close(fd);

	uint32_t version = 1;
	fd = raw_connect(&d);
	CHECK(raw_send(fd, 1, 0, &version, 4) == 0);
	CHECK(raw_send(fd, 1, 99, NULL, 0) == 0);
	CHECK(raw_expect_error_and_close(fd, 2)); /* invalid_method */
	close(fd);

	fd = raw_connect(&d);
	CHECK(raw_send(fd, 1, 0, &version, 4) == 0);
	CHECK(raw_send(fd, 77, 0, NULL, 0) == 0);
	CHECK(raw_expect_error_and_close(fd, 1)); /* invalid_object */
	close(fd);

	fd = raw_connect(&d);
	CHECK(raw_send(fd, 1, 6, NULL, 0) == 0);  /* commit before hello */
	CHECK(raw_expect_error_and_close(fd, 7)); /* version */
	close(fd);

	/* The good client is still served, its volume intact. */
	CHECK(spindle_commit_and_wait(good, NULL) == 0);
	struct volume *vol = capture_volume(good);
	check_disk(vol, 0.7, 0.3, 1);
	volume_destroy(vol);
	struct spindle_status st;
	CHECK(spindle_get_status(good, &st) == 0 && st.clients == 1);
	CHECK(daemon_fd_count(&d) == fds_before);
	spindle_disconnect(good);
	daemon_stop(&d);
}

/* A draw past the end of its buffer is a fatal error for that client. */
static void test_draw_out_of_range(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	float v[6] = { 0 };
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, sizeof(v));
	struct spindle_list *list = spindle_list_create(sp);
	CHECK(buf && list);
	CHECK(spindle_list_lines(list, buf, 0, 4, 0) == 0); /* 4 vertices, buffer holds 2 */
	CHECK(spindle_roundtrip(sp) == -EPIPE);
	CHECK(strstr(spindle_get_error(sp), "past the end") != NULL);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* create_buffer with a memfd that is not sealed is refused. */
static void test_unsealed_memfd(void)
{
	struct daemon d;
	daemon_start(&d);
	int fd = raw_connect(&d);
	uint32_t version = 1;
	CHECK(raw_send(fd, 1, 0, &version, 4) == 0);
	int mfd = memfd_create("unsealed", MFD_CLOEXEC);
	CHECK(ftruncate(mfd, 4096) == 0);
	uint8_t msg[24];
	uint32_t obj = 1, size = 24, id = 2;
	uint16_t op = 2, nfds = 1;
	uint64_t bytes = 4096;
	memcpy(msg, &obj, 4), memcpy(msg + 4, &op, 2), memcpy(msg + 6, &nfds, 2), memcpy(msg + 8, &size, 4);
	memcpy(msg + 12, &id, 4), memcpy(msg + 16, &bytes, 8);
	union {
		char buf[CMSG_SPACE(sizeof(int))];
		struct cmsghdr align;
	} ctl;
	struct iovec iov = { msg, sizeof(msg) };
	struct msghdr mh = { .msg_iov = &iov,
			     .msg_iovlen = 1,
			     .msg_control = ctl.buf,
			     .msg_controllen = sizeof(ctl.buf) };
	struct cmsghdr *c = CMSG_FIRSTHDR(&mh);
	c->cmsg_level = SOL_SOCKET, c->cmsg_type = SCM_RIGHTS, c->cmsg_len = CMSG_LEN(sizeof(int));
	memcpy(CMSG_DATA(c), &mfd, sizeof(int));
	CHECK(sendmsg(fd, &mh, MSG_NOSIGNAL) == sizeof(msg));
	CHECK(raw_expect_error_and_close(fd, 5)); /* bad_fd */
	close(fd);
	close(mfd);
	daemon_stop(&d);
}

/* List and layer transforms, visibility, and commit being atomic. */
static void test_layers(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	float v[6];
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, axis_line(v) * 12);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	CHECK(buf && list && layer);
	const float half_y[16] = { 1, 0, 0, 0, 0, 0.5f, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
	CHECK(spindle_list_set_transform(list, half_y) == 0);
	CHECK(spindle_list_lines(list, buf, 0, 2, 0) == 0);
	CHECK(spindle_layer_set_list(layer, list) == 0);
	CHECK(spindle_commit_and_wait(sp, NULL) == 0);
	struct volume *vol = capture_volume(sp);
	for (uint32_t k = 0; k < NV; k++) {
		CHECK(lit_near(vol, k, col(0), row(0.29), 0, 1) && lit_near(vol, k, col(0), row(-0.29), 0, 1));
		CHECK(!lit_near(vol, k, col(0), row(0.4), 0, 1) && !lit_near(vol, k, col(0), row(-0.4), 0, 1));
	}
	volume_destroy(vol);

	CHECK(spindle_layer_set_visible(layer, false) == 0);
	CHECK(spindle_commit_and_wait(sp, NULL) == 0);
	vol = capture_volume(sp);
	CHECK(count_lit(vol, 0) + count_lit(vol, 1) + count_lit(vol, 2) == 0);
	volume_destroy(vol);

	/* Pending changes show nothing until the commit, then all at once. */
	const float shift_x[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5f, 0, 0, 1 };
	CHECK(spindle_layer_set_visible(layer, true) == 0);
	CHECK(spindle_layer_set_transform(layer, shift_x) == 0);
	CHECK(spindle_roundtrip(sp) == 0);
	vol = capture_volume(sp);
	CHECK(count_lit(vol, 0) == 0);
	volume_destroy(vol);
	CHECK(spindle_commit_and_wait(sp, NULL) == 0);
	vol = capture_volume(sp);
	for (double y = -0.28; y <= 0.28; y += 0.01)
		CHECK(lit_near(vol, 0, col(0.5), row(y), 0, 1));
	for (uint32_t k = 2; k < NV - 1; k++)
		CHECK(count_lit_image(vol, k, 0) == 0);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A client that asks for events and never reads them is cut off once its
 * queue is full; the daemon does not stall and the others are served. */
static void test_slow_reader(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *good = client_connect(&d);
	int fd = raw_connect(&d);
	uint32_t version = 1;
	CHECK(raw_send(fd, 1, 0, &version, 4) == 0);
	uint8_t req[12 * 256];
	for (int i = 0; i < 256; i++) {
		uint32_t obj = 1, size = 12;
		uint16_t op = 7, nfds = 0; /* display.get_status */
		memcpy(req + 12 * i, &obj, 4), memcpy(req + 12 * i + 4, &op, 2);
		memcpy(req + 12 * i + 6, &nfds, 2), memcpy(req + 12 * i + 8, &size, 4);
	}
	bool cut_off = false;
	for (int i = 0; i < 4000 && !cut_off; i++) {
		if (send(fd, req, sizeof(req), MSG_NOSIGNAL) < 0)
			cut_off = errno == EPIPE || errno == ECONNRESET;
		struct spindle_status st;
		if (i % 100 == 0)
			CHECK(spindle_get_status(good, &st) == 0);
	}
	CHECK(cut_off);
	struct spindle_status st;
	CHECK(spindle_get_status(good, &st) == 0 && st.clients == 1);
	close(fd);
	spindle_disconnect(good);
	daemon_stop(&d);
}

/* A sphere (blue) on one layer, shown. */
static struct spindle_layer *show_sphere(struct spindle *sp, struct spindle_frame *frame)
{
	static float v[48 * 24 * 18];
	uint32_t n = sphere(v, 0.6, 48, 24);
	return show_triangles(sp, frame, v, n, 0, 0, 255);
}

/* Frames of changed commits: each is a new volume, shown later. */
static void test_frames(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct spindle_frame prev, f;
	struct spindle_layer *layer = show_sphere(sp, &prev);
	for (int i = 1; i <= 5; i++) {
		float m[16];
		shift_x(m, 0.01f * (float)i);
		CHECK(spindle_layer_set_transform(layer, m) == 0);
		CHECK(spindle_commit_and_wait(sp, &f) == 0);
		CHECK(f.volume_seq > prev.volume_seq && f.time_ns > prev.time_ns);
		uint64_t now = mono_ns();
		CHECK(f.time_ns <= now && now - f.time_ns < 2000000000u);
		prev = f;
	}
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* Frame callbacks answered asynchronously, in the order they came. */
struct frame_log {
	struct spindle_frame frame[4];
	int order[4];
	int arrived;
};

struct frame_slot {
	struct frame_log *log;
	int index;
};

static void log_frame(void *data, const struct spindle_frame *frame)
{
	struct frame_slot *slot = data;
	slot->log->frame[slot->index] = *frame;
	slot->log->order[slot->log->arrived++] = slot->index;
}

static void wait_frames(struct spindle *sp, struct frame_log *log, int n)
{
	uint64_t deadline = mono_ns() + 5000000000u;
	while (log->arrived < n) {
		CHECK(mono_ns() < deadline);
		CHECK(spindle_flush(sp) == 0);
		struct pollfd p = { spindle_get_fd(sp), POLLIN, 0 };
		CHECK(poll(&p, 1, 100) >= 0);
		CHECK(spindle_dispatch(sp) >= 0);
	}
}

/* Commits that change nothing render and upload nothing, yet their frame
 * callbacks are answered by the volume on display, at the first revolution
 * start after the commit. */
static void check_unchanged_commits(struct spindle *sp, const struct spindle_frame *shown)
{
	struct spindle_status before = status_of(sp);
	struct spindle_frame prev = *shown, f;
	for (int i = 0; i < 10; i++) {
		uint64_t committed = mono_ns();
		CHECK(spindle_commit_and_wait(sp, &f) == 0);
		CHECK_EQ(f.volume_seq, shown->volume_seq);
		CHECK(f.time_ns >= committed && f.time_ns > prev.time_ns && f.time_ns <= mono_ns());
		prev = f;
	}
	struct spindle_status after = status_of(sp);
	CHECK_EQ(after.volumes_rendered, before.volumes_rendered);
	CHECK_EQ(after.bytes_uploaded, before.bytes_uploaded);
	CHECK_EQ(after.volumes_skipped, before.volumes_skipped + 10);
}

/* A changed commit renders exactly one volume and uploads it. */
static struct spindle_frame check_changed_commit(struct spindle *sp, struct spindle_layer *layer, float dx,
						 const struct spindle_frame *prev)
{
	struct spindle_status before = status_of(sp);
	float m[16];
	shift_x(m, dx);
	CHECK(spindle_layer_set_transform(layer, m) == 0);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	CHECK(f.volume_seq > prev->volume_seq && f.time_ns > prev->time_ns);
	struct spindle_status after = status_of(sp);
	CHECK_EQ(after.volumes_rendered, before.volumes_rendered + 1);
	CHECK(after.bytes_uploaded > before.bytes_uploaded && after.render_us > 0);
	return f;
}

/* A changed commit A, then B, identical, sent while A renders: B is
 * answered with A's volume, not before A's volume is shown. */
static void check_commit_while_rendering(struct spindle *sp, struct spindle_layer *layer)
{
	struct spindle_status before = status_of(sp);
	struct frame_log log = { .arrived = 0 };
	struct frame_slot a = { &log, 0 }, b = { &log, 1 };
	float m[16];
	shift_x(m, 0.1f);
	CHECK(spindle_layer_set_transform(layer, m) == 0);
	uint64_t committed = mono_ns();
	CHECK(spindle_request_frame(sp, log_frame, &a) == 0 && spindle_commit(sp) == 0);
	CHECK(spindle_request_frame(sp, log_frame, &b) == 0 && spindle_commit(sp) == 0);
	wait_frames(sp, &log, 2);
	CHECK(log.order[0] == 0 && log.order[1] == 1);
	CHECK_EQ(log.frame[1].volume_seq, log.frame[0].volume_seq);
	CHECK(log.frame[0].time_ns >= committed && log.frame[1].time_ns >= log.frame[0].time_ns);
	struct spindle_status after = status_of(sp);
	CHECK_EQ(after.volumes_rendered, before.volumes_rendered + 1);
	/* The second commit's scene is compared (skipped) when the first
	 * render had started; when the render waited for its start time both
	 * commits went into one scene. */
	CHECK(after.volumes_skipped <= before.volumes_skipped + 1);
	CHECK(after.volumes_shown > before.volumes_shown);
}

static void test_unchanged(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct spindle_frame shown;
	struct spindle_layer *layer = show_sphere(sp, &shown);
	check_unchanged_commits(sp, &shown);
	shown = check_changed_commit(sp, layer, 0.05f, &shown);
	check_unchanged_commits(sp, &shown);
	check_commit_while_rendering(sp, layer);
	/* The volume shown is still the scene's: a sphere, nothing else. */
	struct volume *vol = capture_volume(sp);
	CHECK(count_lit(vol, 2) > 0 && count_lit(vol, 0) == 0);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* Commits a change and checks that it rendered one new volume. */
static struct spindle_frame commit_rendered(struct spindle *sp, const struct spindle_frame *prev)
{
	struct spindle_status before = status_of(sp);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	CHECK(f.volume_seq > prev->volume_seq);
	CHECK_EQ(status_of(sp).volumes_rendered, before.volumes_rendered + 1);
	return f;
}

/* A scene changed back and forth is rendered every time: the identity check
 * is against the last volume rendered, not any older one. */
static void test_back_and_forth(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	/* Two lists alike but for their vertices: the axis, and a line off it. */
	float axis[6], off[6];
	axis_line(axis), axis_line(off);
	off[0] = off[3] = 0.5f;
	struct spindle_buffer *ab = spindle_buffer_create(sp, axis, sizeof(axis));
	struct spindle_buffer *ob = spindle_buffer_create(sp, off, sizeof(off));
	struct spindle_list *a = spindle_list_create(sp), *b = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	CHECK(ab && ob && a && b && layer);
	CHECK(spindle_list_lines(a, ab, 0, 2, 0) == 0 && spindle_list_lines(b, ob, 0, 2, 0) == 0);
	struct spindle_frame f = { 0 };
	for (int i = 0; i < 3; i++) {
		CHECK(spindle_layer_set_list(layer, i % 2 ? b : a) == 0);
		f = commit_rendered(sp, &f);
	}
	check_shows_axis_line(sp);
	/* The same with a layer transform and with visibility. */
	float m[16];
	shift_x(m, 0.2f);
	for (int i = 0; i < 3; i++) {
		CHECK(spindle_layer_set_transform(layer, i % 2 ? identity : m) == 0);
		f = commit_rendered(sp, &f);
	}
	for (int i = 0; i < 3; i++) {
		CHECK(spindle_layer_set_visible(layer, i % 2) == 0);
		f = commit_rendered(sp, &f);
	}
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* ---- GL renderer failures (SPINDLE_GL_FAULT, see gl_context.h) ---- */

/* A green disk (r 0.7 at y 0.3) on its own layer, committed and shown. */
static struct spindle_layer *show_disk(struct spindle *sp, struct spindle_frame *frame)
{
	static float v[64 * 9];
	uint32_t n = disk(v, 0.7, 0.3, 64);
	return show_triangles(sp, frame, v, n, 0, 255, 0);
}

/* The GL context is lost after the first volume (SPINDLE_GL_FAULT=lost):
 * the daemon says so, renders on the CPU from then on, and every changed
 * commit is still rendered, shown (its frame callback arrives with a newer
 * volume) and right (the CPU renderer's exact disk). */
static void test_gl_lost(const char *backend)
{
	CHECK(setenv("SPINDLE_GL_FAULT", "lost", 1) == 0);
	struct daemon d;
	daemon_start_renderer(&d, backend);
	daemon_require_renderer(&d, backend);
	struct spindle *sp = client_connect(&d);
	struct spindle_frame prev, f;
	struct spindle_layer *layer = show_disk(sp, &prev); /* rendered on GL */
	CHECK(!daemon_log_contains(&d, "falling back"));
	for (int i = 1; i <= 6; i++) {
		double y = 0.3 - 0.1 * i;
		float m[16];
		memcpy(m, identity, sizeof(m));
		m[13] = (float)(y - 0.3);
		struct spindle_status before = status_of(sp);
		CHECK(spindle_layer_set_transform(layer, m) == 0);
		CHECK(spindle_commit_and_wait(sp, &f) == 0);
		CHECK(f.volume_seq > prev.volume_seq && f.time_ns > prev.time_ns);
		CHECK_EQ(status_of(sp).volumes_rendered, before.volumes_rendered + 1);
		struct volume *vol = capture_volume(sp);
		check_disk(vol, 0.7, y, 1);
		CHECK(count_lit(vol, 0) == 0 && count_lit(vol, 2) == 0);
		volume_destroy(vol);
		prev = f;
	}
	CHECK(daemon_log_contains(&d, "context lost"));
	char line[80];
	snprintf(line, sizeof(line), "GL renderer (%s) failed", backend);
	CHECK(daemon_log_contains(&d, line));
	CHECK(daemon_log_contains(&d, "falling back to the CPU renderer"));
	CHECK(daemon_alive(&d));
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void test_gl_lost_egl(void)
{
	test_gl_lost("egl");
}

static void test_gl_lost_osmesa(void)
{
	test_gl_lost("osmesa");
}

/* No GL at start (fault: no display, or shaders that do not compile): the
 * daemon warns, starts on the CPU renderer and serves. */
static void test_gl_unavailable(const char *fault, const char *why)
{
	CHECK(setenv("SPINDLE_GL_FAULT", fault, 1) == 0);
	struct daemon d;
	daemon_start_renderer(&d, "egl");
	CHECK(daemon_log_contains(&d, why));
	CHECK(daemon_log_contains(&d, "warning: renderer 'egl' unavailable"));
	CHECK(daemon_log_contains(&d, "using the CPU renderer"));
	CHECK(daemon_log_contains(&d, "renderer: cpu\n"));
	struct spindle *sp = client_connect(&d);
	struct spindle_frame f;
	show_disk(sp, &f);
	struct volume *vol = capture_volume(sp);
	check_disk(vol, 0.7, 0.3, 1);
	volume_destroy(vol);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void test_gl_no_display(void)
{
	test_gl_unavailable("display", "no egl display (fault injected");
}

static void test_gl_bad_shader(void)
{
	test_gl_unavailable("shader", "shader does not compile");
}

/* A capture on a display that has shown nothing is answered at once with
 * the empty volume: while it is still dark (the simulated rotor spinning
 * up, no timing yet) and once it is lit with an empty scene. */
static void test_capture_empty(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	for (int lit = 0; lit < 2; lit++) {
		int r = lit ? spindle_commit_and_wait(sp, NULL) : 0; /* answered once shown lit */
		if (r < 0) {
			printf("commit_and_wait: %s (%s); the daemon's log:\n", strerror(-r),
			       spindle_get_error(sp) ? spindle_get_error(sp) : "no daemon error");
			daemon_print_log(&d);
		}
		CHECK(r == 0);
		struct timespec t0, t1;
		clock_gettime(CLOCK_MONOTONIC, &t0);
		struct volume *vol = capture_volume(sp);
		clock_gettime(CLOCK_MONOTONIC, &t1);
		double s = (double)(t1.tv_sec - t0.tv_sec) + (double)(t1.tv_nsec - t0.tv_nsec) / 1e9;
		printf("capture %s: %llu tiles in %.3f s\n", lit ? "lit" : "dark",
		       (unsigned long long)volume_tile_count(vol), s);
		CHECK(volume_tile_count(vol) == 0);
		CHECK(s < 2.0); /* a state timer period or a revolution, with room for a loaded machine */
		volume_destroy(vol);
	}
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static const struct named_test tests[] = {
	{ "capture-empty", test_capture_empty },
	{ "device-info", test_device_info },
	{ "axis-line", test_axis_line },
	{ "disk", test_disk },
	{ "sphere", test_sphere },
	{ "wall", test_wall },
	{ "points", test_points },
	{ "two-clients", test_two_clients },
	{ "client-leaves", test_client_leaves },
	{ "garbage", test_garbage },
	{ "draw-out-of-range", test_draw_out_of_range },
	{ "unsealed-memfd", test_unsealed_memfd },
	{ "frames", test_frames },
	{ "slow-reader", test_slow_reader },
	{ "layers", test_layers },
	{ "unchanged", test_unchanged },
	{ "back-and-forth", test_back_and_forth },
	{ "gl-lost-egl", test_gl_lost_egl },
	{ "gl-lost-osmesa", test_gl_lost_osmesa },
	{ "gl-no-display", test_gl_no_display },
	{ "gl-bad-shader", test_gl_bad_shader },
};

int main(int argc, char **argv)
{
	return run_named_tests(tests, sizeof(tests) / sizeof(tests[0]), argc, argv);
}
