/* spindle-gl: the one Spindle connection of the process and, for each GL
 * context, its layers on the display. Frames are paced by frame
 * callbacks, at most one in flight per context: a frame that finds one in
 * flight is dropped, so a slow display never blocks the program. Without
 * a daemon (or when it goes away) the program runs on after one warning,
 * and the layer reconnects when the daemon is back. Everything here runs
 * under one lock (libspindle is used from one thread at a time). */
#ifndef SPINDLE_GL_OUTPUT_H
#define SPINDLE_GL_OUTPUT_H

#include <stdbool.h>
#include <stdint.h>

#include "state.h"

enum sgl_send { SGL_SENT, SGL_DROPPED, SGL_OFFLINE };

struct sgl_out *sgl_out_create(uint32_t ctx_id);
/* Takes the context's layers off the display. */
void sgl_out_destroy(struct sgl_out *o);
/* At a frame's end: connects if it is time to try, handles the daemon's
 * events, and says whether a frame can go now (SGL_SENT), or would be
 * dropped (one in flight) or has no display. *h gets the display's half
 * height (volume |y| <= h), the last one known while offline. */
enum sgl_send sgl_out_poll(struct sgl_out *o, float *h);
/* Shows the frame: each call by reference (a layer showing the
 * segment's retained list, transform map * s) where that is affine, the
 * rest and the immediate geometry (stage space, which this may append
 * to) on one layer through map. */
enum sgl_send sgl_out_send(struct sgl_out *o, struct sgl_frame *f, const float map[16]);
/* The segment is going: destroys its retained lists. */
void sgl_out_seg_release(struct sgl_seg *seg);

#endif
