/* The protocol test suite: spindled on the simulated device at the small
 * profile, driven through libspindle and raw sockets. Every expectation is
 * computed here from DESIGN.md section 3. Usage: test-protocol NAME. */
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
#include "projwire.h"

#define W 128
#define H 128
#define NV 64 /* images per volume: N = 128, mirrored */

static struct geometry small(void)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	return g;
}

static int col(double s)
{
	struct geometry g = small();
	return (int)geometry_column(&g, s);
}

static int row(double y)
{
	struct geometry g = small();
	return (int)geometry_row(&g, y);
}

/* ---- shapes ---- */

static uint32_t axis_line(float *v)
{
	const float p[] = { 0, -0.6f, 0, 0, 0.6f, 0 };
	memcpy(v, p, sizeof(p));
	return 2;
}

static uint32_t disk(float *v, double r, double y, int segs)
{
	uint32_t n = 0;
	for (int i = 0; i < segs; i++) {
		double a0 = 2 * M_PI * i / segs, a1 = 2 * M_PI * (i + 1) / segs;
		float t[] = { 0, (float)y, 0, (float)(r * cos(a0)), (float)y, (float)(r * sin(a0)),
			      (float)(r * cos(a1)), (float)y, (float)(r * sin(a1)) };
		memcpy(v + 3 * n, t, sizeof(t));
		n += 3;
	}
	return n;
}

static void sphere_point(float *out, double r, int i, int j, int slices, int stacks)
{
	double th = M_PI * j / stacks, ph = 2 * M_PI * i / slices;
	out[0] = (float)(r * sin(th) * cos(ph));
	out[1] = (float)(r * cos(th));
	out[2] = (float)(r * sin(th) * sin(ph));
}

static uint32_t sphere(float *v, double r, int slices, int stacks)
{
	uint32_t n = 0;
	for (int j = 0; j < stacks; j++)
		for (int i = 0; i < slices; i++) {
			float a[3], b[3], c[3], d[3];
			sphere_point(a, r, i, j, slices, stacks);
			sphere_point(b, r, i + 1, j, slices, stacks);
			sphere_point(c, r, i + 1, j + 1, slices, stacks);
			sphere_point(d, r, i, j + 1, slices, stacks);
			float *t = v + 3 * n;
			memcpy(t, a, 12), memcpy(t + 3, b, 12), memcpy(t + 6, c, 12);
			memcpy(t + 9, a, 12), memcpy(t + 12, c, 12), memcpy(t + 15, d, 12);
			n += 6;
		}
	return n;
}

/* ---- checks ---- */

static void check_axis_line(const struct volume *vol, int c)
{
	int top = row(0.6), bottom = row(-0.6);
	for (uint32_t k = 0; k < NV; k++) {
		for (int v = top; v <= bottom; v++)
			CHECK(lit_near(vol, k, col(0), v, c, 1));
		for (int v = 0; v < H; v++)
			for (int u = 0; u < W; u++)
				if (volume_pixel(vol, k, (uint32_t)u, (uint32_t)v, c))
					CHECK(abs(u - col(0)) <= 1 && v >= top - 1 && v <= bottom + 1);
	}
}

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
	CHECK(spindle_get_version(sp) == 1);
	struct spindle_status st;
	CHECK(spindle_get_status(sp, &st) == 0);
	CHECK(st.clients == 1 && st.projector_present);
	CHECK(spindle_roundtrip(sp) == 0);
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
	struct volume *vol = capture_volume(sp);
	for (int c = 0; c < 3; c++)
		check_axis_line(vol, c);
	volume_destroy(vol);
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
	const double r = 0.6, voxel = 2.0 / W;
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
				double s = (u + 0.5) * voxel - 1, yy = 1 - (y + 0.5) * voxel;
				CHECK(fabs(hypot(s, yy) - r) <= 2.5 * voxel);
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
	double phi = atan2(z, x), d = 2 * M_PI / g->images_per_rev;
	double f = phi / d - floor(phi / d);
	if (fabs(f - 0.5) < 0.05)
		return false;
	struct voxel e = expected_point(g, x, y, z);
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

static uint64_t count_lit_image(const struct volume *vol, uint32_t k, int c)
{
	uint64_t n = 0;
	for (uint32_t y = 0; y < H; y++)
		for (uint32_t u = 0; u < W; u++)
			n += volume_pixel(vol, k, u, y, c);
	return n;
}

static uint64_t count_lit(const struct volume *vol, int c)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < vol->image_count; k++)
		n += count_lit_image(vol, k, c);
	return n;
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
	CHECK(raw_send(fd, 1, 6, NULL, 0) == 0); /* commit before hello */
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
	struct msghdr mh = { .msg_iov = &iov, .msg_iovlen = 1, .msg_control = ctl.buf,
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

static uint64_t mono_ns(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };

/* Identity moved by dx along x. */
static void shift_x(float m[16], float dx)
{
	memcpy(m, identity, sizeof(identity));
	m[12] = dx;
}

/* n triangle vertices v in one colour on a layer of their own, committed
 * and shown; frame says by which volume. */
static struct spindle_layer *show_triangles(struct spindle *sp, struct spindle_frame *frame, const float *v,
					    uint32_t n, uint8_t r, uint8_t g, uint8_t b)
{
	struct spindle_buffer *buf = spindle_buffer_create(sp, v, (size_t)n * 12);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	CHECK(buf && list && layer);
	CHECK(spindle_list_set_color(list, r, g, b, 255) == 0);
	CHECK(spindle_list_triangles(list, buf, 0, n, 0) == 0);
	CHECK(spindle_layer_set_list(layer, list) == 0);
	CHECK(spindle_commit_and_wait(sp, frame) == 0);
	CHECK(frame->volume_seq > 0 && frame->time_ns > 0);
	return layer;
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

static struct spindle_status status_of(struct spindle *sp)
{
	struct spindle_status st;
	CHECK(spindle_get_status(sp, &st) == 0);
	return st;
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
	CHECK_EQ(after.volumes_skipped, before.volumes_skipped + 1);
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
	struct volume *vol = capture_volume(sp);
	for (int c = 0; c < 3; c++)
		check_axis_line(vol, c);
	volume_destroy(vol);
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

/* ---- pacing and uploads to the projector ---- */

/* Tiles present in a or b whose content differs between them. */
static uint64_t tiles_changed(const struct volume *a, const struct volume *b)
{
	uint64_t n = 0;
	for (uint32_t k = 0; k < a->image_count; k++) {
		const struct volume_image *x = &a->images[k], *y = &b->images[k];
		const uint8_t *px = x->tiles, *py = y->tiles;
		for (uint32_t t = 0; t < volume_tiles_per_image(a); t++) {
			int ix = volume_tile_present(x, t), iy = volume_tile_present(y, t);
			n += (ix || iy) && (ix != iy || memcmp(px, py, VOLUME_TILE_BYTES));
			px += ix ? VOLUME_TILE_BYTES : 0;
			py += iy ? VOLUME_TILE_BYTES : 0;
		}
	}
	return n;
}

/* A small sphere moving past a large one: each volume is sent as a delta
 * against the free buffer's content, the volume two back, and costs
 * exactly the projector protocol's delta of the two (computed here from
 * captures); about as large a share of the whole as the share of tiles
 * that changed. An unchanged scene sends nothing. */
static void test_delta(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	static float big[48 * 24 * 18], ball[24 * 12 * 18];
	struct spindle_frame f;
	show_triangles(sp, &f, big, sphere(big, 0.85, 48, 24), 0, 0, 255);
	struct spindle_layer *layer = show_triangles(sp, &f, ball, sphere(ball, 0.16, 24, 12), 255, 0, 0);
	struct volume *shown[8];
	for (int i = 0; i < 8; i++) {
		struct spindle_status before = status_of(sp);
		float m[16];
		shift_x(m, 0.1f + 0.08f * (float)i);
		CHECK(spindle_layer_set_transform(layer, m) == 0);
		CHECK(spindle_commit_and_wait(sp, &f) == 0);
		shown[i] = capture_volume(sp);
		uint64_t sent = status_of(sp).bytes_uploaded - before.bytes_uploaded;
		if (i < 3)
			continue; /* until every buffer holds a volume of this scene */
		const struct volume *base = shown[i - 2];
		size_t whole = projwire_volume_size(shown[i]);
		bool delta;
		CHECK_EQ(sent, projwire_upload_size(shown[i], base, &delta));
		CHECK(delta);
		double tiles = (double)tiles_changed(shown[i], base) / (double)volume_tile_count(shown[i]);
		double bytes = (double)sent / (double)whole;
		printf("volume %d: %.1f%% of %llu tiles changed, %llu of %zu bytes sent (%.1f%%)\n", i, 100 * tiles,
		       (unsigned long long)volume_tile_count(shown[i]), (unsigned long long)sent, whole, 100 * bytes);
		CHECK(tiles > 0.05 && tiles < 0.2);
		CHECK(bytes < tiles * 1.1 + 0.01);
	}
	struct spindle_status before = status_of(sp);
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	CHECK_EQ(status_of(sp).bytes_uploaded, before.bytes_uploaded);
	for (int i = 0; i < 8; i++)
		volume_destroy(shown[i]);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A daemon with config, a client, and an axis line shown: the projector
 * is lit from here on. */
static struct spindle *start_lit(struct daemon *d, const char *config)
{
	daemon_start_config(d, config);
	struct spindle *sp = client_connect(d);
	static float axis[6];
	show_vertices(sp, 1, axis, axis_line(axis), 255, 255, 255);
	return sp;
}

/* The big sphere shown on a lit projector, by a daemon with this config;
 * its frame, the time it was committed, and what was shown. */
static struct volume *show_big_sphere(const char *config, struct spindle_frame *f, uint64_t *committed,
				      struct spindle_status *st)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, config);
	static float big[48 * 24 * 18];
	uint32_t n = sphere(big, 0.85, 48, 24);
	struct spindle_status before = status_of(sp);
	*committed = mono_ns();
	show_triangles(sp, f, big, n, 0, 0, 255);
	struct volume *vol = capture_volume(sp);
	*st = status_of(sp);
	st->underruns -= before.underruns;
	spindle_disconnect(sp);
	daemon_stop(&d);
	return vol;
}

/* A volume that takes 1.5 revolutions to cross the link misses the
 * revolution start after its swap request (one underrun), and is shown
 * later and whole: bit for bit what an unlimited link shows. */
static void test_underrun(void)
{
	struct spindle_frame f;
	uint64_t committed;
	struct spindle_status st;
	struct volume *ref = show_big_sphere("sim-link-rate = 0\n", &f, &committed, &st);
	CHECK_EQ(st.underruns, 0);
	struct geometry g = small();
	double period = 60.0 / g.rpm;
	uint64_t rate = (uint64_t)((double)projwire_volume_size(ref) / (1.5 * period));
	char config[64];
	snprintf(config, sizeof(config), "sim-link-rate = %llu\n", (unsigned long long)rate);
	struct volume *late = show_big_sphere(config, &f, &committed, &st);
	printf("link %llu bytes/s: shown %.1f ms after the commit, %llu underruns\n", (unsigned long long)rate,
	       (double)(f.time_ns - committed) / 1e6, (unsigned long long)st.underruns);
	CHECK_EQ(st.underruns, 1);
	CHECK((double)(f.time_ns - committed) >= 1.5 * period * 1e9);
	CHECK_EQ(tiles_changed(late, ref), 0);
	CHECK_EQ(volume_tile_count(late), volume_tile_count(ref));
	volume_destroy(ref);
	volume_destroy(late);
}

/* Polls status for ms milliseconds: never lit while unlocked. Returns
 * whether it saw the projector dark, and (if lit_again) lit again. */
static void watch_light(struct spindle *sp, int ms, bool *dark, bool *relit)
{
	uint64_t end = mono_ns() + (uint64_t)ms * 1000000u;
	while (mono_ns() < end) {
		struct spindle_status st = status_of(sp);
		CHECK_MSG(st.blanked || st.locked, "lit while unlocked");
		if (st.blanked)
			*dark = true;
		else if (*dark)
			*relit = true;
		struct timespec ts = { 0, 2000000 };
		nanosleep(&ts, NULL);
	}
}

/* The number after key in the daemon's log, or -1. */
static double log_number(struct daemon *d, const char *key)
{
	FILE *f = fopen(d->log, "r");
	char line[1024];
	double v = -1;
	while (f && fgets(line, sizeof(line), f)) {
		const char *p = strstr(line, key);
		if (p)
			v = atof(p + strlen(key));
	}
	if (f)
		fclose(f);
	return v;
}

/* The rotor stops dead 1.5 s after start and turns again 1 s later: the
 * projector goes dark within 2 revolution periods of the last true index
 * pulse (the simulated projector measures it against the true rotor), is
 * never lit while unlocked, is lit again after the restart, and what is
 * committed meanwhile is shown once it is. */
static void test_stall(void)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, "sim-faults = stall=1.5+1.0/0.2\n");
	bool dark = false, relit = false;
	watch_light(sp, 2800, &dark, &relit);
	CHECK(dark && relit);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	spindle_disconnect(sp);
	daemon_stop_keep_log(&d);
	double stalls = log_number(&d, "simulated projector: ");
	double delay = log_number(&d, "dark at most ");
	printf("stalls %.0f, dark %.2f periods after the last true index pulse\n", stalls, delay);
	CHECK(stalls == 1 && delay > 0 && delay < 2.0);
	CHECK_EQ(log_number(&d, "ms while stopped and "), 0);
	daemon_remove_files(&d);
}

/* 0.1 % period jitter on the index pulse: the daemon lights once its fit
 * has settled, and the simulated projector's slice angle error stays
 * under a quarter of a slice (status reports it, with the jitter). */
static void test_jitter(void)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, "sim-faults = jitter=0.001,seed=7\n");
	struct timespec ts = { 3, 0 };
	nanosleep(&ts, NULL);
	struct spindle_status st = status_of(sp);
	struct geometry g = small();
	double period_us = 60e6 / g.rpm;
	printf("jitter %.1f us (%.3f%% of a period), index error %.1f us, slice angle error p99 %.3f max %.3f\n",
	       st.jitter_us, 100 * st.jitter_us / period_us, st.index_error_us, st.angle_error_p99,
	       st.angle_error_max);
	CHECK(st.locked && !st.blanked);
	/* RMS over the last 16 periods: a small sample of a 0.1 % spread. */
	CHECK(st.jitter_us > 0.0002 * period_us && st.jitter_us < 0.003 * period_us);
	CHECK(st.index_error_us > 0);
	CHECK(st.angle_error_p99 >= 0 && st.angle_error_p99 < 0.25);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* The simulated projector is unplugged four times for 0.3 s: status
 * answers throughout and says it is gone (and dark), the daemon sets the
 * new one up and lights it within 2 s of each re-plug, and a commit made
 * while it is away is shown, whole, once it is back. */
static void test_unplug(void)
{
	struct daemon d;
	struct spindle *sp =
		start_lit(&d, "sim-faults = unplug=1.0+0.3,unplug=1.8+0.3,unplug=2.6+0.3,unplug=3.4+0.3\n");
	int gone = 0, back = 0;
	uint64_t gone_at = 0, end = mono_ns() + 4200000000u, worst = 0;
	bool present = true;
	while (mono_ns() < end) {
		struct spindle_status st = status_of(sp);
		CHECK_MSG(st.blanked || (st.locked && st.projector_present), "lit while unlocked or absent");
		if (present && !st.projector_present) {
			gone++, gone_at = mono_ns();
			CHECK(spindle_commit(sp) == 0); /* shown once it is back */
		} else if (!present && st.projector_present) {
			back++;
		}
		present = st.projector_present;
		if (gone_at && present && !st.blanked) {
			uint64_t t = mono_ns() - gone_at;
			worst = t > worst ? t : worst;
			gone_at = 0;
		}
		struct timespec ts = { 0, 2000000 };
		nanosleep(&ts, NULL);
	}
	printf("unplugged %d times, back %d; lit again at most %.0f ms after the unplug (0.3 s away)\n", gone, back,
	       worst / 1e6);
	CHECK(gone == 4 && back == 4 && present);
	CHECK(worst > 0 && worst < 2300000000u); /* gone is seen a poll late: no lower bound */
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	struct volume *vol = capture_volume(sp);
	for (int c = 0; c < 3; c++)
		check_axis_line(vol, c);
	volume_destroy(vol);
	CHECK(daemon_alive(&d));
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* No projector when the daemon starts ("unplug=0+0.5"): it starts and
 * serves anyway, says the projector is missing, and shows what was
 * committed once one is plugged in. */
static void test_late_projector(void)
{
	struct daemon d;
	daemon_start_config(&d, "sim-faults = unplug=0+0.5\n");
	struct spindle *sp = client_connect(&d);
	struct spindle_status st = status_of(sp);
	CHECK(!st.projector_present && st.blanked);
	static float v[6];
	uint64_t t0 = mono_ns();
	show_vertices(sp, 1, v, axis_line(v), 255, 255, 255);
	printf("shown %.0f ms after the commit, the projector arriving 500 ms after start\n", (mono_ns() - t0) / 1e6);
	st = status_of(sp);
	CHECK(st.projector_present && !st.blanked);
	struct volume *vol = capture_volume(sp);
	for (int c = 0; c < 3; c++)
		check_axis_line(vol, c);
	volume_destroy(vol);
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

static const struct {
	const char *name;
	void (*run)(void);
} tests[] = {
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
	{ "delta", test_delta },
	{ "underrun", test_underrun },
	{ "stall", test_stall },
	{ "jitter", test_jitter },
	{ "unplug", test_unplug },
	{ "late-projector", test_late_projector },
	{ "gl-lost-egl", test_gl_lost_egl },
	{ "gl-lost-osmesa", test_gl_lost_osmesa },
	{ "gl-no-display", test_gl_no_display },
	{ "gl-bad-shader", test_gl_bad_shader },
};

int main(int argc, char **argv)
{
	for (size_t i = 0; i < sizeof(tests) / sizeof(tests[0]); i++) {
		if (argc < 2 || strcmp(argv[1], tests[i].name) == 0) {
			tests[i].run();
			printf("ok %s\n", tests[i].name);
		}
	}
	return check_done();
}
