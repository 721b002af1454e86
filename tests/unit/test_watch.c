/* daemon/watch: watchers sent the volume on display, one in flight (nothing
 * more until release, the volumes shown meanwhile skipped and counted, the
 * newest sent after release), at most their rate (the client's, capped by
 * max-watch-rate), one encoding per volume shared by every watcher, the
 * max-watchers limit, and watch_next_due() for the rate timer. */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "geometry.h"
#include "volume.h"
#include "watch.h"
#include "wvol.h"

#define MS 1000000ll

static struct sent {
	struct watch_entry *w;
	uint64_t seq, skipped, size;
	struct stat st;
} sent[64];
static int nsent, nanswered, nwake;

static void on_send(void *data, struct watch_entry *w, int fd, uint64_t size, uint64_t seq, uint64_t skipped)
{
	CHECK(nsent < 64 && fd >= 0);
	struct sent *s = &sent[nsent++];
	*s = (struct sent){ .w = w, .seq = seq, .skipped = skipped, .size = size };
	CHECK(fstat(fd, &s->st) == 0 && (uint64_t)s->st.st_size == size);
	int seals = fcntl(fd, F_GET_SEALS);
	CHECK(seals >= 0 && (seals & F_SEAL_WRITE) && (seals & F_SEAL_SHRINK) && (seals & F_SEAL_GROW));
	void *p = mmap(NULL, size, PROT_READ, MAP_SHARED, fd, 0);
	CHECK(p != MAP_FAILED);
	struct volume *v = wvol_decode(p, size);
	CHECK(v != NULL && v->seq == seq);
	volume_destroy(v);
	munmap(p, size);
}

static void on_answered(void *data)
{
	nanswered++;
}

static void on_wake(void *data)
{
	nwake++;
}

static const struct watch_listener listener = {
	.version = WATCH_LISTENER_VERSION,
	.send = on_send,
	.answered = on_answered,
	.wake = on_wake,
};

static struct volume *vol(uint64_t seq)
{
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	struct volume *v = volume_create(&g);
	uint8_t tile[VOLUME_TILE_BYTES] = { 0x80 };
	CHECK(v && volume_image_append(v, (uint32_t)(seq % v->image_count), 0, tile) == 0);
	v->seq = seq;
	return v;
}

static void check_one_in_flight(void)
{
	struct watch wt;
	struct watch_entry a, b;
	watch_init(&wt, 4, 10, &listener, NULL);
	nsent = nwake = 0;
	CHECK(!watch_any(&wt));
	CHECK(watch_add(&wt, &a, 0) == 0); /* the daemon's 10 Hz: 100 ms apart */
	CHECK(nwake == 1 && watch_any(&wt));
	struct volume *v1 = vol(1), *v2 = vol(2), *v3 = vol(3), *v4 = vol(4);
	watch_serve(&wt, v1, 1000 * MS);
	CHECK(nsent == 1 && sent[0].seq == 1 && sent[0].skipped == 0);
	watch_serve(&wt, v1, 1001 * MS); /* the same volume again: nothing */
	watch_serve(&wt, v2, 1200 * MS); /* in flight: skipped later */
	watch_serve(&wt, v3, 1300 * MS);
	CHECK(nsent == 1);
	CHECK(watch_next_due(&wt) == 0); /* in flight: no timer */
	watch_release(&wt, &a);
	CHECK(nwake == 2);
	watch_serve(&wt, v3, 1310 * MS);
	CHECK(nsent == 2 && sent[1].seq == 3 && sent[1].skipped == 1);
	CHECK_EQ(wt.stats.skipped, 1u);
	/* Released at once, but not due for 100 ms: the timer says when. */
	watch_release(&wt, &a);
	watch_serve(&wt, v4, 1350 * MS);
	CHECK(nsent == 2);
	CHECK(watch_next_due(&wt) == 1410 * MS);
	watch_serve(&wt, v4, 1410 * MS);
	CHECK(nsent == 3 && sent[2].seq == 4 && sent[2].skipped == 0);
	/* A second watcher at 5 Hz shares the encoding of volume 4. */
	CHECK(watch_add(&wt, &b, 5) == 0);
	watch_serve(&wt, v4, 1420 * MS);
	CHECK(nsent == 4 && sent[3].w == &b && sent[3].st.st_ino == sent[2].st.st_ino);
	CHECK_EQ(b.period_ns, 200u * MS);
	CHECK_EQ(wt.stats.sent, 4u);
	CHECK_EQ(wt.stats.bytes, sent[0].size + sent[1].size + sent[2].size);
	/* A client asking for more than max-watch-rate gets max-watch-rate. */
	watch_remove(&wt, &b);
	watch_remove(&wt, &b); /* twice: nothing */
	CHECK(watch_add(&wt, &b, 1000) == 0 && b.period_ns == 100u * MS);
	watch_remove(&wt, &a);
	watch_remove(&wt, &b);
	CHECK(!watch_any(&wt) && wt.fd < 0); /* the encoding goes with the last watcher */
	watch_fini(&wt);
	volume_destroy(v1);
	volume_destroy(v2);
	volume_destroy(v3);
	volume_destroy(v4);
}

static void check_limit(void)
{
	struct watch wt;
	struct watch_entry e[3];
	watch_init(&wt, 2, 15, &listener, NULL);
	CHECK(watch_add(&wt, &e[0], 0) == 0);
	CHECK(watch_add(&wt, &e[1], 0) == 0);
	CHECK(watch_add(&wt, &e[2], 0) == -EUSERS);
	CHECK_EQ(wt.stats.refused, 1u);
	CHECK_EQ(wt.count, 2u);
	watch_remove(&wt, &e[0]);
	CHECK(watch_add(&wt, &e[2], 0) == 0);
	watch_count_denied(&wt);
	CHECK_EQ(wt.stats.denied, 1u);
	watch_remove(&wt, &e[1]);
	watch_remove(&wt, &e[2]);
	watch_fini(&wt);
}

int main(void)
{
	check_one_in_flight();
	check_limit();
	return check_done();
}
