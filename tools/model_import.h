/* Reading a model file with assimp into a checked indexed mesh: what the
 * loader child of model_sandbox.c runs once it is confined, and what the
 * fuzz target fuzz/fuzz_model.c calls in process. The file comes as an
 * open fd that assimp reads through callbacks (pread); assimp may open no
 * other file (an OBJ's .mtl, a glTF's .bin: refused, so their materials or
 * buffers are missing). */
#ifndef SPINDLE_TOOLS_MODEL_IMPORT_H
#define SPINDLE_TOOLS_MODEL_IMPORT_H

#include <stddef.h>
#include <stdint.h>

#include "model_wire.h"

/* Reads the file: fd open for reading, size its size, name its path (the
 * extension picks the importer; assimp's messages name it). assimp's
 * validation runs before any other step. Every count, pointer and index of
 * the scene assimp returns is checked as the scene is walked; node
 * transforms are applied and every coordinate must come out finite.
 * 0 with mesh filled (free it with model_mesh_free()), or -errno (EINVAL,
 * ENODATA, E2BIG, ENOMEM) with reason filled (without the path). */
int model_import_fd(int fd, uint64_t size, const char *name, struct model_mesh *mesh, char *reason, size_t reason_size);

#endif
