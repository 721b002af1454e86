/* Model files: opened here, read by the sandboxed loader (model_sandbox.c,
 * model_import.c), checked again (model_wire.c); bounds and the fit. */
#include "model.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "model_import.h"
#include "model_sandbox.h"

static void set_err(char *err, size_t err_size, const char *path, const char *reason)
{
	if (err && err_size > 0)
		snprintf(err, err_size, "%s: %s", path, reason);
}

/* The file, opened here with the caller's rights (the loader has none):
 * a regular file only, so that a FIFO or a device cannot block it. */
static int open_model(const char *path, uint64_t *size)
{
	struct stat st;
	int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
	if (fd < 0)
		return -errno;
	int e = fstat(fd, &st) < 0 ? errno : S_ISREG(st.st_mode) ? 0 : EINVAL;
	if (e) {
		close(fd);
		return -e;
	}
	*size = (uint64_t)st.st_size;
	return fd;
}

struct model *model_load(const char *path, char *err, size_t err_size)
{
	char reason[512];
	struct model *m = NULL;
	uint64_t size = 0;
	int fd = open_model(path, &size);
	if (fd < 0) {
		set_err(err, err_size, path, fd == -EINVAL ? "not a regular file" : strerror(-fd));
		errno = -fd;
		return NULL;
	}
	struct model_companions comp;
	model_companions_read(fd, size, path, &comp); /* an OBJ's .mtl files */
	int ret = model_sandbox_load(fd, size, path, &comp, &m, reason, sizeof(reason));
	model_companions_free(&comp);
	close(fd);
	if (ret < 0) {
		set_err(err, err_size, path, reason);
		errno = -ret;
		return NULL;
	}
	return m;
}

void model_set_progress(FILE *f)
{
	model_sandbox_set_progress(f);
}

void model_destroy(struct model *m)
{
	if (!m)
		return;
	free(m->triangles);
	free(m->lines);
	free(m->points);
	free(m->triangle_colors);
	free(m->line_colors);
	free(m->point_colors);
	free(m);
}

size_t model_vertex_count(const struct model *m)
{
	return 3 * m->triangle_count + 2 * m->line_count + m->point_count;
}

/* Calls fn on each vertex of each primitive array. */
static void for_each_vertex(const struct model *m, void (*fn)(float *v, void *data), void *data)
{
	float *arrays[3] = { m->triangles, m->lines, m->points };
	size_t counts[3] = { 3 * m->triangle_count, 2 * m->line_count, m->point_count };

	for (int a = 0; a < 3; a++)
		for (size_t i = 0; i < counts[a]; i++)
			fn(&arrays[a][3 * i], data);
}

struct bounds {
	float min[3], max[3];
};

static void grow_bounds(float *v, void *data)
{
	struct bounds *b = data;
	for (int i = 0; i < 3; i++) {
		b->min[i] = fminf(b->min[i], v[i]);
		b->max[i] = fmaxf(b->max[i], v[i]);
	}
}

int model_bounds(const struct model *m, float min[3], float max[3])
{
	struct bounds b = { { INFINITY, INFINITY, INFINITY }, { -INFINITY, -INFINITY, -INFINITY } };

	if (model_vertex_count(m) == 0)
		return -ENODATA;
	for_each_vertex(m, grow_bounds, &b);
	memcpy(min, b.min, sizeof(b.min));
	memcpy(max, b.max, sizeof(b.max));
	return 0;
}

struct radius_search {
	float cx, cz;
	double r2;
};

static void grow_radius(float *v, void *data)
{
	struct radius_search *r = data;
	double dx = v[0] - r->cx, dz = v[2] - r->cz;
	r->r2 = fmax(r->r2, dx * dx + dz * dz);
}

int model_compute_fit(const struct model *m, float half_height, float margin, struct model_fit *out)
{
	float min[3], max[3];

	if (!(margin > 0.0f && margin <= 1.0f) || !(half_height > 0.0f))
		return -EINVAL;
	int ret = model_bounds(m, min, max);
	if (ret < 0)
		return ret;
	/* in double: min + max can overflow a float */
	for (int i = 0; i < 3; i++)
		out->centre[i] = (float)(0.5 * ((double)min[i] + max[i]));

	/* The bounding-box centre is not the smallest enclosing circle's, but it
	 * is predictable ("centred" means the box is), and costs little room. */
	struct radius_search r = { out->centre[0], out->centre[2], 0.0 };
	for_each_vertex(m, grow_radius, &r);
	double radius = sqrt(r.r2);
	double half_y = 0.5 * ((double)max[1] - min[1]);

	double scale = INFINITY;
	if (radius > 0.0)
		scale = margin / radius;
	if (half_y > 0.0)
		scale = fmin(scale, margin * half_height / half_y);
	/* A model a few denormals wide needs more than a float holds: it gets
	 * the largest (model_apply_fit() works in double). */
	out->scale = isfinite(scale) ? (float)fmin(scale, FLT_MAX) : 1.0f;
	return 0;
}

static void apply_fit(float *v, void *data)
{
	const struct model_fit *fit = data;
	for (int i = 0; i < 3; i++)
		v[i] = (float)(((double)v[i] - fit->centre[i]) * fit->scale);
}

void model_apply_fit(struct model *m, const struct model_fit *fit)
{
	for_each_vertex(m, apply_fit, (void *)fit);
}
