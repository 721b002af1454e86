/* The loader's result on the pipe (model_wire.h): sending it, and checking
 * it as input from an untrusted process. */
#include "model_wire.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fdio.h"
void model_mesh_free(struct model_mesh *mesh)
{
	free(mesh->vertices);
	free(mesh->colors);
	free(mesh->indices);
	memset(mesh, 0, sizeof(*mesh));
}

static size_t index_count(size_t triangles, size_t lines, size_t points)
{
	return 3 * triangles + 2 * lines + points;
}

struct model_wire_header model_wire_mesh_header(const struct model_mesh *mesh)
{
	return (struct model_wire_header){
		.magic = MODEL_WIRE_MAGIC,
		.flags = mesh->colored ? MODEL_WIRE_COLORS : 0,
		.vertex_count = mesh->vertex_count,
		.triangle_count = mesh->triangle_count,
		.line_count = mesh->line_count,
		.point_count = mesh->point_count,
	};
}

int model_wire_send_mesh(int fd, const struct model_mesh *mesh)
{
	struct model_wire_header h = model_wire_mesh_header(mesh);
	size_t indices = index_count(mesh->triangle_count, mesh->line_count, mesh->point_count);
	int ret = fd_write_all(fd, &h, sizeof(h));
	if (ret == 0)
		ret = fd_write_all(fd, mesh->vertices, 3 * sizeof(float) * mesh->vertex_count);
	if (ret == 0 && mesh->colored)
		ret = fd_write_all(fd, mesh->colors, 4 * mesh->vertex_count);
	if (ret == 0)
		ret = fd_write_all(fd, mesh->indices, sizeof(uint32_t) * indices);
	return ret;
}

int model_wire_send_error(int fd, int status, const char *text)
{
	size_t len = strlen(text);
	struct model_wire_header h = {
		.magic = MODEL_WIRE_MAGIC,
		.status = status > 0 ? (uint32_t)status : EINVAL,
		.text_len = len < MODEL_MAX_TEXT ? (uint32_t)len : MODEL_MAX_TEXT,
	};
	int ret = fd_write_all(fd, &h, sizeof(h));
	return ret == 0 ? fd_write_all(fd, text, h.text_len) : ret;
}

static int fail(char *why, size_t why_size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int fail(char *why, size_t why_size, const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	if (why && why_size > 0)
		vsnprintf(why, why_size, fmt, ap);
	va_end(ap);
	return -EINVAL;
}

int model_wire_check_header(const struct model_wire_header *h, size_t *payload, char *why, size_t why_size)
{
	if (h->magic != MODEL_WIRE_MAGIC)
		return fail(why, why_size, "bad magic 0x%08x", h->magic);
	if (h->status != 0) {
		if (h->text_len > MODEL_MAX_TEXT || h->flags || h->vertex_count || h->triangle_count || h->line_count ||
		    h->point_count)
			return fail(why, why_size, "a bad error header");
		*payload = h->text_len;
		return 0;
	}
	if (h->flags & ~MODEL_WIRE_COLORS || h->text_len)
		return fail(why, why_size, "unknown flags 0x%x", h->flags);
	if (h->vertex_count > MODEL_MAX_VERTICES)
		return fail(why, why_size, "%llu vertices", (unsigned long long)h->vertex_count);
	/* Each count is checked alone first, so the sum cannot wrap. */
	if (h->triangle_count > MODEL_MAX_PRIMITIVES || h->line_count > MODEL_MAX_PRIMITIVES ||
	    h->point_count > MODEL_MAX_PRIMITIVES ||
	    h->triangle_count + h->line_count + h->point_count > MODEL_MAX_PRIMITIVES)
		return fail(why, why_size, "too many primitives");
	size_t per_vertex = 3 * sizeof(float) + (h->flags & MODEL_WIRE_COLORS ? 4 : 0);
	*payload = per_vertex * h->vertex_count +
		   sizeof(uint32_t) * index_count(h->triangle_count, h->line_count, h->point_count);
	return 0;
}

void model_wire_error_text(const uint8_t *text, size_t len, char *out, size_t out_size)
{
	size_t n = len < out_size - 1 ? len : out_size - 1;
	for (size_t i = 0; i < n; i++)
		out[i] = text[i] >= 0x20 && text[i] < 0x7f ? (char)text[i] : '?';
	out[n] = '\0';
}

int model_wire_error_errno(uint32_t status)
{
	switch (status) {
	case ENODATA:
	case E2BIG:
	case ENOMEM:
	case EPERM:
		return (int)status;
	default:
		return EINVAL;
	}
}

/* The payload, cut into its arrays. */
struct wire_arrays {
	const float *vertices;
	const uint8_t *colors; /* NULL without MODEL_WIRE_COLORS */
	const uint32_t *indices;
	size_t vertex_count;
};

/* Copies n vertices picked by idx (checked) into xyz and, with colours, rgba. */
static int gather(const struct wire_arrays *w, const uint32_t *idx, size_t n, float *xyz, uint8_t *rgba)
{
	for (size_t i = 0; i < n; i++) {
		uint32_t v = idx[i];
		if (v >= w->vertex_count)
			return -ERANGE;
		memcpy(&xyz[3 * i], &w->vertices[3 * (size_t)v], 3 * sizeof(float));
		if (rgba)
			memcpy(&rgba[4 * i], &w->colors[4 * (size_t)v], 4);
	}
	return 0;
}

static bool all_finite(const float *v, size_t n)
{
	for (size_t i = 0; i < n; i++)
		if (!isfinite(v[i]))
			return false;
	return true;
}

/* calloc of at least one byte, so NULL means failure. */
static void *alloc_array(size_t n, size_t size)
{
	return calloc(n ? n : 1, size);
}

static int alloc_model(struct model *m, bool colors)
{
	m->triangles = alloc_array(9 * m->triangle_count, sizeof(float));
	m->lines = alloc_array(6 * m->line_count, sizeof(float));
	m->points = alloc_array(3 * m->point_count, sizeof(float));
	if (!m->triangles || !m->lines || !m->points)
		return -ENOMEM;
	if (!colors)
		return 0;
	m->triangle_colors = alloc_array(12 * m->triangle_count, 1);
	m->line_colors = alloc_array(8 * m->line_count, 1);
	m->point_colors = alloc_array(4 * m->point_count, 1);
	return m->triangle_colors && m->line_colors && m->point_colors ? 0 : -ENOMEM;
}

static int fill_model(struct model *m, const struct wire_arrays *w)
{
	const uint32_t *idx = w->indices;
	int ret = gather(w, idx, 3 * m->triangle_count, m->triangles, m->triangle_colors);
	idx += 3 * m->triangle_count;
	if (ret == 0)
		ret = gather(w, idx, 2 * m->line_count, m->lines, m->line_colors);
	idx += 2 * m->line_count;
	if (ret == 0)
		ret = gather(w, idx, m->point_count, m->points, m->point_colors);
	return ret;
}

int model_wire_decode(const struct model_wire_header *h, const uint8_t *payload, struct model **out, char *why,
		      size_t why_size)
{
	bool colors = h->flags & MODEL_WIRE_COLORS;
	struct wire_arrays w = { .vertices = (const float *)payload, .vertex_count = h->vertex_count };
	w.colors = colors ? payload + 3 * sizeof(float) * w.vertex_count : NULL;
	w.indices = (const uint32_t *)(payload + (3 * sizeof(float) + (colors ? 4 : 0)) * w.vertex_count);

	if (h->triangle_count + h->line_count + h->point_count == 0) {
		snprintf(why, why_size, "no triangles, lines or points in the file");
		return -ENODATA;
	}
	if (!all_finite(w.vertices, 3 * w.vertex_count))
		return fail(why, why_size, "a vertex coordinate is not finite");
	struct model *m = calloc(1, sizeof(*m));
	if (!m)
		return -ENOMEM;
	m->triangle_count = h->triangle_count;
	m->line_count = h->line_count;
	m->point_count = h->point_count;
	int ret = alloc_model(m, colors);
	if (ret == 0 && fill_model(m, &w) < 0)
		ret = fail(why, why_size, "an index out of range");
	if (ret < 0) {
		if (ret == -ENOMEM)
			snprintf(why, why_size, "%s", strerror(ENOMEM));
		model_destroy(m);
		return ret;
	}
	*out = m;
	return 0;
}
