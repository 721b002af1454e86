#include "model.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Only Triangulate: it splits polygons but leaves 1- and 2-index faces
 * (points, OBJ `l` segments) alone. No FindDegenerates (it would turn thin
 * triangles into lines) and no JoinIdenticalVertices (we emit flat arrays,
 * so shared vertices buy nothing). assimp 5.2.4 reads a PLY with vertices
 * only as a mesh with no faces and primitive type POINT; walk_mesh() turns
 * that into points, so no PLY reader of our own is needed. */
#define MODEL_IMPORT_FLAGS (aiProcess_Triangulate)

/* A pass over the scene either counts primitives (out arrays NULL) or
 * writes them at the cursors. */
struct model_walk {
	struct model *m;
	bool fill;
};

static void set_err(char *err, size_t err_size, const char *fmt, const char *a, const char *b)
{
	if (err && err_size > 0)
		snprintf(err, err_size, fmt, a, b);
}

static void put_vertex(float *dst, const struct aiMatrix4x4 *xf, struct aiVector3D v)
{
	aiTransformVecByMatrix4(&v, xf);
	dst[0] = v.x;
	dst[1] = v.y;
	dst[2] = v.z;
}

static void emit_point(struct model_walk *w, const struct aiMatrix4x4 *xf, struct aiVector3D v)
{
	if (w->fill)
		put_vertex(&w->m->points[3 * w->m->point_count], xf, v);
	w->m->point_count++;
}

static void emit_line(struct model_walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh, unsigned a,
		      unsigned b)
{
	if (w->fill) {
		float *dst = &w->m->lines[6 * w->m->line_count];
		put_vertex(dst, xf, mesh->mVertices[a]);
		put_vertex(dst + 3, xf, mesh->mVertices[b]);
	}
	w->m->line_count++;
}

static void emit_triangle(struct model_walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh, unsigned a,
			  unsigned b, unsigned c)
{
	if (w->fill) {
		float *dst = &w->m->triangles[9 * w->m->triangle_count];
		put_vertex(dst, xf, mesh->mVertices[a]);
		put_vertex(dst + 3, xf, mesh->mVertices[b]);
		put_vertex(dst + 6, xf, mesh->mVertices[c]);
	}
	w->m->triangle_count++;
}

static void walk_face(struct model_walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh,
		      const struct aiFace *f)
{
	const unsigned *ix = f->mIndices;

	if (f->mNumIndices == 1) {
		emit_point(w, xf, mesh->mVertices[ix[0]]);
	} else if (f->mNumIndices == 2) {
		emit_line(w, xf, mesh, ix[0], ix[1]);
	} else {
		/* Triangulate has run, so n == 3; a fan keeps us correct anyway. */
		for (unsigned i = 2; i < f->mNumIndices; i++)
			emit_triangle(w, xf, mesh, ix[0], ix[i - 1], ix[i]);
	}
}

static void walk_mesh(struct model_walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh)
{
	if (mesh->mNumFaces == 0) {
		/* A point cloud: assimp gives vertices and no faces. */
		for (unsigned i = 0; i < mesh->mNumVertices; i++)
			emit_point(w, xf, mesh->mVertices[i]);
		return;
	}
	for (unsigned i = 0; i < mesh->mNumFaces; i++)
		walk_face(w, xf, mesh, &mesh->mFaces[i]);
}

static void walk_node(struct model_walk *w, const struct aiScene *scene, const struct aiNode *node,
		      const struct aiMatrix4x4 *parent)
{
	/* world = parent * local (column vectors, as assimp applies them) */
	struct aiMatrix4x4 xf = *parent;
	aiMultiplyMatrix4(&xf, &node->mTransformation);

	for (unsigned i = 0; i < node->mNumMeshes; i++) {
		unsigned mi = node->mMeshes[i];
		if (mi < scene->mNumMeshes)
			walk_mesh(w, &xf, scene->mMeshes[mi]);
	}
	for (unsigned i = 0; i < node->mNumChildren; i++)
		walk_node(w, scene, node->mChildren[i], &xf);
}

static void walk_scene(struct model_walk *w, const struct aiScene *scene)
{
	struct aiMatrix4x4 identity;
	aiIdentityMatrix4(&identity);
	w->m->triangle_count = w->m->line_count = w->m->point_count = 0;
	if (scene->mRootNode)
		walk_node(w, scene, scene->mRootNode, &identity);
}

/* calloc of n records of rec floats, at least one byte so NULL means failure. */
static float *alloc_floats(size_t n, size_t rec)
{
	return calloc(n ? n * rec : 1, sizeof(float));
}

static int convert_scene(struct model *m, const struct aiScene *scene)
{
	struct model_walk w = { .m = m, .fill = false };

	walk_scene(&w, scene);
	if (m->triangle_count + m->line_count + m->point_count == 0)
		return -ENODATA;
	m->triangles = alloc_floats(m->triangle_count, 9);
	m->lines = alloc_floats(m->line_count, 6);
	m->points = alloc_floats(m->point_count, 3);
	if (!m->triangles || !m->lines || !m->points)
		return -ENOMEM;
	w.fill = true;
	walk_scene(&w, scene);
	return 0;
}

struct model *model_load(const char *path, char *err, size_t err_size)
{
	struct stat st;
	if (stat(path, &st) < 0) {
		int e = errno;
		set_err(err, err_size, "%s: %s", path, strerror(e));
		errno = e;
		return NULL;
	}

	const struct aiScene *scene = aiImportFile(path, MODEL_IMPORT_FLAGS);
	if (!scene) {
		set_err(err, err_size, "%s: cannot load model: %s", path, aiGetErrorString());
		errno = EINVAL;
		return NULL;
	}

	struct model *m = calloc(1, sizeof(*m));
	int ret = m ? convert_scene(m, scene) : -ENOMEM;
	aiReleaseImport(scene);
	if (ret < 0) {
		set_err(err, err_size, "%s: %s", path,
			ret == -ENODATA ? "no triangles, lines or points in the file" : strerror(-ret));
		model_destroy(m);
		errno = -ret;
		return NULL;
	}
	return m;
}

void model_destroy(struct model *m)
{
	if (!m)
		return;
	free(m->triangles);
	free(m->lines);
	free(m->points);
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
	for (int i = 0; i < 3; i++)
		out->centre[i] = 0.5f * (min[i] + max[i]);

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
	out->scale = isfinite(scale) ? (float)scale : 1.0f;
	return 0;
}

static void apply_fit(float *v, void *data)
{
	const struct model_fit *fit = data;
	for (int i = 0; i < 3; i++)
		v[i] = (v[i] - fit->centre[i]) * fit->scale;
}

void model_apply_fit(struct model *m, const struct model_fit *fit)
{
	for_each_vertex(m, apply_fit, (void *)fit);
}
