/* assimp on an open file, and its scene walked into a checked indexed mesh
 * (model_import.h). Nothing of the scene is trusted: assimp's validation
 * catches most broken scenes, and the walk checks again whatever it reads
 * (counts, pointers, indices, node depth) and that every coordinate is
 * finite, since assimp passes NaN and infinities through. */
#include "model_import.h"

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

/* Validation first (assimp runs it before anything else, the scene
 * preprocessor included, whose crashes on broken files it prevents), then
 * Triangulate, which splits polygons but leaves 1- and 2-index faces
 * (points, OBJ `l` segments) alone. No FindDegenerates (it would turn thin
 * triangles into lines) and no JoinIdenticalVertices (we emit flat arrays).
 * assimp 5.2's validation refuses a mesh without faces, which is how it
 * reads a PLY with vertices only; such a file is read again without any
 * step and kept only if every mesh is such a point cloud (the walk checks
 * it as it checks everything). */
#define IMPORT_FLAGS (aiProcess_ValidateDataStructure | aiProcess_Triangulate)
#define NO_FACES_ERROR "contains no faces"

/* A node tree deeper than this, or with more node visits, is refused (a
 * broken scene could hold a cycle). */
#define MAX_NODE_DEPTH 256
#define MAX_NODE_VISITS (1u << 20)

/* ---- the file, read through callbacks ---- */

struct fd_source {
	int fd;              /* the model, or -1: */
	const uint8_t *data; /* a companion in memory */
	uint64_t size;
	const char *name;
	const struct model_companions *comp;
	struct fd_source *companion; /* MODEL_COMPANIONS, made by fd_open() */
};

struct fd_file {
	struct aiFile file; /* first: assimp's pointer is ours */
	const struct fd_source *src;
	uint64_t pos;
};

static size_t fd_read(struct aiFile *f, char *buf, size_t size, size_t count)
{
	struct fd_file *ff = (struct fd_file *)f;
	if (size == 0 || count == 0 || ff->pos >= ff->src->size)
		return 0;
	size_t want = count > SIZE_MAX / size ? SIZE_MAX : size * count;
	if (want > ff->src->size - ff->pos)
		want = (size_t)(ff->src->size - ff->pos);
	size_t got = 0;
	if (ff->src->data) {
		memcpy(buf, ff->src->data + ff->pos, want);
		got = want;
	}
	while (got < want) {
		ssize_t n = pread(ff->src->fd, buf + got, want - got, (off_t)(ff->pos + got));
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			break;
		got += (size_t)n;
	}
	ff->pos += got;
	return got / size;
}

static size_t fd_write(struct aiFile *f, const char *buf, size_t size, size_t count)
{
	return 0;
}

static size_t fd_tell(struct aiFile *f)
{
	return (size_t)((struct fd_file *)f)->pos;
}

static size_t fd_size(struct aiFile *f)
{
	return (size_t)((struct fd_file *)f)->src->size;
}

/* assimp passes negative offsets as size_t: unsigned wrap-around adds them. */
static enum aiReturn fd_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
	struct fd_file *ff = (struct fd_file *)f;
	uint64_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? ff->pos : ff->src->size;
	if (origin != aiOrigin_SET && origin != aiOrigin_CUR && origin != aiOrigin_END)
		return aiReturn_FAILURE;
	uint64_t pos = base + (uint64_t)offset;
	if (pos > ff->src->size)
		return aiReturn_FAILURE;
	ff->pos = pos;
	return aiReturn_SUCCESS;
}

static void fd_flush(struct aiFile *f)
{
}

/* The source for a name assimp opens: the model, or a companion read for
 * it (matched by its file name: they all lie beside the model); NULL for
 * any other. */
static const struct fd_source *source_of(struct fd_source *model, const char *name)
{
	if (!strcmp(name, model->name))
		return model;
	const char *base = strrchr(name, '/');
	base = base ? base + 1 : name;
	for (unsigned i = 0; model->comp && i < model->comp->count; i++) {
		const struct model_companion *c = &model->comp->file[i];
		if (!strcmp(base, c->name)) {
			model->companion[i] =
				(struct fd_source){ .fd = -1, .data = c->data, .size = c->size, .name = c->name };
			return &model->companion[i];
		}
	}
	return NULL;
}

/* The model file or a companion, for reading: no other name opens. */
static struct aiFile *fd_open(struct aiFileIO *io, const char *name, const char *mode)
{
	const struct fd_source *src = name ? source_of((struct fd_source *)io->UserData, name) : NULL;
	if (!src || !mode || strpbrk(mode, "wa+"))
		return NULL;
	struct fd_file *ff = calloc(1, sizeof(*ff));
	if (!ff)
		return NULL;
	ff->file.ReadProc = fd_read;
	ff->file.WriteProc = fd_write;
	ff->file.TellProc = fd_tell;
	ff->file.FileSizeProc = fd_size;
	ff->file.SeekProc = fd_seek;
	ff->file.FlushProc = fd_flush;
	ff->src = src;
	return &ff->file;
}

static void fd_close(struct aiFileIO *io, struct aiFile *f)
{
	free(f);
}

/* ---- the walk ---- */

/* A pass over the scene counts (mesh NULL) or fills the mesh; the count
 * pass checks everything the fill pass reads. */
struct walk {
	const struct aiScene *scene;
	bool materials; /* material colours are the file's */
	struct model_mesh *mesh;
	size_t vertices, triangles, lines, points;
	size_t visits;
	const char *error; /* the reason the count pass stopped */
	int status;
};

static bool walk_fail(struct walk *w, int status, const char *why)
{
	if (!w->error) {
		w->error = why;
		w->status = status;
	}
	return false;
}

static bool check_face(struct walk *w, const struct aiMesh *mesh, const struct aiFace *f)
{
	if (f->mNumIndices == 0 || !f->mIndices)
		return walk_fail(w, EINVAL, "a face without vertices");
	if (f->mNumIndices > MODEL_MAX_PRIMITIVES)
		return walk_fail(w, E2BIG, "too many primitives");
	for (unsigned i = 0; i < f->mNumIndices; i++)
		if (f->mIndices[i] >= mesh->mNumVertices)
			return walk_fail(w, EINVAL, "a face index is out of range");
	if (f->mNumIndices == 1)
		w->points++;
	else if (f->mNumIndices == 2)
		w->lines++;
	else
		w->triangles += f->mNumIndices - 2u; /* Triangulate has run: 1; a fan otherwise */
	if (w->triangles + w->lines + w->points > MODEL_MAX_PRIMITIVES)
		return walk_fail(w, E2BIG, "too many primitives");
	return true;
}

static bool check_mesh(struct walk *w, const struct aiMesh *mesh)
{
	if (!mesh || (mesh->mNumVertices && !mesh->mVertices) || (mesh->mNumFaces && !mesh->mFaces))
		return walk_fail(w, EINVAL, "a malformed mesh");
	w->vertices += mesh->mNumVertices;
	if (w->vertices > MODEL_MAX_VERTICES)
		return walk_fail(w, E2BIG, "too many vertices");
	if (mesh->mNumFaces == 0) {
		/* A point cloud: assimp gives vertices and no faces. */
		w->points += mesh->mNumVertices;
		if (w->triangles + w->lines + w->points > MODEL_MAX_PRIMITIVES)
			return walk_fail(w, E2BIG, "too many primitives");
		return true;
	}
	for (unsigned i = 0; i < mesh->mNumFaces; i++)
		if (!check_face(w, mesh, &mesh->mFaces[i]))
			return false;
	return true;
}

static uint8_t color_byte(float c)
{
	if (!(c > 0.0f)) /* NaN too */
		return 0;
	return c >= 1.0f ? 255 : (uint8_t)lrintf(c * 255.0f);
}

/* The diffuse colour of the mesh's material, unless it is assimp's default
 * material (made up for files without materials: white for us). */
static bool material_color(const struct aiScene *scene, const struct aiMesh *mesh, struct aiColor4D *c)
{
	if (!scene->mMaterials || mesh->mMaterialIndex >= scene->mNumMaterials)
		return false;
	const struct aiMaterial *mat = scene->mMaterials[mesh->mMaterialIndex];
	struct aiString name;
	if (!mat)
		return false;
	if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS &&
	    name.length == strlen(AI_DEFAULT_MATERIAL_NAME) &&
	    memcmp(name.data, AI_DEFAULT_MATERIAL_NAME, name.length) == 0)
		return false;
	return aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, c) == aiReturn_SUCCESS;
}

static void put_color(uint8_t *dst, const struct aiColor4D *c)
{
	dst[0] = color_byte(c->r);
	dst[1] = color_byte(c->g);
	dst[2] = color_byte(c->b);
	dst[3] = color_byte(c->a);
}

/* Colours of the mesh's vertices at dst: its own, its material's, or white. */
static void fill_colors(struct walk *w, const struct aiMesh *mesh, uint8_t *dst)
{
	struct aiColor4D c = { 1.0f, 1.0f, 1.0f, 1.0f };
	const struct aiColor4D *own = mesh->mColors[0];
	if (!own && w->materials)
		material_color(w->scene, mesh, &c);
	for (unsigned i = 0; i < mesh->mNumVertices; i++) {
		put_color(&dst[4 * (size_t)i], own ? &own[i] : &c);
		if (memcmp(&dst[4 * (size_t)i], "\xff\xff\xff\xff", 4) != 0)
			w->mesh->colored = 1;
	}
}

static bool fill_vertices(struct walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh)
{
	float *dst = &w->mesh->vertices[3 * w->vertices];
	for (unsigned i = 0; i < mesh->mNumVertices; i++) {
		struct aiVector3D v = mesh->mVertices[i];
		aiTransformVecByMatrix4(&v, xf);
		if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z))
			return walk_fail(w, EINVAL, "a vertex coordinate is not finite (NaN or infinite)");
		dst[3 * i] = v.x;
		dst[3 * i + 1] = v.y;
		dst[3 * i + 2] = v.z;
	}
	fill_colors(w, mesh, &w->mesh->colors[4 * w->vertices]);
	return true;
}

/* Index arrays of the mesh: triangles, then segments, then points. */
static uint32_t *tri_at(struct walk *w)
{
	return &w->mesh->indices[3 * w->triangles++];
}

static uint32_t *line_at(struct walk *w)
{
	return &w->mesh->indices[3 * w->mesh->triangle_count + 2 * w->lines++];
}

static uint32_t *point_at(struct walk *w)
{
	return &w->mesh->indices[3 * w->mesh->triangle_count + 2 * w->mesh->line_count + w->points++];
}

static void fill_face(struct walk *w, uint32_t base, const struct aiFace *f)
{
	const unsigned *ix = f->mIndices;
	if (f->mNumIndices == 1) {
		*point_at(w) = base + ix[0];
	} else if (f->mNumIndices == 2) {
		uint32_t *seg = line_at(w);
		seg[0] = base + ix[0];
		seg[1] = base + ix[1];
	} else {
		for (unsigned i = 2; i < f->mNumIndices; i++) {
			uint32_t *tri = tri_at(w);
			tri[0] = base + ix[0];
			tri[1] = base + ix[i - 1];
			tri[2] = base + ix[i];
		}
	}
}

static bool fill_mesh(struct walk *w, const struct aiMatrix4x4 *xf, const struct aiMesh *mesh)
{
	uint32_t base = (uint32_t)w->vertices;
	if (!fill_vertices(w, xf, mesh))
		return false;
	w->vertices += mesh->mNumVertices;
	if (mesh->mNumFaces == 0) {
		for (unsigned i = 0; i < mesh->mNumVertices; i++)
			*point_at(w) = base + i;
		return true;
	}
	for (unsigned i = 0; i < mesh->mNumFaces; i++)
		fill_face(w, base, &mesh->mFaces[i]);
	return true;
}

static bool walk_node(struct walk *w, const struct aiNode *node, const struct aiMatrix4x4 *parent, unsigned depth)
{
	if (!node || depth > MAX_NODE_DEPTH || ++w->visits > MAX_NODE_VISITS)
		return walk_fail(w, EINVAL, node ? "a node tree too deep or too large" : "a malformed node tree");
	if ((node->mNumMeshes && !node->mMeshes) || (node->mNumChildren && !node->mChildren))
		return walk_fail(w, EINVAL, "a malformed node");
	/* world = parent * local (column vectors, as assimp applies them) */
	struct aiMatrix4x4 xf = *parent;
	aiMultiplyMatrix4(&xf, &node->mTransformation);

	for (unsigned i = 0; i < node->mNumMeshes; i++) {
		unsigned mi = node->mMeshes[i];
		if (mi >= w->scene->mNumMeshes || !w->scene->mMeshes)
			return walk_fail(w, EINVAL, "a node names a mesh that is not there");
		const struct aiMesh *mesh = w->scene->mMeshes[mi];
		if (!(w->mesh ? fill_mesh(w, &xf, mesh) : check_mesh(w, mesh)))
			return false;
	}
	for (unsigned i = 0; i < node->mNumChildren; i++)
		if (!walk_node(w, node->mChildren[i], &xf, depth + 1))
			return false;
	return true;
}

static bool walk_scene(struct walk *w)
{
	struct aiMatrix4x4 identity;
	aiIdentityMatrix4(&identity);
	w->vertices = w->triangles = w->lines = w->points = w->visits = 0;
	return !w->scene->mRootNode || walk_node(w, w->scene->mRootNode, &identity, 0);
}

static int alloc_mesh(struct model_mesh *mesh, const struct walk *w)
{
	size_t indices = 3 * w->triangles + 2 * w->lines + w->points;
	mesh->vertex_count = w->vertices;
	mesh->triangle_count = w->triangles;
	mesh->line_count = w->lines;
	mesh->point_count = w->points;
	mesh->vertices = malloc(3 * sizeof(float) * (w->vertices ? w->vertices : 1));
	mesh->colors = malloc(4 * (w->vertices ? w->vertices : 1));
	mesh->indices = malloc(sizeof(uint32_t) * (indices ? indices : 1));
	return mesh->vertices && mesh->colors && mesh->indices ? 0 : -ENOMEM;
}

/* An OBJ's materials are in its .mtl files: without them (none read for
 * it) assimp makes up a grey one for every `usemtl`. */
static bool own_materials(const char *name, const struct model_companions *comp)
{
	const char *dot = strrchr(name, '.');
	return !dot || strcasecmp(dot, ".obj") != 0 || (comp && comp->count > 0);
}

static int convert_scene(const struct aiScene *scene, const char *name, const struct model_companions *comp,
			 struct model_mesh *mesh, const char **why)
{
	struct walk w = { .scene = scene, .materials = own_materials(name, comp) };
	if (!walk_scene(&w)) {
		*why = w.error;
		return -w.status;
	}
	if (w.triangles + w.lines + w.points == 0) {
		*why = "no triangles, lines or points in the file";
		return -ENODATA;
	}
	if (alloc_mesh(mesh, &w) < 0) {
		*why = "out of memory";
		return -ENOMEM;
	}
	w.mesh = mesh;
	if (!walk_scene(&w)) {
		*why = w.error;
		return -w.status;
	}
	return 0;
}

static bool only_point_clouds(const struct aiScene *scene)
{
	if (!scene->mMeshes)
		return false;
	for (unsigned i = 0; i < scene->mNumMeshes; i++)
		if (!scene->mMeshes[i] || scene->mMeshes[i]->mNumFaces != 0)
			return false;
	return true;
}

/* The scene, or NULL with the reason in reason. */
static const struct aiScene *import(const char *name, struct aiFileIO *io, char *reason, size_t reason_size)
{
	const struct aiScene *scene = aiImportFileEx(name, IMPORT_FLAGS, io);
	if (scene)
		return scene;
	snprintf(reason, reason_size, "cannot load model: %s", aiGetErrorString());
	if (!strstr(reason, NO_FACES_ERROR))
		return NULL;
	scene = aiImportFileEx(name, 0, io);
	if (scene && !only_point_clouds(scene)) {
		aiReleaseImport(scene);
		scene = NULL;
	}
	return scene;
}

int model_import_fd(int fd, uint64_t size, const char *name, const struct model_companions *comp,
		    struct model_mesh *mesh, char *reason, size_t reason_size)
{
	struct fd_source companion[MODEL_COMPANIONS];
	struct fd_source src = { .fd = fd, .size = size, .name = name, .comp = comp, .companion = companion };
	struct aiFileIO io = { .OpenProc = fd_open, .CloseProc = fd_close, .UserData = (aiUserData)&src };
	const char *why = NULL;

	memset(mesh, 0, sizeof(*mesh));
	const struct aiScene *scene = import(name, &io, reason, reason_size);
	if (!scene)
		return -EINVAL;
	int ret = convert_scene(scene, name, comp, mesh, &why);
	aiReleaseImport(scene);
	if (ret < 0) {
		snprintf(reason, reason_size, "%s", why);
		model_mesh_free(mesh);
	}
	return ret;
}
