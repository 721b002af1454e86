/* The GL renderer's back end (gl_pack.h): the GPU halftone + pack
 * pass over the touched tiles of a batch (gl_list_cs, gl_pack_cs), and the
 * CPU collecting its output behind a fence; and the naive pipeline's back
 * end, a whole-image glReadPixels packed on the CPU. */
#include "gl_pack.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "brightness.h"
#include "halftone.h"
#include "log.h"
#include "render_gl_priv.h"

/* The storage buffers of the pack pass: two output sets (double
 * buffering), the tile marks and the tile list, all zero. */
int gl_pack_create_buffers(struct render_gl *r)
{
	const struct gl_api *gl = r->gl;
	size_t tiles = (size_t)r->batch * r->tiles_per_image;
	for (int i = 0; i < 2; i++) {
		gl->GenBuffers(1, &r->out[i].tiles);
		gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->out[i].tiles);
		gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(tiles * VOLUME_TILE_BYTES), NULL, GL_STREAM_READ);
		gl->GenBuffers(1, &r->out[i].ids);
		gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->out[i].ids);
		gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((tiles + 1) * 4), NULL, GL_STREAM_READ);
	}
	/* The list: a 3-word header padded to 16 bytes, then (tile, rows). */
	uint32_t *zero = calloc(tiles * 2 + 4, 4);
	if (!zero)
		return -ENOMEM;
	gl->GenBuffers(1, &r->touched);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->touched);
	gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(tiles * 4), zero, GL_DYNAMIC_COPY);
	gl->GenBuffers(1, &r->tile_list);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->tile_list);
	gl->BufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)((tiles * 2 + 4) * 4), zero, GL_DYNAMIC_COPY);
	free(zero);
	return 0;
}

/* Queues halftone + pack of the batch just drawn into out: the touched
 * tiles are listed, then packed (and zeroed in the atlas) by an indirect
 * dispatch over the list. */
void gl_pack_batch(struct render_gl *r, struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	static const uint32_t zero = 0, list_head[3] = { 0, 1, 1 };
	uint32_t tiles = out->n * r->tiles_per_image;
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, out->ids);
	gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, 4, &zero);
	gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, r->tile_list);
	gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(list_head), list_head);
	gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
	gl->UseProgram(r->list);
	gl->Uniform1ui(r->list_count, tiles);
	gl->DispatchCompute((tiles + 63) / 64, 1, 1);
	gl->MemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);

	gl->UseProgram(r->pack);
	gl->ActiveTexture(GL_TEXTURE1);
	gl->BindTexture(GL_TEXTURE_2D, r->atlas);
	gl->Uniform1i(r->pack_colour, 1);
	gl->Uniform4ui(r->pack_uni, out->first, g->width, g->height, r->tiles_per_image);
	gl->BindImageTexture(0, r->atlas, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out->tiles);
	gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out->ids);
	/* Binding 2 holds the tile marks for the draws and the list pass; the
	 * pack pass reads the brightness pattern's tables there. */
	if (r->bright_buf)
		gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, r->bright_buf);
	gl->BindBuffer(GL_DISPATCH_INDIRECT_BUFFER, r->tile_list);
	gl->DispatchComputeIndirect(0);
	if (r->bright_buf)
		gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, r->touched);
	gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
			  GL_SHADER_STORAGE_BARRIER_BIT);
	out->fence = gl->FenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
	gl->Flush();
	gl->ActiveTexture(GL_TEXTURE0);
}

/* Reads the tile numbers of a packed batch into slot_of (each tile's slot
 * in the output, or -1). Returns how many tiles were packed, or -EIO when
 * the list cannot be read or is corrupt (out of range, repeated). */
static int map_slots(struct render_gl *r, const struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	uint32_t tiles = out->n * r->tiles_per_image;
	gl->BindBuffer(GL_COPY_READ_BUFFER, out->ids);
	const uint32_t *ids =
		gl->MapBufferRange(GL_COPY_READ_BUFFER, 0, (GLsizeiptr)((tiles + 1) * 4), GL_MAP_READ_BIT);
	if (!ids)
		return -EIO;
	uint32_t count = ids[0];
	int err = count > tiles ? -EIO : 0;
	for (uint32_t t = 0; t < tiles; t++)
		r->slot_of[t] = -1;
	for (uint32_t i = 0; err == 0 && i < count; i++) {
		if (ids[1 + i] >= tiles || r->slot_of[ids[1 + i]] >= 0)
			err = -EIO;
		else
			r->slot_of[ids[1 + i]] = (int32_t)i;
	}
	gl->UnmapBuffer(GL_COPY_READ_BUFFER);
	if (err < 0)
		log_error("GL renderer: the pack pass returned a corrupt tile list");
	return err < 0 ? err : (int)count;
}

/* Appends the tiles of a packed batch, mapped at data (their slots in
 * r->slot_of), to the volume in tile order. 0, or the first error. */
static int append_tiles(struct render_gl *r, const struct gl_batch *out, const uint8_t *data)
{
	int err = 0;
	for (uint32_t i = 0; err == 0 && i < out->n; i++) {
		const int32_t *slot = r->slot_of + (size_t)i * r->tiles_per_image;
		for (uint32_t t = 0; err == 0 && t < r->tiles_per_image; t++) {
			if (slot[t] < 0)
				continue;
			uint8_t *dst = volume_image_next(r->vol, out->first + i);
			if (!dst) {
				err = -ENOMEM;
				break;
			}
			memcpy(dst, data + (size_t)slot[t] * VOLUME_TILE_BYTES, VOLUME_TILE_BYTES);
			err = volume_image_push(r->vol, out->first + i, t);
		}
	}
	return err;
}

/* Waits for a packed batch and appends its tiles, in tile order, to the
 * volume. */
int gl_pack_collect(struct render_gl *r, struct gl_batch *out)
{
	const struct gl_api *gl = r->gl;
	if (!out->fence)
		return 0;
	uint64_t t0 = (uint64_t)now_ns();
	GLenum w = gl->ClientWaitSync(out->fence, GL_SYNC_FLUSH_COMMANDS_BIT, GL_FENCE_TIMEOUT_NS);
	gl->DeleteSync(out->fence);
	out->fence = NULL;
	uint64_t t1 = (uint64_t)now_ns();
	r->wait_ns += t1 - t0;
	if (w != GL_ALREADY_SIGNALED && w != GL_CONDITION_SATISFIED) {
		log_error("GL renderer: a batch did not finish within %llu s",
			  (unsigned long long)(GL_FENCE_TIMEOUT_NS / 1000000000ull));
		return -ETIMEDOUT;
	}
	int count = map_slots(r, out);
	if (count <= 0)
		return count;
	gl->BindBuffer(GL_COPY_READ_BUFFER, out->tiles);
	const uint8_t *data = gl->MapBufferRange(GL_COPY_READ_BUFFER, 0,
						 (GLsizeiptr)((size_t)count * VOLUME_TILE_BYTES), GL_MAP_READ_BIT);
	if (!data)
		return -EIO;
	int err = append_tiles(r, out, data);
	gl->UnmapBuffer(GL_COPY_READ_BUFFER);
	r->base.stats.tiles += (uint64_t)count;
	r->copy_ns += (uint64_t)now_ns() - t1;
	return err;
}

/* brightness_threshold() as halftone_rgba_with() takes it. */
static uint8_t bright_threshold(const void *ctx, uint32_t k, uint32_t u, uint32_t v)
{
	return brightness_threshold(ctx, k, u, v);
}

/* The naive pipeline's back end: the whole RGBA image read back,
 * halftoned (against the brightness model's thresholds where it thins) and
 * packed on the CPU. */
int gl_pack_naive(struct render_gl *r, uint32_t k)
{
	const struct gl_api *gl = r->gl;
	const struct geometry *g = &r->base.geom;
	uint64_t t0 = (uint64_t)now_ns();
	gl->ReadPixels(0, 0, (GLsizei)g->width, (GLsizei)g->height, GL_RGBA, GL_UNSIGNED_BYTE, r->rgba);
	uint64_t t1 = (uint64_t)now_ns();
	r->wait_ns += t1 - t0;
	int e = r->bright_on ? halftone_rgba_with(r->vol, k, r->rgba, bright_threshold, &r->bright)
			     : halftone_rgba_image(r->vol, k, r->rgba);
	if (e < 0)
		return e;
	r->copy_ns += (uint64_t)now_ns() - t1;
	return 0;
}
