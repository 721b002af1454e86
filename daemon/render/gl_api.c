#include "gl_api.h"

#include <errno.h>
#include <stddef.h>

#define GL_API_LOAD(ret, name, params)                              \
	api->name = (ret(GL_APIENTRY *) params)getproc("gl" #name); \
	if (!api->name) {                                           \
		*missing = "gl" #name;                              \
		return -ENOSYS;                                     \
	}

int gl_api_load(struct gl_api *api, gl_proc (*getproc)(const char *name), const char **missing)
{
	GL_API_FUNCTIONS(GL_API_LOAD)
	static const char *const reset[] = { "glGetGraphicsResetStatus", "glGetGraphicsResetStatusKHR",
					     "glGetGraphicsResetStatusEXT" };
	api->GetGraphicsResetStatus = NULL;
	for (size_t i = 0; i < sizeof(reset) / sizeof(reset[0]) && !api->GetGraphicsResetStatus; i++)
		api->GetGraphicsResetStatus = (GLenum(GL_APIENTRY *)(void))getproc(reset[i]);
	return 0;
}
