/* Protocol version 2 through libspindle: each new way of drawing is
 * checked against a version 1 way of drawing the same thing (captured
 * volumes bit for bit equal), and the new rules (refused commits,
 * exclusive layers, priority, state events) by what is shown. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "scenes.h"

/* Every image of a and b equal, bit for bit. */
static bool same_volume(const struct volume *a, const struct volume *b)
{
	size_t n = volume_dense_image_bytes(a);
	uint8_t *da = malloc(n), *db = malloc(n);
	bool same = da && db;
	for (uint32_t k = 0; same && k < NV; k++) {
		volume_image_to_dense(a, k, da);
		volume_image_to_dense(b, k, db);
		same = memcmp(da, db, n) == 0;
	}
	free(da);
	free(db);
	return same;
}

static bool volume_empty(const struct volume *v)
{
	return volume_tile_count(v) == 0;
}

/* A list on a layer of its own, for a test to fill; shown after commit. */
struct shown {
	struct spindle_list *list;
	struct spindle_layer *layer;
};

static struct shown new_layer(struct spindle *sp)
{
	struct shown s = { spindle_list_create(sp), spindle_layer_create(sp) };
	CHECK(s.list && s.layer);
	CHECK(spindle_layer_set_list(s.layer, s.list) == 0);
	return s;
}

/* Commits, waits until shown, captures. */
static struct volume *commit_capture(struct spindle *sp)
{
	CHECK(spindle_commit_and_wait(sp, NULL) == 0);
	return capture_volume(sp);
}

/* The edges of a cube of half size a about (0, 0.1, 0.3), as 12 segments. */
static const float cube[8][3] = {
	{ -.2f, -.1f, .1f }, { .2f, -.1f, .1f }, { .2f, .3f, .1f }, { -.2f, .3f, .1f },
	{ -.2f, -.1f, .5f }, { .2f, -.1f, .5f }, { .2f, .3f, .5f }, { -.2f, .3f, .5f },
};
static const uint16_t cube_edges[24] = { 0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 6, 6, 7, 7, 4, 0, 4, 1, 5, 2, 6, 3, 7 };

/* draw_indexed (u16 and u32) shows what the same segments drawn one by
 * one show; so does a line strip against its segments, and an inline
 * buffer against a memfd one. */
static void test_indexed(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	float segs[24][3];
	for (int i = 0; i < 24; i++)
		memcpy(segs[i], cube[cube_edges[i]], 12);
	struct shown s = new_layer(sp);
	struct spindle_buffer *flat = spindle_buffer_create_inline(sp, segs, sizeof(segs));
	CHECK(spindle_list_lines(s.list, flat, 0, 24, 0) == 0);
	struct volume *ref = commit_capture(sp);
	CHECK(!volume_empty(ref));

	struct spindle_buffer *verts = spindle_buffer_create(sp, cube, sizeof(cube));
	struct spindle_buffer *idx16 = spindle_buffer_create(sp, cube_edges, sizeof(cube_edges));
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_draw_indexed(s.list, SPINDLE_LINES, verts, 0, 8, 0, idx16, 0, 24, SPINDLE_INDEX_U16) == 0);
	struct volume *v16 = commit_capture(sp);
	CHECK(same_volume(ref, v16));

	uint32_t idx[24];
	for (int i = 0; i < 24; i++)
		idx[i] = cube_edges[i];
	int fd = memfd_create("indices", MFD_ALLOW_SEALING);
	CHECK(fd >= 0 && write(fd, idx, sizeof(idx)) == sizeof(idx) && fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK) == 0);
	struct spindle_buffer *idx32 = spindle_buffer_create_from_fd(sp, fd, sizeof(idx));
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_draw_indexed(s.list, SPINDLE_LINES, verts, 0, 8, 0, idx32, 0, 24, SPINDLE_INDEX_U32) == 0);
	/* Indices flipped once the daemon has the draw change nothing drawn. */
	CHECK(spindle_roundtrip(sp) == 0);
	memset(idx, 0, sizeof(idx));
	CHECK(pwrite(fd, idx, sizeof(idx), 0) == sizeof(idx));
	close(fd);
	struct volume *v32 = commit_capture(sp);
	CHECK(same_volume(ref, v32));

	/* The bottom face as a strip 0-1-2-3-0 against its four segments. */
	static const uint16_t strip[5] = { 0, 1, 2, 3, 0 };
	struct spindle_buffer *sidx = spindle_buffer_create(sp, strip, sizeof(strip));
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_draw_indexed(s.list, SPINDLE_LINE_STRIP, verts, 0, 8, 0, sidx, 0, 5, SPINDLE_INDEX_U16) ==
	      0);
	struct volume *vs = commit_capture(sp);
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_lines(s.list, flat, 0, 8, 0) == 0);
	struct volume *vl = commit_capture(sp);
	CHECK(same_volume(vs, vl) && !volume_empty(vs));
	volume_destroy(ref);
	volume_destroy(v16);
	volume_destroy(v32);
	volume_destroy(vs);
	volume_destroy(vl);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* An index past vertex_count is a fatal error for that client alone. */
static void test_bad_index(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *witness = client_connect(&d);
	struct spindle *sp = client_connect(&d);
	struct shown s = new_layer(sp);
	struct spindle_buffer *verts = spindle_buffer_create(sp, cube, sizeof(cube));
	static const uint16_t bad[2] = { 0, 8 };
	struct spindle_buffer *idx = spindle_buffer_create(sp, bad, sizeof(bad));
	spindle_list_draw_indexed(s.list, SPINDLE_LINES, verts, 0, 8, 0, idx, 0, 2, SPINDLE_INDEX_U16);
	CHECK(spindle_roundtrip(sp) == -EPIPE);
	CHECK(spindle_get_error_code(sp) == SPINDLE_ERROR_INVALID_VALUE);
	CHECK(strstr(spindle_get_error(sp), "index 1"));
	CHECK(spindle_roundtrip(witness) == 0);
	spindle_disconnect(sp);
	spindle_disconnect(witness);
	daemon_stop(&d);
}

static void translate(float m[16], float x, float y, float z)
{
	memcpy(m, identity, sizeof(identity));
	m[12] = x;
	m[13] = y;
	m[14] = z;
}

/* push, multiply_transform and pop give what set_transform gives. */
static void test_nested_transforms(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct shown s = new_layer(sp);
	float v[6], a[16], b[16], ab[16];
	struct spindle_buffer *line = spindle_buffer_create(sp, v, axis_line(v) * 12);
	translate(a, 0.3f, 0, 0);
	translate(b, 0, 0, 0.2f);
	translate(ab, 0.3f, 0, 0.2f);
	CHECK(spindle_list_set_transform(s.list, ab) == 0);
	CHECK(spindle_list_lines(s.list, line, 0, 2, 0) == 0);
	CHECK(spindle_list_set_transform(s.list, a) == 0);
	CHECK(spindle_list_lines(s.list, line, 0, 2, 0) == 0);
	struct volume *ref = commit_capture(sp);

	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_multiply_transform(s.list, a) == 0);
	CHECK(spindle_list_push(s.list) == 0);
	CHECK(spindle_list_multiply_transform(s.list, b) == 0);
	CHECK(spindle_list_set_color(s.list, 255, 255, 255, 255) == 0);
	CHECK(spindle_list_lines(s.list, line, 0, 2, 0) == 0);
	CHECK(spindle_list_pop(s.list) == 0);
	CHECK(spindle_list_lines(s.list, line, 0, 2, 0) == 0);
	struct volume *nested = commit_capture(sp);
	CHECK(same_volume(ref, nested) && !volume_empty(ref));
	/* A pop with nothing pushed is fatal. */
	CHECK(spindle_list_pop(s.list) == 0);
	CHECK(spindle_list_pop(s.list) == 0);
	CHECK(spindle_roundtrip(sp) == -EPIPE && spindle_get_error_code(sp) == SPINDLE_ERROR_INVALID_VALUE);
	volume_destroy(ref);
	volume_destroy(nested);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

struct cvertex {
	float xyz[3];
	uint8_t rgba[4];
};

/* Per-vertex colour: one colour at every vertex shows as set_color does;
 * a red-to-blue line is red at one end and blue at the other. */
static void test_vertex_colour(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct shown s = new_layer(sp);
	float v[6];
	axis_line(v);
	struct spindle_buffer *plain = spindle_buffer_create(sp, v, sizeof(v));
	CHECK(spindle_list_set_color(s.list, 255, 0, 0, 255) == 0);
	CHECK(spindle_list_lines(s.list, plain, 0, 2, 0) == 0);
	struct volume *ref = commit_capture(sp);

	struct cvertex cv[2] = { { { v[0], v[1], v[2] }, { 255, 0, 0, 255 } },
				 { { v[3], v[4], v[5] }, { 255, 0, 0, 255 } } };
	struct spindle_buffer *red = spindle_buffer_create(sp, cv, sizeof(cv));
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_set_vertex_format(s.list, SPINDLE_XYZ_RGBA8) == 0);
	CHECK(spindle_list_set_color(s.list, 0, 255, 0, 255) == 0); /* not used */
	CHECK(spindle_list_lines(s.list, red, 0, 2, 0) == 0);
	struct volume *same = commit_capture(sp);
	CHECK(same_volume(ref, same));

	/* Red at y = -0.6, blue at y = 0.6: rows near each end one colour. */
	memcpy(cv[1].rgba, (uint8_t[4]){ 0, 0, 255, 255 }, 4);
	struct spindle_buffer *grad = spindle_buffer_create(sp, cv, sizeof(cv));
	CHECK(spindle_list_clear(s.list) == 0);
	CHECK(spindle_list_set_vertex_format(s.list, SPINDLE_XYZ_RGBA8) == 0);
	CHECK(spindle_list_lines(s.list, grad, 0, 2, 0) == 0);
	struct volume *g = commit_capture(sp);
	int lit[2][3] = { { 0 } }; /* [bottom, top][channel] */
	for (uint32_t k = 0; k < NV; k++)
		for (uint32_t u = 0; u < W; u++)
			for (int c = 0; c < 3; c++) {
				lit[0][c] += volume_pixel(g, k, u, (uint32_t)row(-0.55), c);
				lit[1][c] += volume_pixel(g, k, u, (uint32_t)row(0.55), c);
			}
	/* Dithered: near each end the other colour is only a few percent. */
	printf("bottom row: %d red, %d blue; top row: %d red, %d blue\n", lit[0][0], lit[0][2], lit[1][0], lit[1][2]);
	CHECK(lit[0][0] > 8 * lit[0][2] && lit[1][2] > 8 * lit[1][0] && lit[0][0] > 0 && lit[1][2] > 0);
	CHECK_EQ(lit[0][1] + lit[1][1], 0);
	volume_destroy(ref);
	volume_destroy(same);
	volume_destroy(g);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A point of size 3 lights the 3 x 3 pixels around its voxel, and only
 * them (docs/design.md section 3, computed here). */
static void test_point_size(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct shown s = new_layer(sp);
	static const float p[3] = { 0.5f, 0.2f, 0.1f };
	struct spindle_buffer *b = spindle_buffer_create(sp, p, sizeof(p));
	CHECK(spindle_list_set_point_size(s.list, 3) == 0);
	CHECK(spindle_list_points(s.list, b, 0, 1, 0) == 0);
	struct volume *v = commit_capture(sp);
	struct geometry g = small();
	struct voxel x = expected_point(&g, p[0], p[1], p[2]);
	int lit = 0, inside = 0;
	for (uint32_t k = 0; k < NV; k++)
		for (uint32_t row_ = 0; row_ < H; row_++)
			for (uint32_t u = 0; u < W; u++) {
				if (!volume_pixel(v, k, u, row_, 0))
					continue;
				lit++;
				inside += k == x.k % NV && abs((int)u - (int)x.u) <= 1 &&
					  abs((int)row_ - (int)x.v) <= 1;
			}
	CHECK_EQ(lit, 9);
	CHECK_EQ(inside, 9);
	volume_destroy(v);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static void check_refused(struct spindle *sp, int expect, struct volume *before)
{
	CHECK(spindle_commit_and_wait(sp, NULL) == expect);
	/* Nothing of it shows; the connection goes on. */
	struct volume *now = capture_volume(sp);
	CHECK(same_volume(before, now));
	volume_destroy(now);
}

/* A commit over max-primitives is refused whole and stays pending. */
static void test_primitives_quota(void)
{
	struct daemon d;
	daemon_start_config(&d, "renderer = cpu\nmax-primitives = 10\n");
	struct spindle *sp = client_connect(&d);
	float v[6];
	struct shown a = new_layer(sp);
	struct spindle_buffer *line = spindle_buffer_create(sp, v, axis_line(v) * 12);
	CHECK(spindle_list_lines(a.list, line, 0, 2, 0) == 0);
	struct volume *before = commit_capture(sp);
	/* Ten more segments on a second layer: eleven in all. */
	struct shown b = new_layer(sp);
	for (int i = 0; i < 10; i++)
		CHECK(spindle_list_lines(b.list, line, 0, 2, 0) == 0);
	check_refused(sp, -EDQUOT, before);
	/* Still pending: hiding the first layer makes it fit. */
	CHECK(spindle_layer_set_visible(a.layer, false) == 0);
	CHECK(spindle_commit_and_wait(sp, NULL) == 0);
	volume_destroy(before);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A white axis line on a layer of its own. */
static struct shown show_line(struct spindle *sp, float dx)
{
	float v[6], m[16];
	struct shown s = new_layer(sp);
	struct spindle_buffer *line = spindle_buffer_create(sp, v, axis_line(v) * 12);
	shift_x(m, dx);
	CHECK(spindle_list_set_transform(s.list, m) == 0);
	CHECK(spindle_list_lines(s.list, line, 0, 2, 0) == 0);
	return s;
}

/* Whether sp captures want within 2 s (a change made by another client,
 * such as its leaving, shows a volume or two later). */
static bool eventually_shows(struct spindle *sp, const struct volume *want)
{
	uint64_t end = mono_ns() + 2000000000ull;
	while (mono_ns() < end) {
		struct volume *v = capture_volume(sp);
		bool same = same_volume(v, want);
		volume_destroy(v);
		if (same)
			return true;
	}
	return false;
}

/* An exclusive layer shows its client alone, and only one client at a
 * time; policy none refuses it. */
static void test_exclusive(void)
{
	struct daemon d;
	daemon_start_config(&d, "renderer = cpu\nexclusive = any\n");
	struct spindle *a = client_connect(&d), *b = client_connect(&d), *c = client_connect(&d);
	show_line(a, 0);
	struct volume *only_a = commit_capture(a);
	struct shown sb = show_line(b, 0.4f);
	struct volume *both = commit_capture(b);
	CHECK(spindle_layer_set_exclusive(sb.layer, true) == 0);
	struct volume *only_b = commit_capture(b);
	CHECK(!same_volume(both, only_b) && !same_volume(only_a, only_b) && !volume_empty(only_b));
	struct shown sc = show_line(c, -0.4f);
	CHECK(spindle_layer_set_exclusive(sc.layer, true) == 0);
	check_refused(c, -EBUSY, only_b);
	/* b hides its exclusive layer: a shows again, beside c's line once c
	 * gives up asking. */
	CHECK(spindle_layer_set_visible(sb.layer, false) == 0);
	struct volume *a_again = commit_capture(b);
	CHECK(same_volume(only_a, a_again));
	CHECK(spindle_layer_set_exclusive(sc.layer, false) == 0);
	struct volume *a_c = commit_capture(c);
	/* b's exclusive layer again, then b leaves: a and c come back. */
	CHECK(spindle_layer_set_visible(sb.layer, true) == 0);
	struct volume *b_again = commit_capture(b);
	CHECK(same_volume(only_b, b_again));
	spindle_disconnect(b);
	CHECK(eventually_shows(a, a_c));
	volume_destroy(only_a);
	volume_destroy(both);
	volume_destroy(only_b);
	volume_destroy(a_again);
	volume_destroy(a_c);
	volume_destroy(b_again);
	spindle_disconnect(a);
	spindle_disconnect(c);
	daemon_stop(&d);

	daemon_start_config(&d, "renderer = cpu\nexclusive = none\n");
	a = client_connect(&d);
	struct shown sa = show_line(a, 0);
	struct volume *shown = commit_capture(a);
	CHECK(spindle_layer_set_exclusive(sa.layer, true) == 0);
	check_refused(a, -EACCES, shown);
	volume_destroy(shown);
	spindle_disconnect(a);
	daemon_stop(&d);
}

/* Over max-scene-primitives the lower priority layer is left out. */
static void test_priority(void)
{
	struct daemon d;
	daemon_start_config(&d, "renderer = cpu\nmax-scene-primitives = 1\n");
	struct spindle *a = client_connect(&d), *b = client_connect(&d);
	struct shown la = show_line(a, 0);
	struct volume *only_a = commit_capture(a);
	struct shown lb = show_line(b, 0.4f);
	CHECK(spindle_layer_set_priority(lb.layer, 5) == 0);
	struct volume *only_b = commit_capture(b);
	CHECK(!same_volume(only_a, only_b) && !volume_empty(only_b));
	CHECK(spindle_layer_set_priority(la.layer, 6) == 0);
	struct volume *a_again = commit_capture(a);
	CHECK(same_volume(only_a, a_again));
	volume_destroy(only_a);
	volume_destroy(only_b);
	volume_destroy(a_again);
	spindle_disconnect(a);
	spindle_disconnect(b);
	daemon_stop(&d);
}

/* Locked, then unlocked and blanked, then locked again. */
struct states {
	int phase;
	float min_rpm;
};

static void on_state(void *data, const struct spindle_state *st)
{
	struct states *s = data;
	if (s->phase == 1)
		s->min_rpm = fminf(s->min_rpm, st->rpm);
	if (s->phase == 0 && st->locked)
		s->phase = 1;
	else if (s->phase == 1 && !st->locked && st->blanked)
		s->phase = 2;
	else if (s->phase == 2 && st->locked)
		s->phase = 3;
}

/* A stall and restart of the rotor reach the client as state events. */
static void test_state_events(void)
{
	struct daemon d;
	daemon_start_config(&d, "renderer = cpu\nsim-faults = stall=0.8/0.3+0.4/0.1\n");
	struct spindle *sp = client_connect(&d);
	struct states s = { .min_rpm = 1e9f };
	static const struct spindle_listener listener = { .state = on_state };
	spindle_set_listener(sp, &listener, &s);
	struct spindle_state now;
	CHECK(spindle_get_state(sp, &now) == 0);
	on_state(&s, &now);
	uint64_t end = mono_ns() + 4000000000ull;
	while (s.phase < 3 && mono_ns() < end) {
		CHECK(spindle_roundtrip(sp) >= 0);
		usleep(10000);
	}
	CHECK_EQ(s.phase, 3);
	/* rpm events followed the slowing rotor down. */
	CHECK(s.min_rpm < 0.8f * spindle_get_device_info(sp)->rpm);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static const struct named_test tests[] = {
	{ "indexed", test_indexed },
	{ "bad-index", test_bad_index },
	{ "nested-transforms", test_nested_transforms },
	{ "vertex-colour", test_vertex_colour },
	{ "point-size", test_point_size },
	{ "primitives-quota", test_primitives_quota },
	{ "exclusive", test_exclusive },
	{ "priority", test_priority },
	{ "state-events", test_state_events },
};

int main(int argc, char **argv)
{
	return run_named_tests(tests, sizeof(tests) / sizeof(tests[0]), argc, argv);
}
