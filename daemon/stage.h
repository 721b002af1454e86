/* The stage: the committed scene of every client. Clients add their layers
 * when they make them, write the committed state on display.commit and
 * remove them when they go; the pipeline reads the stage, through
 * snapshot.c, when it builds a volume. The stage ranks the layers (priority,
 * then age), knows the exclusive owner, and is the one place that says
 * "the scene changed": its listener is told, and asks for a new volume. */
#ifndef SPINDLE_STAGE_H
#define SPINDLE_STAGE_H

#include <stdbool.h>
#include <stdint.h>

#include "layer.h"
#include "link.h"

#define STAGE_LISTENER_VERSION 1

struct stage_listener {
	uint32_t version; /* STAGE_LISTENER_VERSION */
	/* What the stage shows may have changed, or commits wait for frame
	 * callbacks: a new volume is wanted. */
	void (*changed)(void *data);
};

struct stage {
	struct link layers; /* struct stage_layer.link, in creation order */
	uint64_t serial;    /* layers added so far */
	const struct stage_listener *listener;
	void *data;
};

void stage_init(struct stage *s, const struct stage_listener *listener, void *data);

/* Puts a new layer on the stage, with its owner set; it shows nothing
 * until its committed state names a list. */
void stage_add(struct stage *s, struct stage_layer *y);
/* Takes a layer off the stage (again is harmless). Returns whether that
 * changed the scene; the caller says so with stage_changed(). */
bool stage_remove(struct stage_layer *y);

/* A commit or a removal may have changed the scene, or commits wait for
 * frames: tells the listener. */
void stage_changed(struct stage *s);

/* The owner whose visible exclusive layer is on the stage, or NULL.
 * Commits are refused so that there is at most one. */
const void *stage_exclusive_owner(const struct stage *s);

/* The layers the display shows, highest priority first (of equal ones,
 * the older): every visible layer with a list, or only the exclusive
 * owner's. Into *layers, grown as needed (*cap entries). Returns how
 * many, or -ENOMEM. */
int stage_shown_layers(const struct stage *s, const struct stage_layer ***layers, uint32_t *cap);

#endif
