#include "watch.h"

#include <errno.h>
#include <string.h>
#include <unistd.h>

#include "log.h"
#include "sealed.h"
#include "volume.h"
#include "wvol.h"

void watch_init(struct watch *wt, uint32_t max_watchers, uint32_t max_rate_hz, const struct watch_listener *listener,
		void *data)
{
	*wt = (struct watch){
		.max_watchers = max_watchers,
		.max_rate_hz = max_rate_hz ? max_rate_hz : 1,
		.fd = -1,
		.listener = listener,
		.data = data,
	};
	link_init(&wt->watchers);
}

void watch_fini(struct watch *wt)
{
	if (wt->fd >= 0)
		close(wt->fd);
	wt->fd = -1;
}

int watch_add(struct watch *wt, struct watch_entry *w, uint32_t rate_hz)
{
	if (wt->count >= wt->max_watchers) {
		wt->stats.refused++;
		return -EUSERS;
	}
	uint32_t rate = rate_hz && rate_hz < wt->max_rate_hz ? rate_hz : wt->max_rate_hz;
	*w = (struct watch_entry){ .period_ns = 1000000000ull / rate };
	link_append(&wt->watchers, &w->link);
	wt->count++;
	wt->listener->wake(wt->data);
	return 0;
}

void watch_count_denied(struct watch *wt)
{
	wt->stats.denied++;
}

void watch_remove(struct watch *wt, struct watch_entry *w)
{
	if (!w->link.next || w->link.next == &w->link)
		return; /* never added, or removed already */
	link_remove(&w->link);
	wt->count--;
	if (!wt->count && wt->fd >= 0) {
		close(wt->fd); /* nobody left to share it with */
		wt->fd = -1;
	}
}

void watch_release(struct watch *wt, struct watch_entry *w)
{
	if (!w->in_flight)
		return;
	w->in_flight = false;
	wt->listener->wake(wt->data);
}

/* wvol_encode() as sealed_memfd() calls it. */
static void fill_wvol(const void *vol, uint8_t *out)
{
	wvol_encode(vol, out);
}

/* The encoding of vol, made once per volume. */
static int encoding(struct watch *wt, const struct volume *vol)
{
	if (wt->fd >= 0 && wt->fd_seq == vol->seq)
		return wt->fd;
	if (wt->fd >= 0)
		close(wt->fd);
	wt->fd_size = wvol_size(vol);
	wt->fd = sealed_memfd("spindle-watch", wt->fd_size, fill_wvol, vol);
	if (wt->fd < 0) {
		int r = wt->fd;
		log_error("watch: cannot encode volume %llu: %s", (unsigned long long)vol->seq, strerror(-r));
		wt->fd = -1;
		return r;
	}
	wt->fd_seq = vol->seq;
	wt->stats.bytes += wt->fd_size;
	return wt->fd;
}

void watch_serve(struct watch *wt, const struct volume *shown, int64_t now_ns)
{
	if (!wt->count || !shown)
		return;
	bool sent = false;
	struct watch_entry *w, *tmp;
	link_for_each_safe(w, tmp, &wt->watchers, link) {
		if (w->sent_any && w->sent_seq == shown->seq)
			continue;
		if (!w->seen_any || w->seen_seq != shown->seq) {
			/* A new volume: the one seen before it, unsent, is skipped. */
			if (w->seen_any && (!w->sent_any || w->sent_seq != w->seen_seq)) {
				w->skipped++;
				wt->stats.skipped++;
			}
			w->seen_any = true;
			w->seen_seq = shown->seq;
		}
		if (w->in_flight || now_ns < w->next_ns)
			continue;
		int fd = encoding(wt, shown);
		if (fd < 0) {
			watch_remove(wt, w);
			wt->listener->send(wt->data, w, fd, 0, 0, 0);
			sent = true;
			continue;
		}
		uint64_t skipped = w->skipped;
		w->sent_any = true;
		w->sent_seq = shown->seq;
		w->skipped = 0;
		w->in_flight = true;
		w->next_ns = now_ns + (int64_t)w->period_ns;
		wt->stats.sent++;
		wt->listener->send(wt->data, w, fd, wt->fd_size, shown->seq, skipped);
		sent = true;
	}
	if (sent)
		wt->listener->answered(wt->data);
}

int64_t watch_next_due(const struct watch *wt)
{
	int64_t due = 0;
	const struct watch_entry *w;
	link_for_each(w, &wt->watchers, link) {
		/* Only one with a volume it has not had waits for its rate. */
		if (w->in_flight || !w->seen_any || (w->sent_any && w->sent_seq == w->seen_seq))
			continue;
		if (!due || w->next_ns < due)
			due = w->next_ns;
	}
	return due;
}
