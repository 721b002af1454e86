/* Fuzz target "model": model files, read in process by what the sandboxed
 * loader child runs (tools/model_import.c: assimp with its validation, the
 * checked scene walk), and loader results, checked by what the parent runs
 * (tools/model_wire.c). Checks: no memory error, leak, hang or undefined
 * behaviour in either (assimp is a system library, not instrumented: its
 * crashes count, its coverage does not guide); a mesh the import accepts
 * has every index in range and every coordinate finite, and passes the
 * parent's checks with the same counts; its fit is finite; no fd left open.
 *
 * Input: sel: u8, then
 *   sel bit 7 clear: the file, named model.<ext>, ext the (sel & 7)th of
 *                    ply obj stl gltf glb off dae fbx (assimp picks the
 *                    importer by it first)
 *   sel bit 7 set:   a result: flags: u8, then the vertex, triangle, line
 *                    and point counts as fuzz_num64(), then the payload
 *                    bytes, repeated (or zeros) to the size the counts give
 *                    (at most 1 MiB)
 * fuzz/gen_model_corpus.py writes the seeds from tests/data. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "harness.h"
#include "model.h"
#include "model_import.h"
#include "model_wire.h"

#define MAX_PAYLOAD (1u << 20)

static const char *const extensions[8] = { "ply", "obj", "stl", "gltf", "glb", "off", "dae", "fbx" };

static void check_model(struct model *m, const struct model_mesh *mesh)
{
	struct model_fit fit;
	float min[3], max[3];
	if (m->triangle_count != mesh->triangle_count || m->line_count != mesh->line_count ||
	    m->point_count != mesh->point_count || !m->triangle_colors != !mesh->colored)
		fuzz_fail("the parent's model differs from the loader's mesh");
	if (model_order_spatial(m) != 0) /* as spindlectl show orders it */
		fuzz_fail("no spatial order");
	if (model_compute_fit(m, 1.0f, 0.95f, &fit) != 0 || !isfinite(fit.scale) || !isfinite(fit.centre[0]) ||
	    !isfinite(fit.centre[1]) || !isfinite(fit.centre[2]))
		fuzz_fail("no finite fit");
	model_apply_fit(m, &fit);
	if (model_bounds(m, min, max) != 0)
		fuzz_fail("no bounds");
	for (int i = 0; i < 3; i++)
		if (!(min[i] >= -1.0f && max[i] <= 1.0f))
			fuzz_fail("fitted bounds [%g, %g] on axis %d", min[i], max[i], i);
}

/* The mesh as the parent receives it: header and payload in memory. */
static void round_trip(const struct model_mesh *mesh)
{
	struct model_wire_header h = model_wire_mesh_header(mesh);
	size_t len = 0, v = 12 * mesh->vertex_count, c = mesh->colored ? 4 * mesh->vertex_count : 0;
	char why[256];
	if (model_wire_check_header(&h, &len, why, sizeof(why)) != 0)
		fuzz_fail("the parent refuses the loader's header: %s", why);
	uint8_t *payload = malloc(len ? len : 1);
	if (!payload)
		return;
	memcpy(payload, mesh->vertices, v);
	memcpy(payload + v, mesh->colors, c);
	memcpy(payload + v + c, mesh->indices, len - v - c);
	struct model *m = NULL;
	int ret = model_wire_decode(&h, payload, &m, why, sizeof(why));
	free(payload);
	if (ret == -ENOMEM)
		return;
	if (ret != 0)
		fuzz_fail("the parent refuses the loader's mesh: %s", why);
	check_model(m, mesh);
	model_destroy(m);
}

static void check_mesh(const struct model_mesh *mesh)
{
	size_t indices = 3 * mesh->triangle_count + 2 * mesh->line_count + mesh->point_count;
	if (indices == 0 || mesh->vertex_count > MODEL_MAX_VERTICES)
		fuzz_fail("a mesh without primitives or with too many vertices");
	for (size_t i = 0; i < 3 * mesh->vertex_count; i++)
		if (!isfinite(mesh->vertices[i]))
			fuzz_fail("vertex coordinate %zu is not finite", i);
	for (size_t i = 0; i < indices; i++)
		if (mesh->indices[i] >= mesh->vertex_count)
			fuzz_fail("index %zu out of range", i);
}

static void import_file(uint8_t sel, const uint8_t *data, size_t size)
{
	char name[16], reason[512];
	struct model_mesh mesh;
	snprintf(name, sizeof(name), "model.%s", extensions[sel & 7]);
	int fd = memfd_create("fuzz-model", MFD_CLOEXEC);
	if (fd < 0)
		return;
	if (size == 0 || write(fd, data, size) == (ssize_t)size) {
		if (model_import_fd(fd, size, name, NULL, &mesh, reason, sizeof(reason)) == 0) {
			check_mesh(&mesh);
			round_trip(&mesh);
			model_mesh_free(&mesh);
		} else if (fuzz_verbose()) {
			fprintf(stderr, "refused: %s\n", reason);
		}
	}
	close(fd);
}

static void decode_result(struct fuzz_input *in)
{
	struct model_wire_header h = { .magic = MODEL_WIRE_MAGIC, .flags = fuzz_u8(in) };
	size_t len = 0, n;
	char why[256];
	struct model *m = NULL;
	h.vertex_count = fuzz_num64(in);
	h.triangle_count = fuzz_num64(in);
	h.line_count = fuzz_num64(in);
	h.point_count = fuzz_num64(in);
	if (model_wire_check_header(&h, &len, why, sizeof(why)) != 0 || len > MAX_PAYLOAD)
		return;
	const uint8_t *bytes = fuzz_bytes(in, len, &n);
	uint8_t *payload = calloc(1, len ? len : 1);
	if (!payload)
		return;
	for (size_t i = 0; n && i < len; i++)
		payload[i] = bytes[i % n];
	if (model_wire_decode(&h, payload, &m, why, sizeof(why)) == 0) {
		float min[3], max[3];
		if (model_bounds(m, min, max) != 0 || !isfinite(min[0]) || !isfinite(max[0]))
			fuzz_fail("a decoded model without finite bounds");
		model_destroy(m);
	}
	free(payload);
}

/* assimp leaks on some refused files (the STL and PLY importers, 5.2.5);
 * the loader child exits right after, so these are not ours to fix. The
 * fast unwinder stops in libstdc++'s operator new (assimp has no frame
 * pointers): our own code, C, never calls it. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
	return "leak:libassimp.so\nleak:libstdc++.so\n";
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_input in = { .data = data, .size = size };
	struct fuzz_resources before;
	if (size == 0)
		return 0;
	fuzz_resources_take(&before);
	uint8_t sel = fuzz_u8(&in);
	if (sel & 0x80)
		decode_result(&in);
	else
		import_file(sel, data + 1, size - 1);
	fuzz_resources_check(&before);
	return 0;
}
