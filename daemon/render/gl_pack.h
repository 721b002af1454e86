/* The GL renderer's back end (gl_pack.c): the GPU halftone + pack pass of
 * a batch and collecting its output, and the naive pipeline's whole-image
 * readback packed on the CPU. On the state of render_gl_priv.h. Private to
 * daemon/render/. */
#ifndef SPINDLE_GL_PACK_H
#define SPINDLE_GL_PACK_H

#include <stdint.h>

struct render_gl;
struct gl_batch;

/* The storage buffers of the pack pass, all zero. 0 or -ENOMEM. */
int gl_pack_create_buffers(struct render_gl *r);
/* Queues the pack of the batch just drawn into out, with a fence. */
void gl_pack_batch(struct render_gl *r, struct gl_batch *out);
/* Waits for out's fence and appends its tiles to r->vol. 0 (also when
 * nothing is pending) or -ETIMEDOUT, -EIO, -ENOMEM, -EINVAL. */
int gl_pack_collect(struct render_gl *r, struct gl_batch *out);
/* The naive back end: reads image k back whole and packs it on the CPU. */
int gl_pack_naive(struct render_gl *r, uint32_t k);

#endif
