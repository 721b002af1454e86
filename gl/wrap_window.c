/* Frames (glXSwapBuffers, eglSwapBuffers; in a context that never swapped
 * through the layer, glFlush, glFinish and glClear), contexts (created, made current,
 * destroyed, through GLX or EGL) and the function loaders, which hand out
 * the layer's own entry points. */
#include "ctx.h"
#include "frame.h"
#include "geom.h"
#include "real.h"

void glXSwapBuffers(Display *dpy, GLXDrawable drawable)
{
	struct sgl_ctx *c = sgl_ctx_current();
	c->swapped = true;
	sgl_frame_end(c, "swap");
	PASS(glXSwapBuffers, dpy, drawable);
}

EGLBoolean eglSwapBuffers(EGLDisplay dpy, EGLSurface surface)
{
	struct sgl_ctx *c = sgl_ctx_current();
	c->swapped = true;
	sgl_frame_end(c, "swap");
	__typeof__(&eglSwapBuffers) real = REAL(eglSwapBuffers);
	return real ? real(dpy, surface) : EGL_FALSE;
}

/* A single-buffered program shows what it drew at glFlush or glFinish. */
static void flushed(const char *why)
{
	struct sgl_ctx *c = sgl_ctx_current();
	if (!c->swapped && !c->rec && !c->in_begin)
		sgl_frame_end(c, why);
}

/* A program whose swaps the layer does not see (a toolkit that took
 * glXSwapBuffers with dlsym from a libGL it opened itself) still clears
 * the colour buffer each frame: what it drew before is a frame. */
void glClear(GLbitfield mask)
{
	struct sgl_ctx *c = sgl_ctx_current();
	bool drawn = c->frame.n_calls || !sgl_geom_empty(&c->frame.imm);
	if ((mask & GL_COLOR_BUFFER_BIT) && drawn && !c->swapped && !c->rec && !c->in_begin)
		sgl_frame_end(c, "clear");
	PASS(glClear, mask);
}

void glFlush(void)
{
	flushed("flush");
	PASS(glFlush);
}

void glFinish(void)
{
	flushed("finish");
	PASS(glFinish);
}

GLXContext glXCreateContext(Display *dpy, XVisualInfo *vis, GLXContext share, Bool direct)
{
	__typeof__(&glXCreateContext) real = REAL(glXCreateContext);
	GLXContext ctx = real ? real(dpy, vis, share, direct) : NULL;
	sgl_ctx_created(ctx, share);
	return ctx;
}

GLXContext glXCreateNewContext(Display *dpy, GLXFBConfig config, int type, GLXContext share, Bool direct)
{
	__typeof__(&glXCreateNewContext) real = REAL(glXCreateNewContext);
	GLXContext ctx = real ? real(dpy, config, type, share, direct) : NULL;
	sgl_ctx_created(ctx, share);
	return ctx;
}

GLXContext glXCreateContextAttribsARB(Display *dpy, GLXFBConfig config, GLXContext share, Bool direct,
				      const int *attribs)
{
	__typeof__(&glXCreateContextAttribsARB) real = REAL(glXCreateContextAttribsARB);
	GLXContext ctx = real ? real(dpy, config, share, direct, attribs) : NULL;
	sgl_ctx_created(ctx, share);
	return ctx;
}

void glXDestroyContext(Display *dpy, GLXContext ctx)
{
	sgl_ctx_destroyed(ctx);
	PASS(glXDestroyContext, dpy, ctx);
}

Bool glXMakeCurrent(Display *dpy, GLXDrawable drawable, GLXContext ctx)
{
	__typeof__(&glXMakeCurrent) real = REAL(glXMakeCurrent);
	Bool r = real ? real(dpy, drawable, ctx) : False;
	if (r)
		sgl_ctx_make_current(ctx);
	return r;
}

Bool glXMakeContextCurrent(Display *dpy, GLXDrawable draw, GLXDrawable read, GLXContext ctx)
{
	__typeof__(&glXMakeContextCurrent) real = REAL(glXMakeContextCurrent);
	Bool r = real ? real(dpy, draw, read, ctx) : False;
	if (r)
		sgl_ctx_make_current(ctx);
	return r;
}

EGLContext eglCreateContext(EGLDisplay dpy, EGLConfig config, EGLContext share, const EGLint *attribs)
{
	__typeof__(&eglCreateContext) real = REAL(eglCreateContext);
	EGLContext ctx = real ? real(dpy, config, share, attribs) : EGL_NO_CONTEXT;
	sgl_ctx_created(ctx, share);
	return ctx;
}

EGLBoolean eglDestroyContext(EGLDisplay dpy, EGLContext ctx)
{
	sgl_ctx_destroyed(ctx);
	__typeof__(&eglDestroyContext) real = REAL(eglDestroyContext);
	return real ? real(dpy, ctx) : EGL_FALSE;
}

EGLBoolean eglMakeCurrent(EGLDisplay dpy, EGLSurface draw, EGLSurface read, EGLContext ctx)
{
	__typeof__(&eglMakeCurrent) real = REAL(eglMakeCurrent);
	EGLBoolean r = real ? real(dpy, draw, read, ctx) : EGL_FALSE;
	if (r)
		sgl_ctx_make_current(ctx);
	return r;
}

/* The real loader's answer, or the layer's own function for a name it
 * wraps (where the real GL has one). */
static sgl_proc lookup(sgl_proc real_answer, const GLubyte *name, bool have_real)
{
	if (have_real && !real_answer)
		return NULL;
	sgl_proc own = sgl_own_proc((const char *)name);
	return own ? own : real_answer;
}

__GLXextFuncPtr glXGetProcAddressARB(const GLubyte *name)
{
	__typeof__(&glXGetProcAddressARB) real = REAL(glXGetProcAddressARB);
	return (__GLXextFuncPtr)lookup(real ? (sgl_proc)real(name) : NULL, name, real != NULL);
}

void (*glXGetProcAddress(const GLubyte *name))(void)
{
	__typeof__(&glXGetProcAddress) real = REAL(glXGetProcAddress);
	return lookup(real ? (sgl_proc)real(name) : NULL, name, real != NULL);
}

__eglMustCastToProperFunctionPointerType eglGetProcAddress(const char *name)
{
	__typeof__(&eglGetProcAddress) real = REAL(eglGetProcAddress);
	const GLubyte *n = (const GLubyte *)name;
	return (__eglMustCastToProperFunctionPointerType)lookup(real ? (sgl_proc)real(name) : NULL, n, real != NULL);
}
