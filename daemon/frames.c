#include "frames.h"

#include <errno.h>
#include <string.h>
#include <unistd.h>

#include "log.h"
#include "sealed.h"
#include "svol.h"

void frames_init(struct frames *f, const struct frames_listener *listener, void *data)
{
	*f = (struct frames){ .listener = listener, .data = data };
	link_init(&f->frames);
	link_init(&f->captures);
}

void frames_commit(struct frames *f, struct waiter *w, int64_t now_ns)
{
	w->commit_ns = now_ns;
	w->volume_seq = 0;
	link_remove(&w->link);
	link_append(&f->frames, &w->link);
}

void frames_capture(struct frames *f, struct waiter *w)
{
	link_remove(&w->link);
	link_append(&f->captures, &w->link);
}

void frames_remove(struct waiter *w)
{
	link_remove(&w->link);
}

unsigned frames_tie(struct frames *f, uint64_t seq)
{
	unsigned n = 0;
	struct waiter *w;
	link_for_each(w, &f->frames, link) {
		if (!w->volume_seq) {
			w->volume_seq = seq;
			n++;
		}
	}
	return n;
}

void frames_wait_revolution(struct frames *f)
{
	f->waiting = true;
}

/* Frames tied to volume seq or older are done: shown at time_ns; those of
 * commits made after time_ns wait. Returns whether any waits so. */
static bool frames_done(struct frames *f, uint64_t seq, int64_t time_ns)
{
	bool later = false, answered = false;
	struct waiter *w, *tmp;
	link_for_each_safe(w, tmp, &f->frames, link) {
		if (!w->volume_seq || w->volume_seq > seq)
			continue;
		if (w->commit_ns > time_ns) {
			later = true;
			continue;
		}
		link_remove(&w->link);
		f->listener->frame_done(f->data, w, seq, time_ns);
		answered = true;
	}
	if (answered)
		f->listener->answered(f->data);
	return later;
}

bool frames_shown(struct frames *f, uint64_t seq, int64_t time_ns, bool lit)
{
	/* Swapped in while dark is not shown: that waits for the light. */
	if (!lit) {
		f->unseen_seq = seq;
		return false;
	}
	f->unseen_seq = 0;
	f->shown_seq = seq;
	if (frames_done(f, seq, time_ns))
		f->waiting = true;
	return true;
}

bool frames_lit(struct frames *f, int64_t time_ns)
{
	return f->unseen_seq && frames_shown(f, f->unseen_seq, time_ns, true);
}

void frames_revolution(struct frames *f, int64_t time_ns, bool swap_pending)
{
	if (!f->waiting || !f->shown_seq || swap_pending)
		return;
	f->waiting = frames_done(f, f->shown_seq, time_ns);
}

bool frames_capture_waiting(const struct frames *f)
{
	return !link_empty(&f->captures);
}

/* svol_encode() as sealed_memfd() calls it. */
static void fill_svol(const void *vol, uint8_t *out)
{
	svol_encode(vol, out);
}

void frames_serve_captures(struct frames *f, const struct volume *shown)
{
	if (!shown || link_empty(&f->captures))
		return;
	uint64_t size = svol_size(shown);
	int fd = sealed_memfd("spindle-capture", size, fill_svol, shown);
	if (fd < 0)
		log_error("capture failed: %s", strerror(-fd));
	struct waiter *w, *tmp;
	link_for_each_safe(w, tmp, &f->captures, link) {
		link_remove(&w->link);
		f->listener->capture_done(f->data, w, fd, size);
	}
	f->listener->answered(f->data);
	if (fd >= 0)
		close(fd);
}
