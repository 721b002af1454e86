#include "gl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef SPINDLE_HAVE_OSMESA
#include <GL/osmesa.h>
#endif

#include "log.h"

struct gl_context_priv {
	EGLDisplay dpy;
	EGLContext ctx;
#ifdef SPINDLE_HAVE_OSMESA
	OSMesaContext osmesa;
	uint32_t pixel; /* OSMesa wants a colour buffer; we draw to FBOs */
#endif
};

const char *gl_backend_name(enum gl_backend b)
{
	return b == GL_BACKEND_OSMESA ? "osmesa" : "egl";
}

enum gl_fault gl_fault_from_env(void)
{
	const char *f = getenv("SPINDLE_GL_FAULT");
	if (!f)
		return GL_FAULT_NONE;
	if (!strcmp(f, "display"))
		return GL_FAULT_DISPLAY;
	if (!strcmp(f, "shader"))
		return GL_FAULT_SHADER;
	if (!strcmp(f, "lost"))
		return GL_FAULT_LOST;
	return GL_FAULT_NONE;
}

static bool has_word(const char *list, const char *word)
{
	size_t n = strlen(word);
	for (const char *p = list; p && (p = strstr(p, word)); p += n)
		if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
			return true;
	return false;
}

/* The first EGL device that is not Mesa's software one, or NULL. */
static EGLDeviceEXT hardware_device(void)
{
	PFNEGLQUERYDEVICESEXTPROC query = (PFNEGLQUERYDEVICESEXTPROC)eglGetProcAddress("eglQueryDevicesEXT");
	PFNEGLQUERYDEVICESTRINGEXTPROC str =
		(PFNEGLQUERYDEVICESTRINGEXTPROC)eglGetProcAddress("eglQueryDeviceStringEXT");
	EGLDeviceEXT devs[16];
	EGLint n = 0;
	if (!query || !str || !query(16, devs, &n))
		return NULL;
	for (EGLint i = 0; i < n; i++) {
		const char *ext = str(devs[i], EGL_EXTENSIONS);
		if (!has_word(ext, "EGL_MESA_device_software"))
			return devs[i];
	}
	return NULL;
}

static EGLDisplay open_display(void)
{
	const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
	PFNEGLGETPLATFORMDISPLAYEXTPROC get =
		(PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
	if (!get)
		return EGL_NO_DISPLAY;
	EGLint major, minor;
	if (has_word(client, "EGL_EXT_platform_device")) {
		EGLDeviceEXT dev = hardware_device();
		EGLDisplay d = dev ? get(EGL_PLATFORM_DEVICE_EXT, dev, NULL) : EGL_NO_DISPLAY;
		if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor))
			return d;
	}
	if (has_word(client, "EGL_MESA_platform_surfaceless")) {
		EGLDisplay d = get(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
		if (d != EGL_NO_DISPLAY && eglInitialize(d, &major, &minor))
			return d;
	}
	return EGL_NO_DISPLAY;
}

static EGLContext create_egl_context(EGLDisplay d, bool *robust)
{
	const char *ext = eglQueryString(d, EGL_EXTENSIONS);
	EGLConfig cfg = EGL_NO_CONFIG_KHR;
	if (!has_word(ext, "EGL_KHR_no_config_context")) {
		const EGLint want[] = { EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT_KHR, EGL_NONE };
		EGLint n = 0;
		if (!eglChooseConfig(d, want, &cfg, 1, &n) || n < 1)
			return EGL_NO_CONTEXT;
	}
	if (!eglBindAPI(EGL_OPENGL_ES_API))
		return EGL_NO_CONTEXT;
	EGLint attrs[] = { EGL_CONTEXT_MAJOR_VERSION,
			   3,
			   EGL_CONTEXT_MINOR_VERSION,
			   1,
			   EGL_CONTEXT_OPENGL_RESET_NOTIFICATION_STRATEGY_EXT,
			   EGL_LOSE_CONTEXT_ON_RESET_EXT,
			   EGL_NONE };
	*robust = has_word(ext, "EGL_EXT_create_context_robustness");
	if (!*robust)
		attrs[4] = EGL_NONE;
	EGLContext c = eglCreateContext(d, cfg, EGL_NO_CONTEXT, attrs);
	if (c == EGL_NO_CONTEXT && *robust) {
		*robust = false;
		attrs[4] = EGL_NONE;
		c = eglCreateContext(d, cfg, EGL_NO_CONTEXT, attrs);
	}
	return c;
}

static gl_proc egl_proc(const char *name)
{
	return (gl_proc)eglGetProcAddress(name);
}

static int create_egl(struct gl_context *c)
{
	struct gl_context_priv *p = c->priv;
	p->dpy = open_display();
	if (p->dpy == EGL_NO_DISPLAY) {
		log_warn("GL renderer: no EGL device or surfaceless display (EGL error 0x%x)", eglGetError());
		return -ENODEV;
	}
	const char *ext = eglQueryString(p->dpy, EGL_EXTENSIONS);
	if (!has_word(ext, "EGL_KHR_surfaceless_context")) {
		log_warn("GL renderer: the EGL display lacks EGL_KHR_surfaceless_context");
		return -ENOTSUP;
	}
	p->ctx = create_egl_context(p->dpy, &c->robust);
	if (p->ctx == EGL_NO_CONTEXT) {
		log_warn("GL renderer: no OpenGL ES 3.1 context (EGL error 0x%x)", eglGetError());
		return -ENOTSUP;
	}
	if (!eglMakeCurrent(p->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, p->ctx)) {
		log_warn("GL renderer: eglMakeCurrent failed (EGL error 0x%x)", eglGetError());
		return -EIO;
	}
	const char *missing = NULL;
	if (gl_api_load(&c->gl, egl_proc, &missing) < 0) {
		log_warn("GL renderer: %s is missing", missing);
		return -ENOTSUP;
	}
	return 0;
}

#ifdef SPINDLE_HAVE_OSMESA
static gl_proc osmesa_proc(const char *name)
{
	return (gl_proc)OSMesaGetProcAddress(name);
}

static int create_osmesa(struct gl_context *c)
{
	struct gl_context_priv *p = c->priv;
	/* 4.5 core carries ARB_ES3_1_compatibility: "#version 310 es" shaders. */
	const int attrs[] = {
		OSMESA_FORMAT,
		OSMESA_RGBA,
		OSMESA_DEPTH_BITS,
		0,
		OSMESA_STENCIL_BITS,
		0,
		OSMESA_PROFILE,
		OSMESA_CORE_PROFILE,
		OSMESA_CONTEXT_MAJOR_VERSION,
		4,
		OSMESA_CONTEXT_MINOR_VERSION,
		5,
		0
	};
	p->osmesa = OSMesaCreateContextAttribs(attrs, NULL);
	if (!p->osmesa) {
		log_warn("GL renderer: OSMesa gives no OpenGL 4.5 core context");
		return -ENOTSUP;
	}
	if (!OSMesaMakeCurrent(p->osmesa, &p->pixel, GL_UNSIGNED_BYTE, 1, 1)) {
		log_warn("GL renderer: OSMesaMakeCurrent failed");
		return -EIO;
	}
	const char *missing = NULL;
	if (gl_api_load(&c->gl, osmesa_proc, &missing) < 0) {
		log_warn("GL renderer: %s is missing", missing);
		return -ENOTSUP;
	}
	return 0;
}
#endif

static void describe(struct gl_context *c)
{
	const char *r = (const char *)c->gl.GetString(GL_RENDERER);
	const char *v = (const char *)c->gl.GetString(GL_VERSION);
	snprintf(c->renderer, sizeof(c->renderer), "%s", r ? r : "?");
	snprintf(c->version, sizeof(c->version), "%s", v ? v : "?");
	static const char *const soft[] = { "llvmpipe", "softpipe", "swrast", "SwiftShader", "Software" };
	c->hardware = true;
	for (size_t i = 0; i < sizeof(soft) / sizeof(soft[0]); i++)
		if (strstr(c->renderer, soft[i]))
			c->hardware = false;
}

int gl_context_create(struct gl_context *c, enum gl_backend backend)
{
	memset(c, 0, sizeof(*c));
	c->backend = backend;
	c->priv = calloc(1, sizeof(*c->priv));
	if (!c->priv)
		return -ENOMEM;
	c->priv->dpy = EGL_NO_DISPLAY;
	c->priv->ctx = EGL_NO_CONTEXT;
	if (gl_fault_from_env() == GL_FAULT_DISPLAY) {
		log_warn("GL renderer: no %s display (fault injected by SPINDLE_GL_FAULT)", gl_backend_name(backend));
		return -ENODEV;
	}
	int r;
	if (backend == GL_BACKEND_EGL) {
		r = create_egl(c);
	} else {
#ifdef SPINDLE_HAVE_OSMESA
		r = create_osmesa(c);
#else
		log_warn("GL renderer: this build has no OSMesa support");
		r = -ENOENT;
#endif
	}
	if (r == 0)
		describe(c);
	return r;
}

int gl_context_bind(struct gl_context *c)
{
	struct gl_context_priv *p = c->priv;
#ifdef SPINDLE_HAVE_OSMESA
	if (c->backend == GL_BACKEND_OSMESA)
		return OSMesaMakeCurrent(p->osmesa, &p->pixel, GL_UNSIGNED_BYTE, 1, 1) ? 0 : -EIO;
#endif
	return eglMakeCurrent(p->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, p->ctx) ? 0 : -EIO;
}

void gl_context_unbind(struct gl_context *c)
{
	struct gl_context_priv *p = c->priv;
#ifdef SPINDLE_HAVE_OSMESA
	if (c->backend == GL_BACKEND_OSMESA) {
		OSMesaMakeCurrent(NULL, NULL, 0, 0, 0);
		return;
	}
#endif
	if (p->dpy != EGL_NO_DISPLAY)
		eglMakeCurrent(p->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

void gl_context_destroy(struct gl_context *c)
{
	struct gl_context_priv *p = c->priv;
	if (!p)
		return;
#ifdef SPINDLE_HAVE_OSMESA
	if (p->osmesa) {
		OSMesaMakeCurrent(NULL, NULL, 0, 0, 0);
		OSMesaDestroyContext(p->osmesa);
	}
#endif
	if (p->dpy != EGL_NO_DISPLAY) {
		eglMakeCurrent(p->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
		if (p->ctx != EGL_NO_CONTEXT)
			eglDestroyContext(p->dpy, p->ctx);
		/* No eglTerminate(): the display is one per process, shared
		 * by every renderer the process opens. */
	}
	free(p);
	c->priv = NULL;
}

GLuint gl_shader_compile(const struct gl_api *gl, GLenum type, const char *src, const char *what, bool broken)
{
	GLuint s = gl->CreateShader(type);
	const char *srcs[2] = { src, broken ? "#error fault injected by SPINDLE_GL_FAULT\n" : "" };
	gl->ShaderSource(s, 2, srcs, NULL);
	gl->CompileShader(s);
	GLint ok = 0;
	gl->GetShaderiv(s, GL_COMPILE_STATUS, &ok);
	if (ok)
		return s;
	char msg[512] = "";
	gl->GetShaderInfoLog(s, sizeof(msg), NULL, msg);
	log_warn("GL renderer: the %s shader does not compile: %s", what, msg);
	gl->DeleteShader(s);
	return 0;
}

GLuint gl_program_link(const struct gl_api *gl, const GLuint *shaders, int n, const char *what)
{
	GLuint p = 0;
	bool ok = true;
	for (int i = 0; i < n; i++)
		ok = ok && shaders[i];
	if (ok) {
		p = gl->CreateProgram();
		for (int i = 0; i < n; i++)
			gl->AttachShader(p, shaders[i]);
		gl->LinkProgram(p);
		GLint linked = 0;
		gl->GetProgramiv(p, GL_LINK_STATUS, &linked);
		if (!linked) {
			char msg[512] = "";
			gl->GetProgramInfoLog(p, sizeof(msg), NULL, msg);
			log_warn("GL renderer: the %s program does not link: %s", what, msg);
			gl->DeleteProgram(p);
			p = 0;
		}
	}
	for (int i = 0; i < n; i++)
		if (shaders[i])
			gl->DeleteShader(shaders[i]);
	return p;
}
