#include "real.h"

#include <dlfcn.h>
#include <string.h>

static sgl_proc slots[SGL_ENTRY_COUNT];

static sgl_proc from_object(void *p)
{
	sgl_proc f;
	memcpy(&f, &p, sizeof(f)); /* POSIX: dlsym results are callable */
	return f;
}

static sgl_proc next_symbol(const char *name)
{
	return from_object(dlsym(RTLD_NEXT, name));
}

/* A GL library opened with RTLD_LOCAL (dlopen by a toolkit) is not
 * under RTLD_NEXT; its loaders answer. */
sgl_proc sgl_real_lookup(const char *name)
{
	sgl_proc f = next_symbol(name);
	if (f)
		return f;
	typedef sgl_proc (*gpa_fn)(const GLubyte *);
	const char *loaders[] = { "glXGetProcAddressARB", "eglGetProcAddress" };
	for (size_t i = 0; i < sizeof(loaders) / sizeof(loaders[0]) && !f; i++) {
		gpa_fn gpa = (gpa_fn)next_symbol(loaders[i]);
		void *lib = NULL;
		if (!gpa) {
			lib = dlopen(i == 0 ? "libGL.so.1" : "libEGL.so.1", RTLD_LAZY | RTLD_NOLOAD);
			gpa = lib ? (gpa_fn)from_object(dlsym(lib, loaders[i])) : NULL;
		}
		if (gpa)
			f = gpa((const GLubyte *)name);
		if (lib)
			dlclose(lib);
	}
	return f;
}

sgl_proc sgl_real(enum sgl_entry e, const char *name)
{
	sgl_proc f = __atomic_load_n(&slots[e], __ATOMIC_ACQUIRE);
	if (f)
		return f;
	f = sgl_real_lookup(name);
	if (f)
		__atomic_store_n(&slots[e], f, __ATOMIC_RELEASE);
	return f;
}

#define SGL_OWN_ENTRY(name) { #name, (sgl_proc)name },
static const struct own_entry {
	const char *name;
	sgl_proc fn;
} own[] = { SGL_ENTRIES(SGL_OWN_ENTRY) };
#undef SGL_OWN_ENTRY

sgl_proc sgl_own_proc(const char *name)
{
	if (!name || (strncmp(name, "gl", 2) != 0 && strncmp(name, "egl", 3) != 0))
		return NULL;
	for (size_t i = 0; i < sizeof(own) / sizeof(own[0]); i++)
		if (!strcmp(own[i].name, name))
			return own[i].fn;
	return NULL;
}
