/* daemon/frames: frame callbacks tied to the volume of their commit and
 * answered when it is shown lit, never with a time before their commit;
 * volumes swapped in while dark shown once lit; the revolution rule for a
 * scene found unchanged; captures answered with the volume on display. */
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "frames.h"
#include "geometry.h"
#include "volume.h"

#define MAX_DONE 16

static struct done {
	struct waiter *w;
	uint64_t seq;
	int64_t time_ns;
	int fd;
	uint64_t size;
} done[MAX_DONE];
static int ndone, nanswered;

static void frame_done(void *data, struct waiter *w, uint64_t seq, int64_t time_ns)
{
	CHECK(ndone < MAX_DONE);
	CHECK(w->link.next == &w->link); /* off the queue before the call */
	done[ndone++] = (struct done){ .w = w, .seq = seq, .time_ns = time_ns, .fd = -1 };
}

static void capture_done(void *data, struct waiter *w, int fd, uint64_t size)
{
	CHECK(ndone < MAX_DONE);
	struct stat st;
	CHECK(fd >= 0 && fstat(fd, &st) == 0 && (uint64_t)st.st_size == size && size > 0);
	done[ndone++] = (struct done){ .w = w, .fd = fd, .size = size };
}

static void answered(void *data)
{
	nanswered++;
}

static const struct frames_listener listener = {
	.version = FRAMES_LISTENER_VERSION,
	.frame_done = frame_done,
	.capture_done = capture_done,
	.answered = answered,
};

static void waiter_init(struct waiter *w)
{
	memset(w, 0, sizeof(*w));
	link_init(&w->link);
}

static void reset(void)
{
	ndone = nanswered = 0;
}

static void test_tie_and_show(void)
{
	struct frames f;
	frames_init(&f, &listener, NULL);
	struct waiter a, b, c;
	waiter_init(&a);
	waiter_init(&b);
	waiter_init(&c);
	reset();
	frames_commit(&f, &a, 100);
	frames_commit(&f, &b, 150);
	CHECK_EQ(frames_tie(&f, 1), 2); /* both commits are in volume 1 */
	frames_commit(&f, &c, 200);
	CHECK_EQ(frames_tie(&f, 2), 1); /* only c was untied */

	/* Volume 1 swapped in while dark: not shown, nothing answered. */
	CHECK(!frames_shown(&f, 1, 1000, false));
	CHECK_EQ(ndone, 0);
	/* Lit later: shown then, with the time it was lit. */
	CHECK(frames_lit(&f, 1200));
	CHECK_EQ(ndone, 2);
	CHECK(done[0].w == &a && done[0].seq == 1 && done[0].time_ns == 1200);
	CHECK(done[1].w == &b && done[1].seq == 1);
	CHECK_EQ(nanswered, 1);
	CHECK(!frames_lit(&f, 1300)); /* nothing unseen any more */

	/* Volume 2 shown lit at once; a newer volume answers older ties too. */
	reset();
	CHECK(frames_shown(&f, 3, 2000, true));
	CHECK_EQ(ndone, 1);
	CHECK(done[0].w == &c && done[0].seq == 3 && done[0].time_ns == 2000);
	CHECK(link_empty(&f.frames));
}

/* A commit made after its volume was swapped in waits for a later
 * revolution start; one found unchanged waits for the next revolution. */
static void test_revolutions(void)
{
	struct frames f;
	frames_init(&f, &listener, NULL);
	struct waiter a, b;
	waiter_init(&a);
	waiter_init(&b);
	reset();
	frames_commit(&f, &a, 5000);
	frames_tie(&f, 1);
	CHECK(frames_shown(&f, 1, 4000, true)); /* swapped in before the commit */
	CHECK_EQ(ndone, 0);
	frames_revolution(&f, 6000, true); /* a swap pending answers it instead */
	CHECK_EQ(ndone, 0);
	frames_revolution(&f, 6000, false);
	CHECK_EQ(ndone, 1);
	CHECK(done[0].w == &a && done[0].seq == 1 && done[0].time_ns == 6000);

	/* The next scene is unchanged: its frame is tied to the volume on
	 * display and answered at the next revolution start. */
	reset();
	frames_commit(&f, &b, 7000);
	CHECK_EQ(frames_tie(&f, 1), 1);
	frames_wait_revolution(&f);
	frames_revolution(&f, 8000, false);
	CHECK_EQ(ndone, 1);
	CHECK(done[0].w == &b && done[0].time_ns == 8000);
	CHECK(!f.waiting); /* nothing left: revolutions cost a test again */
}

static void test_captures(void)
{
	struct frames f;
	frames_init(&f, &listener, NULL);
	struct waiter a, b;
	waiter_init(&a);
	waiter_init(&b);
	reset();
	CHECK(!frames_capture_waiting(&f));
	frames_capture(&f, &a);
	frames_capture(&f, &b);
	CHECK(frames_capture_waiting(&f));
	frames_serve_captures(&f, NULL); /* nothing shown yet: they wait */
	CHECK_EQ(ndone, 0);
	struct geometry g;
	CHECK_EQ(geometry_from_profile("small", &g), 0);
	struct volume *v = volume_create(&g);
	CHECK(v);
	frames_serve_captures(&f, v);
	CHECK_EQ(ndone, 2);
	CHECK(done[0].w == &a && done[1].w == &b && done[0].size == done[1].size);
	CHECK_EQ(nanswered, 1);
	CHECK(!frames_capture_waiting(&f));
	volume_destroy(v);
}

/* A departing client's waiters leave the queues. */
static void test_remove(void)
{
	struct frames f;
	frames_init(&f, &listener, NULL);
	struct waiter a;
	waiter_init(&a);
	reset();
	frames_commit(&f, &a, 10);
	frames_tie(&f, 1);
	frames_remove(&a);
	frames_remove(&a);
	CHECK(frames_shown(&f, 1, 20, true));
	CHECK_EQ(ndone, 0);
	CHECK_EQ(nanswered, 0);
}

int main(void)
{
	int fds = count_fds();
	test_tie_and_show();
	test_revolutions();
	test_captures();
	test_remove();
	CHECK_EQ(count_fds(), fds); /* the capture memfd is closed */
	return check_done();
}
