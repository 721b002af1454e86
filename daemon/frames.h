/* Who waits for which volume: frame callbacks of committed changes, and
 * captures; and telling them when their volume is shown.
 *
 * A frame callback belongs to a commit. When the pipeline takes a scene
 * (frames_tie()), every committed frame not yet tied is tied to that
 * volume; when the volume is swapped in with the projector lit
 * (frames_shown()) the frames tied to it or to an older one are done,
 * with its time, unless their commit came after that time: those wait for
 * a later revolution start (frames_revolution()). A volume swapped in
 * while dark is shown once the projector is lit (frames_lit()). A capture
 * takes the volume on display at the next revolution start while lit, or
 * at the next swap (frames_serve_captures()). */
#ifndef SPINDLE_FRAMES_H
#define SPINDLE_FRAMES_H

#include <stdbool.h>
#include <stdint.h>

#include "link.h"

struct volume;

/* A frame callback or a capture; embedded in the client's object. */
struct waiter {
	uint64_t volume_seq; /* frame: the first volume showing its commit (0: none yet) */
	int64_t commit_ns;   /* frame: when its commit was handled */
	struct link link;    /* a queue of struct frames, or its owner's until then */
};

#define FRAMES_LISTENER_VERSION 1

struct frames_listener {
	uint32_t version; /* FRAMES_LISTENER_VERSION */
	/* Frame w is done: volume seq is shown from time_ns on. w is off the
	 * queue; the listener answers and frees it. */
	void (*frame_done)(void *data, struct waiter *w, uint64_t seq, int64_t time_ns);
	/* Capture w is answered: fd is an .svol file in a sealed memfd of
	 * size bytes, valid during the call (the listener sends a copy), or
	 * a negative errno. w is off the queue; the listener frees it. */
	void (*capture_done)(void *data, struct waiter *w, int fd, uint64_t size);
	/* The frames or captures of one volume were answered: the events
	 * may go out now, one write per client. */
	void (*answered)(void *data);
};

struct frames {
	struct link frames;   /* committed frame callbacks, in commit order */
	struct link captures; /* captures asked for */
	uint64_t unseen_seq;  /* swapped in while the projector was dark */
	uint64_t shown_seq;   /* the volume on display, seen lit */
	/* Frames may wait for a revolution start of shown_seq: of commits
	 * made after it was swapped in, or tied to it when it was shown. */
	bool waiting;
	const struct frames_listener *listener;
	void *data;
};

void frames_init(struct frames *f, const struct frames_listener *listener, void *data);

/* Queues frame w of a commit handled at now_ns. */
void frames_commit(struct frames *f, struct waiter *w, int64_t now_ns);
/* Queues a capture. */
void frames_capture(struct frames *f, struct waiter *w);
/* Takes a waiter off its queue (a departing client's). */
void frames_remove(struct waiter *w);

/* The pipeline took a scene for volume seq: every committed frame not yet
 * tied is tied to it. Returns how many. */
unsigned frames_tie(struct frames *f, uint64_t seq);
/* Frames were tied to a volume that may be on display already: they are
 * answered at the next revolution start. */
void frames_wait_revolution(struct frames *f);

/* Volume seq was swapped in at time_ns. Shown only if lit; else once the
 * projector is lit. Returns whether it was shown (captures may be served). */
bool frames_shown(struct frames *f, uint64_t seq, int64_t time_ns, bool lit);
/* The projector was lit at time_ns: a volume swapped in while dark is
 * shown now. Returns whether there was one. */
bool frames_lit(struct frames *f, int64_t time_ns);
/* A boundary (a revolution start, or with half-turn swaps a half-turn
 * start) at time_ns, the projector lit. swap_pending: a newer volume may
 * be swapped in at this very start, and its report answers the frames
 * instead. Cheap when nothing waits. */
void frames_revolution(struct frames *f, int64_t time_ns, bool swap_pending);

/* Whether a capture waits. */
bool frames_capture_waiting(const struct frames *f);
/* Answers every waiting capture with the volume on display (NULL: none
 * yet, and they keep waiting). */
void frames_serve_captures(struct frames *f, const struct volume *shown);

#endif
