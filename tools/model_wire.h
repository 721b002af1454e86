/* What the model loader child (model_sandbox.c) sends its parent over a
 * pipe, and the parent's checks of it. The child is not trusted: the parent
 * reads a fixed header, checks its counts against the limits below before
 * allocating anything, reads exactly the payload they give, and checks
 * every coordinate (finite) and every index (below the vertex count) while
 * it builds the flat arrays of struct model.
 *
 * The message, in host byte order (both ends are the same program):
 *
 *   struct model_wire_header
 *   status != 0: text_len bytes of a reason (not NUL-terminated)
 *   status == 0: float    vertices[3 * vertex_count]
 *                uint8_t  colors[4 * vertex_count]   (flag MODEL_WIRE_COLORS)
 *                uint32_t indices[3 * triangle_count + 2 * line_count + point_count]
 *                         (triangles, then segments, then points)
 *
 * and then the end of the pipe. */
#ifndef SPINDLE_TOOLS_MODEL_WIRE_H
#define SPINDLE_TOOLS_MODEL_WIRE_H

#include <stddef.h>
#include <stdint.h>

#include "model.h"

#define MODEL_WIRE_MAGIC 0x444d5053u /* "SPMD" */
#define MODEL_WIRE_COLORS 1u

/* Far over what a display shows, low enough that every size below fits in
 * 32 bits of index and a few GiB of memory. */
#define MODEL_MAX_VERTICES (1u << 24)
#define MODEL_MAX_PRIMITIVES (1u << 24) /* triangles + segments + points */
#define MODEL_MAX_TEXT 1024u

struct model_wire_header {
	uint32_t magic;
	uint32_t status; /* 0, or an errno value (EINVAL, ENODATA, E2BIG, ENOMEM, EPERM) */
	uint32_t flags;
	uint32_t text_len;
	uint64_t vertex_count, triangle_count, line_count, point_count;
};

/* An indexed mesh, the loader's result: what the message carries. */
struct model_mesh {
	float *vertices;   /* 3 per vertex */
	uint8_t *colors;   /* 4 per vertex (RGBA) */
	uint32_t *indices; /* triangles, then segments, then points */
	size_t vertex_count, triangle_count, line_count, point_count;
	int colored; /* a colour other than opaque white: colors are sent */
};

void model_mesh_free(struct model_mesh *mesh);

/* The header that goes before mesh. */
struct model_wire_header model_wire_mesh_header(const struct model_mesh *mesh);

/* The child's side: 0 or -errno (the pipe broke). */
int model_wire_send_mesh(int fd, const struct model_mesh *mesh);
int model_wire_send_error(int fd, int status, const char *text);

/* The parent's side. Checks a header; *payload gets the bytes that must
 * follow it. 0, or -EINVAL with why filled. */
int model_wire_check_header(const struct model_wire_header *h, size_t *payload, char *why, size_t why_size);
/* The reason of an error message, made printable (anything but printable
 * ASCII becomes '?') into out (out_size > 0). */
void model_wire_error_text(const uint8_t *text, size_t len, char *out, size_t out_size);
/* The errno an error message's status stands for (EINVAL unless one of
 * the values the child sends). */
int model_wire_error_errno(uint32_t status);
/* Builds the model from a checked header (status 0) and its payload.
 * 0; -EINVAL (why filled: an index out of range, a coordinate not finite),
 * -ENODATA (no primitives) or -ENOMEM. */
int model_wire_decode(const struct model_wire_header *h, const uint8_t *payload, struct model **out, char *why,
		      size_t why_size);

#endif
