/* Reading a model file with assimp into a checked indexed mesh: what the
 * loader child of model_sandbox.c runs once it is confined, and what the
 * fuzz target fuzz/fuzz_model.c calls in process. The file comes as an
 * open fd that assimp reads through callbacks (pread); assimp may open no
 * other file but the companions the caller read for it beforehand (an
 * OBJ's .mtl files, model_companions_read()); a glTF's .bin is refused. */
#ifndef SPINDLE_TOOLS_MODEL_IMPORT_H
#define SPINDLE_TOOLS_MODEL_IMPORT_H

#include <stddef.h>
#include <stdint.h>

#include "model_wire.h"

struct model_companions;

/* Reads the file: fd open for reading, size its size, name its path (the
 * extension picks the importer; assimp's messages name it). assimp's
 * validation runs before any other step. Every count, pointer and index of
 * the scene assimp returns is checked as the scene is walked; node
 * transforms are applied and every coordinate must come out finite.
 * 0 with mesh filled (free it with model_mesh_free()), or -errno (EINVAL,
 * ENODATA, E2BIG, ENOMEM) with reason filled (without the path). */
int model_import_fd(int fd, uint64_t size, const char *name, const struct model_companions *comp,
		    struct model_mesh *mesh, char *reason, size_t reason_size);

/* Files a model names that the importer may read, held in memory: an
 * OBJ's `mtllib` files, found by model_companions_read() beside the model
 * (a plain name: no '/', nothing hidden), regular files of at most
 * MODEL_COMPANION_MAX bytes, at most MODEL_COMPANIONS of them. Any that
 * cannot be read is left out (its materials show white). */
#define MODEL_COMPANIONS 4
#define MODEL_COMPANION_MAX (1u << 20)
struct model_companions {
	unsigned count;
	struct model_companion {
		char name[256];
		uint8_t *data;
		size_t size;
	} file[MODEL_COMPANIONS];
};

/* Reads the companions of the model at path (open as fd, size bytes):
 * for an OBJ, the files its `mtllib` lines name. Never fails; comp->count
 * may be 0. Free with model_companions_free(). */
void model_companions_read(int fd, uint64_t size, const char *path, struct model_companions *comp);
void model_companions_free(struct model_companions *comp);

#endif
