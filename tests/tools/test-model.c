/* Model loading of every supported kind of file, node transforms, colours
 * (per vertex, per material), errors, and the fit into the display
 * cylinder. argv[1]: tests/data; argv[2]: a directory for the files the
 * test writes. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "model.h"
#include "testvol.h"

static const char *data_dir, *work_dir;

static struct model *load(const char *name)
{
	char path[4096], err[512];
	snprintf(path, sizeof(path), "%s/%s", data_dir, name);
	struct model *m = model_load(path, err, sizeof(err));
	if (!m)
		fprintf(stderr, "%s\n", err);
	CHECK(m);
	return m;
}

static void check_counts(const char *name, size_t tris, size_t lines, size_t points)
{
	struct model *m = load(name);
	printf("%s: %zu triangles, %zu lines, %zu points\n", name, m->triangle_count, m->line_count, m->point_count);
	CHECK(m->triangle_count == tris);
	CHECK(m->line_count == lines);
	CHECK(m->point_count == points);
	/* none of these has colours of its own */
	CHECK(!m->triangle_colors && !m->line_colors && !m->point_colors);
	model_destroy(m);
}

/* Writes text to work_dir/name; returns the path (static). */
static const char *write_file(const char *name, const char *text)
{
	static char path[4096];
	snprintf(path, sizeof(path), "%s/%s", work_dir, name);
	FILE *f = fopen(path, "w");
	CHECK(f);
	CHECK(fputs(text, f) >= 0);
	CHECK(fclose(f) == 0);
	return path;
}

static struct model *load_path(const char *path)
{
	char err[512];
	struct model *m = model_load(path, err, sizeof(err));
	if (!m)
		fprintf(stderr, "%s\n", err);
	CHECK(m);
	return m;
}

static void test_vertex_colors(void)
{
	static const uint8_t want[24] = { 255, 0,   0, 255, 0,  255, 0,  255, 0, 0, 255, 255,
					  0,   255, 0, 255, 10, 20,  30, 255, 0, 0, 255, 255 };
	struct model *m = load_path(write_file(
		"colored.ply",
		"ply\nformat ascii 1.0\nelement vertex 4\n"
		"property float x\nproperty float y\nproperty float z\n"
		"property uchar red\nproperty uchar green\n"
		"property uchar blue\nelement face 2\n"
		"property list uchar int vertex_indices\nend_header\n"
		"0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n"
		"1 1 0 10 20 30\n3 0 1 2\n3 1 3 2\n"));
	CHECK(m->triangle_count == 2 && m->triangle_colors && m->line_colors && m->point_colors);
	CHECK(memcmp(m->triangle_colors, want, sizeof(want)) == 0);
	model_destroy(m);

	/* a point cloud, with alpha */
	m = load_path(write_file("colored-points.ply",
				 "ply\nformat ascii 1.0\nelement vertex 2\n"
				 "property float x\nproperty float y\nproperty float z\n"
				 "property uchar red\nproperty uchar green\nproperty uchar blue\n"
				 "property uchar alpha\nend_header\n"
				 "0 0 0 255 0 0 128\n1 0 0 0 255 0 255\n"));
	CHECK(m->point_count == 2 && m->point_colors);
	CHECK(memcmp(m->point_colors, "\xff\x00\x00\x80\x00\xff\x00\xff", 8) == 0);
	model_destroy(m);
}

static void test_material_colors(void)
{
	/* transformed.gltf's triangle with a material: base colour (1, 0.5, 0) */
	static const char gltf[] =
		"{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
		"\"nodes\":[{\"mesh\":0}],\"materials\":[{\"pbrMetallicRoughness\":"
		"{\"baseColorFactor\":[1,0.5,0,1]}}],\"meshes\":[{\"primitives\":[{\"attributes\":"
		"{\"POSITION\":0},\"material\":0,\"mode\":4}]}],\"accessors\":[{\"bufferView\":0,"
		"\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}],"
		"\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"buffers\":[{\"byteLength\":36,"
		"\"uri\":\"data:application/octet-stream;base64,"
		"AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}]}";
	struct model *m = load_path(write_file("material.gltf", gltf));
	CHECK(m->triangle_count == 1 && m->triangle_colors);
	for (int v = 0; v < 3; v++)
		CHECK(memcmp(&m->triangle_colors[4 * v], "\xff\x80\x00\xff", 4) == 0);
	model_destroy(m);

	/* An OBJ's .mtl is another file: read beside it by the parent and
	 * handed to the loader, which may open nothing itself. */
	write_file("side.mtl", "newmtl red\nKd 1 0 0\nnewmtl green\nKd 0 1 0\n");
	m = load_path(write_file("side.obj", "mtllib side.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n"
					     "usemtl green\nf 3 2 1"));
	CHECK(m->triangle_count == 2 && m->triangle_colors);
	for (int v = 0; v < 6; v++)
		CHECK(memcmp(&m->triangle_colors[4 * v], v < 3 ? "\xff\x00\x00\xff" : "\x00\xff\x00\xff", 4) == 0);
	model_destroy(m);
	/* Only plain names beside the model are followed (no path, nothing
	 * hidden), and a missing one is no error: the materials show white. */
	m = load_path(write_file("far.obj", "mtllib ../side.mtl .side.mtl missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
					    "usemtl red\nf 1 2 3\n"));
	CHECK(m->triangle_count == 1 && !m->triangle_colors);
	model_destroy(m);
}

static void test_lines_obj(void)
{
	/* l 1 4 and the polyline l 2 4 3, in file order */
	static const float want[18] = { 0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 1, 0 };
	struct model *m = load("lines.obj");
	CHECK(memcmp(m->lines, want, sizeof(want)) == 0);
	model_destroy(m);
}

static void test_node_transforms(void)
{
	/* parent: translate (10, 0, 0); child: scale 2; triangle (0,0,0) (1,0,0) (0,1,0) */
	static const float want[9] = { 10, 0, 0, 12, 0, 0, 10, 2, 0 };
	struct model *m = load("transformed.gltf");
	CHECK(m->triangle_count == 1);
	for (int i = 0; i < 9; i++)
		CHECK(fabsf(m->triangles[i] - want[i]) < 1e-5f);
	model_destroy(m);
}

static void test_errors(void)
{
	char err[256] = "";
	errno = 0;
	CHECK(model_load("/nonexistent/model.stl", err, sizeof(err)) == NULL);
	CHECK(errno == ENOENT);
	CHECK(strstr(err, "/nonexistent/model.stl") != NULL);

	char path[4096];
	snprintf(path, sizeof(path), "%s/convert-bunny.js", data_dir);
	errno = 0;
	CHECK(model_load(path, err, sizeof(err)) == NULL);
	CHECK(errno == EINVAL || errno == ENODATA);
	printf("error message: %s\n", err);

	const char *nan = write_file("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n");
	errno = 0;
	CHECK(model_load(nan, err, sizeof(err)) == NULL);
	printf("error message: %s\n", err);
	CHECK(errno == EINVAL);
	CHECK(strncmp(err, nan, strlen(nan)) == 0 && strstr(err, "not finite"));

	errno = 0;
	CHECK(model_load(data_dir, err, sizeof(err)) == NULL);
	CHECK(errno == EINVAL && strstr(err, "not a regular file"));
}

static void check_fit(const char *name, float h)
{
	struct model *m = load(name);
	struct model_fit fit;
	float min[3], max[3];
	CHECK(model_compute_fit(m, h, 0.95f, &fit) == 0);
	model_apply_fit(m, &fit);
	CHECK(model_bounds(m, min, max) == 0);

	double r_max = 0.0;
	const float *arrays[3] = { m->triangles, m->lines, m->points };
	size_t counts[3] = { 3 * m->triangle_count, 2 * m->line_count, m->point_count };
	for (int a = 0; a < 3; a++)
		for (size_t i = 0; i < counts[a]; i++)
			r_max = fmax(r_max, hypot(arrays[a][3 * i], arrays[a][3 * i + 2]));
	printf("%s fitted to h=%.2f: y [%.4f, %.4f], max radius %.4f\n", name, h, min[1], max[1], r_max);
	CHECK(r_max <= 0.95 + 1e-5);
	CHECK(max[1] <= 0.95f * h + 1e-5f && min[1] >= -0.95f * h - 1e-5f);
	/* centred: the bounding box is symmetric about the origin */
	for (int i = 0; i < 3; i++)
		CHECK(fabsf(min[i] + max[i]) < 1e-4f);
	/* tight: one of the two limits is reached */
	CHECK(r_max > 0.95 - 1e-4 || max[1] > 0.95f * h - 1e-4f);
	model_destroy(m);
}

int main(int argc, char **argv)
{
	CHECK(argc == 3);
	data_dir = argv[1];
	work_dir = argv[2];
	check_counts("cube.stl", 12, 0, 0);
	check_counts("lines.obj", 1, 3, 0);
	check_counts("points.ply", 0, 0, 5);
	check_counts("bunny.ply", 3674, 0, 0);
	test_lines_obj();
	test_node_transforms();
	test_errors();
	test_vertex_colors();
	test_material_colors();
	check_fit("bunny.ply", 1.0f);
	check_fit("bunny.ply", 0.3f);
	check_fit("cube.stl", 1.0f);
	check_fit("lines.obj", 2.0f);
	check_fit("points.ply", 1.0f);

	struct model_fit fit;
	struct model *m = load("cube.stl");
	CHECK(model_compute_fit(m, 1.0f, 0.0f, &fit) == -EINVAL);
	CHECK(model_compute_fit(m, 0.0f, 0.95f, &fit) == -EINVAL);
	model_destroy(m);
	return 0;
}
