/* spindle-gl: the real entry points under the layer (dlsym(RTLD_NEXT),
 * else the real glXGetProcAddressARB or eglGetProcAddress), and the
 * layer's own by name. */
#ifndef SPINDLE_GL_REAL_H
#define SPINDLE_GL_REAL_H

#include "entries.h"
#include "glapi.h"

typedef void (*sgl_proc)(void);

/* The real function, resolved once (NULL while there is none). */
sgl_proc sgl_real(enum sgl_entry e, const char *name);
/* The real function of any name, not cached. */
sgl_proc sgl_real_lookup(const char *name);
/* The layer's own function of that name, or NULL. */
sgl_proc sgl_own_proc(const char *name);

#define REAL(name) ((__typeof__(&name))sgl_real(SGL_E_##name, #name))
/* Calls the real function when there is one. */
#define PASS(name, ...)                                  \
	do {                                             \
		__typeof__(&name) pass_fn_ = REAL(name); \
		if (pass_fn_)                            \
			pass_fn_(__VA_ARGS__);           \
	} while (0)

#endif
