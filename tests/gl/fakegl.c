/* The fake GL library (fakegl.h): the GL, GLX and EGL entry points the
 * layer interposes, as no-ops that record their calls. */
#define GL_GLEXT_PROTOTYPES 1
#define GLX_GLXEXT_PROTOTYPES 1
#include "fakegl.h"

#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <GL/glxext.h>
#include <dlfcn.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>

void glFrustumf(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f);
void glOrthof(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f);

#define MAX_NAMES 256

static struct record {
	const char *name;
	int count;
	double args[4];
} records[MAX_NAMES];
static int n_records;
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;

static struct record *find(const char *name, int add)
{
	for (int i = 0; i < n_records; i++)
		if (!strcmp(records[i].name, name))
			return &records[i];
	if (!add || n_records == MAX_NAMES)
		return NULL;
	records[n_records].name = name;
	return &records[n_records++];
}

static void rec(const char *name, double a, double b, double c, double d)
{
	pthread_mutex_lock(&lock);
	struct record *r = find(name, 1);
	if (r) {
		r->count++;
		r->args[0] = a;
		r->args[1] = b;
		r->args[2] = c;
		r->args[3] = d;
	}
	pthread_mutex_unlock(&lock);
}

int fakegl_count(const char *name)
{
	pthread_mutex_lock(&lock);
	struct record *r = find(name, 0);
	int n = r ? r->count : 0;
	pthread_mutex_unlock(&lock);
	return n;
}

double fakegl_arg(const char *name, int i)
{
	pthread_mutex_lock(&lock);
	struct record *r = find(name, 0);
	double v = r && i >= 0 && i < 4 ? r->args[i] : 0;
	pthread_mutex_unlock(&lock);
	return v;
}

static _Alignas(16) unsigned char map_memory[1 << 20];

void *fakegl_map_memory(void)
{
	return map_memory;
}

#define R0(name) rec(#name, 0, 0, 0, 0)
#define R1(name, a) rec(#name, (double)(a), 0, 0, 0)
#define R2(name, a, b) rec(#name, (double)(a), (double)(b), 0, 0)
#define R3(name, a, b, c) rec(#name, (double)(a), (double)(b), (double)(c), 0)
#define R4(name, a, b, c, d) rec(#name, (double)(a), (double)(b), (double)(c), (double)(d))
#define RV(name, v, n) \
	rec(#name, (double)(v)[0], (double)(v)[1], (n) > 2 ? (double)(v)[2] : 0, (n) > 3 ? (double)(v)[3] : 0)

/* Families: glVertex, glColor, glNormal, glRect. */
#define VERTEX(sfx, T)                          \
	void glVertex2##sfx(T x, T y)           \
	{                                       \
		R2(glVertex2##sfx, x, y);       \
	}                                       \
	void glVertex2##sfx##v(const T *v)      \
	{                                       \
		RV(glVertex2##sfx##v, v, 2);    \
	}                                       \
	void glVertex3##sfx(T x, T y, T z)      \
	{                                       \
		R3(glVertex3##sfx, x, y, z);    \
	}                                       \
	void glVertex3##sfx##v(const T *v)      \
	{                                       \
		RV(glVertex3##sfx##v, v, 3);    \
	}                                       \
	void glVertex4##sfx(T x, T y, T z, T w) \
	{                                       \
		R4(glVertex4##sfx, x, y, z, w); \
	}                                       \
	void glVertex4##sfx##v(const T *v)      \
	{                                       \
		RV(glVertex4##sfx##v, v, 4);    \
	}
VERTEX(d, GLdouble)
VERTEX(f, GLfloat)
VERTEX(i, GLint)
VERTEX(s, GLshort)

#define COLOR(sfx, T)                          \
	void glColor3##sfx(T r, T g, T b)      \
	{                                      \
		R3(glColor3##sfx, r, g, b);    \
	}                                      \
	void glColor3##sfx##v(const T *v)      \
	{                                      \
		RV(glColor3##sfx##v, v, 3);    \
	}                                      \
	void glColor4##sfx(T r, T g, T b, T a) \
	{                                      \
		R4(glColor4##sfx, r, g, b, a); \
	}                                      \
	void glColor4##sfx##v(const T *v)      \
	{                                      \
		RV(glColor4##sfx##v, v, 4);    \
	}
COLOR(b, GLbyte)
COLOR(d, GLdouble)
COLOR(f, GLfloat)
COLOR(i, GLint)
COLOR(s, GLshort)
COLOR(ub, GLubyte)
COLOR(ui, GLuint)
COLOR(us, GLushort)

#define NORMAL(sfx, T)                       \
	void glNormal3##sfx(T x, T y, T z)   \
	{                                    \
		R3(glNormal3##sfx, x, y, z); \
	}                                    \
	void glNormal3##sfx##v(const T *v)   \
	{                                    \
		RV(glNormal3##sfx##v, v, 3); \
	}
NORMAL(b, GLbyte)
NORMAL(d, GLdouble)
NORMAL(f, GLfloat)
NORMAL(i, GLint)
NORMAL(s, GLshort)

#define RECT(sfx, T)                                        \
	void glRect##sfx(T x1, T y1, T x2, T y2)            \
	{                                                   \
		R4(glRect##sfx, x1, y1, x2, y2);            \
	}                                                   \
	void glRect##sfx##v(const T *a, const T *b)         \
	{                                                   \
		R4(glRect##sfx##v, a[0], a[1], b[0], b[1]); \
	}
RECT(d, GLdouble)
RECT(f, GLfloat)
RECT(i, GLint)
RECT(s, GLshort)

/* One-offs. */
void glBegin(GLenum mode)
{
	R1(glBegin, mode);
}

void glEnd(void)
{
	R0(glEnd);
}

void glMaterialf(GLenum face, GLenum pname, GLfloat p)
{
	R3(glMaterialf, face, pname, p);
}

void glMateriali(GLenum face, GLenum pname, GLint p)
{
	R3(glMateriali, face, pname, p);
}

void glMaterialfv(GLenum face, GLenum pname, const GLfloat *p)
{
	R3(glMaterialfv, face, pname, p[0]);
}

void glMaterialiv(GLenum face, GLenum pname, const GLint *p)
{
	R3(glMaterialiv, face, pname, p[0]);
}

void glColorMaterial(GLenum face, GLenum mode)
{
	R2(glColorMaterial, face, mode);
}

void glShadeModel(GLenum mode)
{
	R1(glShadeModel, mode);
}

void glEnable(GLenum cap)
{
	R1(glEnable, cap);
}

void glDisable(GLenum cap)
{
	R1(glDisable, cap);
}

void glPushAttrib(GLbitfield mask)
{
	R1(glPushAttrib, mask);
}

void glPopAttrib(void)
{
	R0(glPopAttrib);
}

static GLuint next_list = 1;

GLuint glGenLists(GLsizei range)
{
	R1(glGenLists, range);
	GLuint first = next_list;
	next_list += (GLuint)range;
	return first;
}

void glNewList(GLuint list, GLenum mode)
{
	R2(glNewList, list, mode);
}

void glEndList(void)
{
	R0(glEndList);
}

void glCallList(GLuint list)
{
	R1(glCallList, list);
}

void glCallLists(GLsizei n, GLenum type, const void *lists)
{
	R2(glCallLists, n, type);
}

void glDeleteLists(GLuint list, GLsizei range)
{
	R2(glDeleteLists, list, range);
}

void glListBase(GLuint base)
{
	R1(glListBase, base);
}

void glMatrixMode(GLenum mode)
{
	R1(glMatrixMode, mode);
}

void glLoadIdentity(void)
{
	R0(glLoadIdentity);
}

#define MATRIX(name, T, decl)                       \
	void name(const T decl)                     \
	{                                           \
		R4(name, m[0], m[5], m[10], m[12]); \
	}
MATRIX(glLoadMatrixf, GLfloat, *m)
MATRIX(glLoadMatrixd, GLdouble, *m)
MATRIX(glMultMatrixf, GLfloat, *m)
MATRIX(glMultMatrixd, GLdouble, *m)
MATRIX(glLoadTransposeMatrixf, GLfloat, m[16])
MATRIX(glLoadTransposeMatrixd, GLdouble, m[16])
MATRIX(glMultTransposeMatrixf, GLfloat, m[16])
MATRIX(glMultTransposeMatrixd, GLdouble, m[16])

void glPushMatrix(void)
{
	R0(glPushMatrix);
}

void glPopMatrix(void)
{
	R0(glPopMatrix);
}

void glRotatef(GLfloat a, GLfloat x, GLfloat y, GLfloat z)
{
	R4(glRotatef, a, x, y, z);
}

void glRotated(GLdouble a, GLdouble x, GLdouble y, GLdouble z)
{
	R4(glRotated, a, x, y, z);
}

void glTranslatef(GLfloat x, GLfloat y, GLfloat z)
{
	R3(glTranslatef, x, y, z);
}

void glTranslated(GLdouble x, GLdouble y, GLdouble z)
{
	R3(glTranslated, x, y, z);
}

void glScalef(GLfloat x, GLfloat y, GLfloat z)
{
	R3(glScalef, x, y, z);
}

void glScaled(GLdouble x, GLdouble y, GLdouble z)
{
	R3(glScaled, x, y, z);
}

void glFrustum(GLdouble l, GLdouble r, GLdouble b, GLdouble t, GLdouble n, GLdouble f)
{
	R4(glFrustum, l, r, n, f);
}

void glOrtho(GLdouble l, GLdouble r, GLdouble b, GLdouble t, GLdouble n, GLdouble f)
{
	R4(glOrtho, l, r, n, f);
}

void glFrustumf(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f)
{
	R4(glFrustumf, l, r, n, f);
}

void glOrthof(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f)
{
	R4(glOrthof, l, r, n, f);
}

void glVertexPointer(GLint size, GLenum type, GLsizei stride, const void *p)
{
	R3(glVertexPointer, size, type, stride);
}

void glColorPointer(GLint size, GLenum type, GLsizei stride, const void *p)
{
	R3(glColorPointer, size, type, stride);
}

void glEnableClientState(GLenum a)
{
	R1(glEnableClientState, a);
}

void glDisableClientState(GLenum a)
{
	R1(glDisableClientState, a);
}

void glArrayElement(GLint i)
{
	R1(glArrayElement, i);
}

void glDrawArrays(GLenum mode, GLint first, GLsizei count)
{
	R3(glDrawArrays, mode, first, count);
}

void glDrawElements(GLenum mode, GLsizei count, GLenum type, const void *indices)
{
	R3(glDrawElements, mode, count, type);
}

void glDrawRangeElements(GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type, const void *indices)
{
	R4(glDrawRangeElements, mode, start, end, count);
}

void glInterleavedArrays(GLenum format, GLsizei stride, const void *p)
{
	R2(glInterleavedArrays, format, stride);
}

void glBindBuffer(GLenum target, GLuint buffer)
{
	R2(glBindBuffer, target, buffer);
}

void glBindBufferARB(GLenum target, GLuint buffer)
{
	R2(glBindBufferARB, target, buffer);
}

void glBufferData(GLenum target, GLsizeiptr size, const void *data, GLenum usage)
{
	R2(glBufferData, target, size);
}

void glBufferDataARB(GLenum target, GLsizeiptrARB size, const void *data, GLenum usage)
{
	R2(glBufferDataARB, target, size);
}

void glBufferSubData(GLenum target, GLintptr offset, GLsizeiptr size, const void *data)
{
	R3(glBufferSubData, target, offset, size);
}

void glBufferSubDataARB(GLenum target, GLintptrARB offset, GLsizeiptrARB size, const void *data)
{
	R3(glBufferSubDataARB, target, offset, size);
}

void glDeleteBuffers(GLsizei n, const GLuint *names)
{
	R1(glDeleteBuffers, n);
}

void glDeleteBuffersARB(GLsizei n, const GLuint *names)
{
	R1(glDeleteBuffersARB, n);
}

void *glMapBuffer(GLenum target, GLenum access)
{
	R2(glMapBuffer, target, access);
	return map_memory;
}

void *glMapBufferARB(GLenum target, GLenum access)
{
	R2(glMapBufferARB, target, access);
	return map_memory;
}

void *glMapBufferRange(GLenum target, GLintptr offset, GLsizeiptr length, GLbitfield access)
{
	R4(glMapBufferRange, target, offset, length, access);
	return map_memory;
}

GLboolean glUnmapBuffer(GLenum target)
{
	R1(glUnmapBuffer, target);
	return GL_TRUE;
}

GLboolean glUnmapBufferARB(GLenum target)
{
	R1(glUnmapBufferARB, target);
	return GL_TRUE;
}

void glUseProgram(GLuint program)
{
	R1(glUseProgram, program);
}

void glUseProgramObjectARB(GLhandleARB program)
{
	R1(glUseProgramObjectARB, program);
}

void glBindTexture(GLenum target, GLuint texture)
{
	R2(glBindTexture, target, texture);
}

void glTexImage1D(GLenum target, GLint level, GLint internal, GLsizei w, GLint border, GLenum format, GLenum type,
		  const void *pixels)
{
	R2(glTexImage1D, target, w);
}

void glTexImage2D(GLenum target, GLint level, GLint internal, GLsizei w, GLsizei h, GLint border, GLenum format,
		  GLenum type, const void *pixels)
{
	R3(glTexImage2D, target, w, h);
}

void glTexImage3D(GLenum target, GLint level, GLint internal, GLsizei w, GLsizei h, GLsizei d, GLint border,
		  GLenum format, GLenum type, const void *pixels)
{
	R4(glTexImage3D, target, w, h, d);
}

GLint glRenderMode(GLenum mode)
{
	R1(glRenderMode, mode);
	return 0;
}

void glFeedbackBuffer(GLsizei size, GLenum type, GLfloat *buffer)
{
	R2(glFeedbackBuffer, size, type);
}

void glSelectBuffer(GLsizei size, GLuint *buffer)
{
	R1(glSelectBuffer, size);
}

void glClear(GLbitfield mask)
{
	R1(glClear, mask);
}

void glFlush(void)
{
	R0(glFlush);
}

void glFinish(void)
{
	R0(glFinish);
}

/* ---- GLX and EGL: contexts are distinct fake pointers ---- */

static uintptr_t next_context = 0x1000;

static void *new_context(void)
{
	pthread_mutex_lock(&lock);
	next_context += 16;
	void *c = (void *)next_context;
	pthread_mutex_unlock(&lock);
	return c;
}

void glXSwapBuffers(Display *dpy, GLXDrawable drawable)
{
	R1(glXSwapBuffers, drawable);
}

GLXContext glXCreateContext(Display *dpy, XVisualInfo *vis, GLXContext share, Bool direct)
{
	R0(glXCreateContext);
	return new_context();
}

GLXContext glXCreateNewContext(Display *dpy, GLXFBConfig config, int type, GLXContext share, Bool direct)
{
	R0(glXCreateNewContext);
	return new_context();
}

GLXContext glXCreateContextAttribsARB(Display *dpy, GLXFBConfig config, GLXContext share, Bool direct,
				      const int *attribs)
{
	R0(glXCreateContextAttribsARB);
	return new_context();
}

void glXDestroyContext(Display *dpy, GLXContext ctx)
{
	R0(glXDestroyContext);
}

Bool glXMakeCurrent(Display *dpy, GLXDrawable drawable, GLXContext ctx)
{
	R1(glXMakeCurrent, drawable);
	return True;
}

Bool glXMakeContextCurrent(Display *dpy, GLXDrawable draw, GLXDrawable read, GLXContext ctx)
{
	R2(glXMakeContextCurrent, draw, read);
	return True;
}

EGLBoolean eglSwapBuffers(EGLDisplay dpy, EGLSurface surface)
{
	R0(eglSwapBuffers);
	return EGL_TRUE;
}

EGLContext eglCreateContext(EGLDisplay dpy, EGLConfig config, EGLContext share, const EGLint *attribs)
{
	R0(eglCreateContext);
	return new_context();
}

EGLBoolean eglDestroyContext(EGLDisplay dpy, EGLContext ctx)
{
	R0(eglDestroyContext);
	return EGL_TRUE;
}

EGLBoolean eglMakeCurrent(EGLDisplay dpy, EGLSurface draw, EGLSurface read, EGLContext ctx)
{
	R0(eglMakeCurrent);
	return EGL_TRUE;
}

/* The loaders answer with this library's own functions. */
static void (*own(const char *name))(void)
{
	Dl_info info;
	void (*f)(void) = NULL;
	if (!dladdr(map_memory, &info))
		return NULL;
	void *self = dlopen(info.dli_fname, RTLD_LAZY | RTLD_NOLOAD);
	if (!self)
		return NULL;
	void *p = dlsym(self, name);
	memcpy(&f, &p, sizeof(f));
	dlclose(self);
	return f;
}

__GLXextFuncPtr glXGetProcAddressARB(const GLubyte *name)
{
	R0(glXGetProcAddressARB);
	return own((const char *)name);
}

void (*glXGetProcAddress(const GLubyte *name))(void)
{
	R0(glXGetProcAddress);
	return own((const char *)name);
}

__eglMustCastToProperFunctionPointerType eglGetProcAddress(const char *name)
{
	R0(eglGetProcAddress);
	return own(name);
}
