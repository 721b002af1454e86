/* Watchers through libspindle (protocol 5): spindle_watch_create() gets the
 * volume on display, the same bits as a capture of it; the next comes only
 * after spindle_watch_release(), and it is the newest; the daemon counts it
 * all (spindle_get_watch_stats()); a client speaking version 4 cannot
 * watch. */
#include <errno.h>
#include <poll.h>
#include <string.h>
#include <time.h>

#include "scenes.h"
#include "wvol.h"

struct got {
	struct volume *vol; /* the last volume received, decoded */
	uint64_t seq, skipped;
	int volumes;
	bool failed;
};

static void on_volume(void *data, struct spindle_watcher *w, const struct spindle_watch_volume *v)
{
	struct got *g = data;
	if (!v) {
		g->failed = true;
		return;
	}
	volume_destroy(g->vol);
	g->vol = wvol_decode(v->data, v->size);
	CHECK(g->vol != NULL);
	CHECK(v->fd >= 0);
	g->seq = v->seq;
	g->skipped = v->skipped;
	g->volumes++;
}

/* Dispatches until the watcher has had n volumes (or ms milliseconds). */
static bool wait_volumes_ms(struct spindle *sp, struct got *g, int n, int ms)
{
	for (int i = 0; i < ms / 10 && g->volumes < n && !g->failed; i++) {
		struct pollfd pfd = { spindle_get_fd(sp), POLLIN, 0 };
		if (poll(&pfd, 1, 10) > 0)
			CHECK(spindle_dispatch(sp) >= 0);
	}
	return g->volumes >= n;
}

static bool wait_volumes(struct spindle *sp, struct got *g, int n)
{
	return wait_volumes_ms(sp, g, n, 5000);
}

static bool same_volume(const struct volume *a, const struct volume *b)
{
	if (a->image_count != b->image_count)
		return false;
	size_t n = volume_dense_image_bytes(a);
	uint8_t *da = malloc(n), *db = malloc(n);
	bool same = true;
	for (uint32_t k = 0; k < a->image_count && same; k++) {
		volume_image_to_dense(a, k, da);
		volume_image_to_dense(b, k, db);
		same = memcmp(da, db, n) == 0;
	}
	free(da);
	free(db);
	return same;
}

static void test_watch_lib(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	CHECK_EQ(spindle_get_version(sp), SPINDLE_PROTOCOL_VERSION);
	const float line[] = { 0.1f, -0.5f, 0.0f, 0.7f, 0.4f, 0.2f };
	show_vertices(sp, SPINDLE_LINES, line, 2, 255, 128, 0);
	struct volume *cap = capture_volume(sp);
	struct got g = { 0 };
	struct spindle_watcher *w = spindle_watch_create(sp, 0, on_volume, &g);
	CHECK(w != NULL);
	CHECK(wait_volumes(sp, &g, 1));
	CHECK_EQ(g.seq, cap->seq);
	CHECK(volume_tile_count(g.vol) > 0);
	CHECK_MSG(same_volume(g.vol, cap), "the watched volume is the captured one");
	/* Not released: a new scene is not sent. */
	const float line2[] = { -0.6f, 0.3f, 0.1f, 0.2f, -0.4f, -0.5f };
	show_vertices(sp, SPINDLE_LINES, line2, 2, 0, 255, 0);
	struct volume *cap2 = capture_volume(sp);
	CHECK(cap2->seq > cap->seq);
	CHECK(!wait_volumes_ms(sp, &g, 2, 400));
	/* Released: the volume on display now comes. */
	CHECK(spindle_watch_release(w) == 0);
	CHECK(wait_volumes(sp, &g, 2));
	CHECK_EQ(g.seq, cap2->seq);
	CHECK_MSG(same_volume(g.vol, cap2), "after release, the newest volume");
	struct spindle_watch_stats st;
	CHECK(spindle_get_watch_stats(sp, &st) == 0);
	CHECK(st.watchers == 1 && st.max_watchers == 4 && st.max_rate_hz == 15 && st.volumes_sent >= 2);
	CHECK(st.bytes_sent > 0);
	CHECK_EQ(spindle_watch_get_error(w), 0);
	spindle_watch_destroy(w);
	CHECK(spindle_get_watch_stats(sp, &st) == 0 && st.watchers == 0);
	volume_destroy(g.vol);
	volume_destroy(cap);
	volume_destroy(cap2);
	/* Version 4 has no watchers. */
	struct spindle *old = spindle_connect_version(d.socket, 4);
	CHECK(old != NULL);
	errno = 0;
	CHECK(spindle_watch_create(old, 0, on_volume, &g) == NULL && errno == EPROTONOSUPPORT);
	CHECK(spindle_get_watch_stats(old, &st) == -EPROTONOSUPPORT);
	spindle_disconnect(old);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A watcher left held when the client disconnects: freed with it. */
static void test_watch_disconnect(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	struct got g = { 0 };
	CHECK(spindle_watch_create(sp, 5, on_volume, &g) != NULL);
	CHECK(spindle_watch_create(sp, 0, on_volume, &g) != NULL);
	CHECK(wait_volumes(sp, &g, 2));
	spindle_disconnect(sp); /* frees both, with the volume held */
	sp = client_connect(&d);
	struct spindle_watch_stats st;
	CHECK(spindle_get_watch_stats(sp, &st) == 0 && st.watchers == 0 && st.volumes_sent == 2);
	spindle_disconnect(sp);
	volume_destroy(g.vol);
	daemon_stop(&d);
}

/* Destroyed with a volume on its way: the daemon sent it before it read
 * the destroy. It is dropped, not taken for an event of an unknown object,
 * and the connection goes on. */
static void test_watch_destroy_in_flight(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	const float line[] = { 0.1f, -0.5f, 0.0f, 0.7f, 0.4f, 0.2f };
	show_vertices(sp, SPINDLE_LINES, line, 2, 255, 128, 0);
	struct got g = { 0 };
	struct spindle_watcher *w = spindle_watch_create(sp, 0, on_volume, &g);
	CHECK(w != NULL);
	CHECK(wait_volumes(sp, &g, 1));
	const float line2[] = { -0.6f, 0.3f, 0.1f, 0.2f, -0.4f, -0.5f };
	show_vertices(sp, SPINDLE_LINES, line2, 2, 0, 255, 0);
	/* Released: the volume shown meanwhile is sent at once. Not read
	 * before the destroy (if the daemon is slower than this, the case
	 * checks less, and still passes). */
	CHECK(spindle_watch_release(w) == 0);
	struct timespec ts = { 0, 300000000 };
	nanosleep(&ts, NULL);
	spindle_watch_destroy(w);
	struct spindle_watch_stats st;
	CHECK(spindle_get_watch_stats(sp, &st) == 0 && st.watchers == 0);
	CHECK_EQ(g.volumes, 1);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0); /* forgets the destroyed watcher */
	CHECK(spindle_get_watch_stats(sp, &st) == 0);
	spindle_disconnect(sp);
	volume_destroy(g.vol);
	daemon_stop(&d);
}

static const struct named_test tests[] = {
	{ "lib", test_watch_lib },
	{ "disconnect", test_watch_disconnect },
	{ "destroy-in-flight", test_watch_destroy_in_flight },
};

int main(int argc, char **argv)
{
	return run_named_tests(tests, sizeof(tests) / sizeof(tests[0]), argc, argv);
}
