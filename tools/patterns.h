/* Built-in test patterns (`spindlectl pattern NAME`): known shapes in
 * volume space (docs/design.md section 3) for aligning and checking a
 * display, made as models so that they are shown like any model file. */
#ifndef SPINDLE_TOOLS_PATTERNS_H
#define SPINDLE_TOOLS_PATTERNS_H

#include "model.h"

/* The pattern called name for a display of half height h, or NULL with
 * errno EINVAL (unknown name) or ENOMEM. Free with model_destroy(). */
struct model *pattern_build(const char *name, float h);

/* The names, comma-separated, for messages and the help. */
extern const char pattern_names[];

#endif
