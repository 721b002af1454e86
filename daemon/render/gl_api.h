/* The OpenGL (ES) entry points the GL renderers use, loaded at run time
 * through eglGetProcAddress() or OSMesaGetProcAddress(), so that one GL code
 * path serves both context kinds and the daemon never links a GL library
 * (libOSMesa exports gl* symbols of its own; libGLESv2 would clash).
 *
 * Only what OpenGL ES 3.1 and desktop OpenGL 4.3 core both have. */
#ifndef SPINDLE_GL_API_H
#define SPINDLE_GL_API_H

#include <GLES3/gl31.h>

/* X(return type, name without the gl prefix, parameter list) */
#define GL_API_FUNCTIONS(X)                                                                                          \
	X(const GLubyte *, GetString, (GLenum name))                                                                 \
	X(void, GetIntegerv, (GLenum pname, GLint * data))                                                           \
	X(GLenum, GetError, (void))                                                                                  \
	X(GLuint, CreateShader, (GLenum type))                                                                       \
	X(void, ShaderSource, (GLuint s, GLsizei n, const GLchar *const *str, const GLint *len))                     \
	X(void, CompileShader, (GLuint s))                                                                           \
	X(void, GetShaderiv, (GLuint s, GLenum pname, GLint * out))                                                  \
	X(void, GetShaderInfoLog, (GLuint s, GLsizei size, GLsizei * len, GLchar * log))                             \
	X(void, DeleteShader, (GLuint s))                                                                            \
	X(GLuint, CreateProgram, (void))                                                                             \
	X(void, AttachShader, (GLuint p, GLuint s))                                                                  \
	X(void, LinkProgram, (GLuint p))                                                                             \
	X(void, GetProgramiv, (GLuint p, GLenum pname, GLint * out))                                                 \
	X(void, GetProgramInfoLog, (GLuint p, GLsizei size, GLsizei * len, GLchar * log))                            \
	X(void, DeleteProgram, (GLuint p))                                                                           \
	X(void, UseProgram, (GLuint p))                                                                              \
	X(GLint, GetUniformLocation, (GLuint p, const GLchar *name))                                                 \
	X(void, Uniform1i, (GLint loc, GLint v))                                                                     \
	X(void, Uniform1ui, (GLint loc, GLuint v))                                                                   \
	X(void, Uniform4f, (GLint loc, GLfloat a, GLfloat b, GLfloat c, GLfloat d))                                  \
	X(void, Uniform4ui, (GLint loc, GLuint a, GLuint b, GLuint c, GLuint d))                                     \
	X(void, GenTextures, (GLsizei n, GLuint * t))                                                                \
	X(void, DeleteTextures, (GLsizei n, const GLuint *t))                                                        \
	X(void, BindTexture, (GLenum target, GLuint t))                                                              \
	X(void, ActiveTexture, (GLenum unit))                                                                        \
	X(void, TexStorage2D, (GLenum target, GLsizei levels, GLenum fmt, GLsizei w, GLsizei h))                     \
	X(void, TexSubImage2D,                                                                                       \
	  (GLenum target, GLint level, GLint x, GLint y, GLsizei w, GLsizei h, GLenum fmt, GLenum type,              \
	   const void *pixels))                                                                                      \
	X(void, TexStorage3D, (GLenum target, GLsizei levels, GLenum fmt, GLsizei w, GLsizei h, GLsizei d))          \
	X(void, TexSubImage3D,                                                                                       \
	  (GLenum tg, GLint lv, GLint x, GLint y, GLint z, GLsizei w, GLsizei h, GLsizei d, GLenum fmt, GLenum type, \
	   const void *pixels))                                                                                      \
	X(void, TexParameteri, (GLenum target, GLenum pname, GLint v))                                               \
	X(void, PixelStorei, (GLenum pname, GLint v))                                                                \
	X(void, GenFramebuffers, (GLsizei n, GLuint * f))                                                            \
	X(void, DeleteFramebuffers, (GLsizei n, const GLuint *f))                                                    \
	X(void, BindFramebuffer, (GLenum target, GLuint f))                                                          \
	X(void, FramebufferTexture2D, (GLenum target, GLenum att, GLenum tt, GLuint t, GLint level))                 \
	X(GLenum, CheckFramebufferStatus, (GLenum target))                                                           \
	X(void, ReadPixels, (GLint x, GLint y, GLsizei w, GLsizei h, GLenum fmt, GLenum type, void *pixels))         \
	X(void, GenBuffers, (GLsizei n, GLuint * b))                                                                 \
	X(void, DeleteBuffers, (GLsizei n, const GLuint *b))                                                         \
	X(void, BindBuffer, (GLenum target, GLuint b))                                                               \
	X(void, BindBufferBase, (GLenum target, GLuint index, GLuint b))                                             \
	X(void, BufferData, (GLenum target, GLsizeiptr size, const void *data, GLenum usage))                        \
	X(void, BufferSubData, (GLenum target, GLintptr off, GLsizeiptr size, const void *data))                     \
	X(void *, MapBufferRange, (GLenum target, GLintptr off, GLsizeiptr len, GLbitfield access))                  \
	X(GLboolean, UnmapBuffer, (GLenum target))                                                                   \
	X(void, GenVertexArrays, (GLsizei n, GLuint * a))                                                            \
	X(void, DeleteVertexArrays, (GLsizei n, const GLuint *a))                                                    \
	X(void, BindVertexArray, (GLuint a))                                                                         \
	X(void, VertexAttribIPointer, (GLuint i, GLint size, GLenum type, GLsizei stride, const void *ptr))          \
	X(void, EnableVertexAttribArray, (GLuint i))                                                                 \
	X(void, Viewport, (GLint x, GLint y, GLsizei w, GLsizei h))                                                  \
	X(void, Scissor, (GLint x, GLint y, GLsizei w, GLsizei h))                                                   \
	X(void, Enable, (GLenum cap))                                                                                \
	X(void, Disable, (GLenum cap))                                                                               \
	X(void, ClearColor, (GLfloat r, GLfloat g, GLfloat b, GLfloat a))                                            \
	X(void, Clear, (GLbitfield mask))                                                                            \
	X(void, BlendEquation, (GLenum mode))                                                                        \
	X(void, DrawArrays, (GLenum mode, GLint first, GLsizei count))                                               \
	X(void, DispatchCompute, (GLuint x, GLuint y, GLuint z))                                                     \
	X(void, DispatchComputeIndirect, (GLintptr offset))                                                          \
	X(void, BindImageTexture,                                                                                    \
	  (GLuint unit, GLuint t, GLint level, GLboolean layered, GLint layer, GLenum access, GLenum fmt))           \
	X(void, MemoryBarrier, (GLbitfield barriers))                                                                \
	X(GLsync, FenceSync, (GLenum cond, GLbitfield flags))                                                        \
	X(GLenum, ClientWaitSync, (GLsync s, GLbitfield flags, GLuint64 timeout))                                    \
	X(void, DeleteSync, (GLsync s))                                                                              \
	X(void, Flush, (void))                                                                                       \
	X(void, Finish, (void))

#define GL_API_MEMBER(ret, name, params) ret(GL_APIENTRY *name) params;

struct gl_api {
	GL_API_FUNCTIONS(GL_API_MEMBER)
	/* glGetGraphicsResetStatus (ES 3.2, GL 4.5) or its KHR/EXT form;
	 * NULL where the context has none. */
	GLenum(GL_APIENTRY *GetGraphicsResetStatus)(void);
};

/* Fills api through getproc. Returns 0, or -ENOSYS naming the first entry
 * point missing in *missing. */
typedef void (*gl_proc)(void);
int gl_api_load(struct gl_api *api, gl_proc (*getproc)(const char *name), const char **missing);

#endif
