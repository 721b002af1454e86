/* Buffers: bytes that draws and volumes read, from a sealed memfd the
 * daemon maps read-only, or copied from the message (inline). Counted
 * against max-buffer-bytes, memory-budget and max-mappings. */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "client.h"
#include "config.h"

void buffers_destroy(struct buffer *b)
{
	if (b->inline_data)
		free((void *)b->map);
	else if (b->map)
		munmap((void *)b->map, b->size ? b->size : 1);
	objects_account_buffer(b->base.client, -(int64_t)b->size, b->map && !b->inline_data ? -1 : 0);
	free(b);
}

/* The fd must be a memfd sealed against shrinking, at least size bytes. */
static int check_memfd(struct client *c, int fd, uint64_t size)
{
	int seals = fcntl(fd, F_GET_SEALS);
	if (seals < 0)
		return client_fail(c, 1, PROTO_ERR_FD, "buffer fd is not a memfd");
	if (!(seals & F_SEAL_SHRINK))
		return client_fail(c, 1, PROTO_ERR_FD, "buffer memfd is not sealed against shrinking");
	struct stat st;
	if (fstat(fd, &st) < 0 || (uint64_t)st.st_size < size)
		return client_fail(c, 1, PROTO_ERR_FD, "buffer memfd smaller than its declared size %llu",
				   (unsigned long long)size);
	return 0;
}

int objects_create_buffer(struct client *c, uint32_t id, uint64_t size, int fd)
{
	int r = check_memfd(c, fd, size);
	if (r < 0)
		goto out_close;
	if (size > c->env->cfg->max_buffer_bytes - c->buffer_bytes || size > SIZE_MAX / 2) {
		r = client_fail(c, 1, PROTO_ERR_QUOTA, "buffers over %llu bytes",
				(unsigned long long)c->env->cfg->max_buffer_bytes);
		goto out_close;
	}
	if ((r = objects_budget_room(c, size)) < 0)
		goto out_close;
	if (size && c->env->totals->mappings >= c->env->cfg->max_mappings) {
		c->env->totals->refused_mappings++;
		r = client_fail(c, 1, PROTO_ERR_QUOTA, "the daemon maps as many buffers as it may (%u)",
				c->env->cfg->max_mappings);
		goto out_close;
	}
	struct buffer *b = calloc(1, sizeof(*b));
	if (!b) {
		r = client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
		goto out_close;
	}
	if (size) {
		void *map = mmap(NULL, size, PROT_READ, MAP_SHARED, fd, 0);
		if (map == MAP_FAILED) {
			free(b);
			r = client_fail(c, 1, PROTO_ERR_FD, "cannot map buffer: %s", strerror(errno));
			goto out_close;
		}
		b->map = map;
	}
	b->size = size;
	b->base.client = c;
	objects_account_buffer(c, (int64_t)size, size ? 1 : 0);
	r = object_register(c, &b->base, id, PROTO_IFACE_BUFFER);
	if (r < 0)
		buffers_destroy(b);
out_close:
	close(fd);
	return r;
}

/* Inline data is copied: the message's bytes go with the message. */
int objects_create_buffer_inline(struct client *c, uint32_t id, const void *data, uint32_t size)
{
	if (size > c->env->cfg->max_buffer_bytes - c->buffer_bytes)
		return client_fail(c, 1, PROTO_ERR_QUOTA, "buffers over %llu bytes",
				   (unsigned long long)c->env->cfg->max_buffer_bytes);
	if (objects_budget_room(c, size) < 0)
		return -EPROTO;
	struct buffer *b = calloc(1, sizeof(*b));
	void *copy = malloc(size ? size : 1);
	if (!b || !copy) {
		free(b);
		free(copy);
		return client_fail(c, 1, PROTO_ERR_NO_MEMORY, "out of memory");
	}
	if (size)
		memcpy(copy, data, size);
	b->map = copy;
	b->inline_data = true;
	b->size = size;
	b->base.client = c;
	objects_account_buffer(c, size, 0);
	int r = object_register(c, &b->base, id, PROTO_IFACE_BUFFER);
	if (r < 0)
		buffers_destroy(b);
	return r;
}

const struct proto_buffer_requests buffer_requests = {
	.destroy = objects_destroy_req,
};
