/* spindle-gl: the system's OpenGL, GLX and EGL headers with every
 * prototype the layer defines, and the two OpenGL ES 1 entry points
 * (glFrustumf, glOrthof) that the desktop headers lack. */
#ifndef SPINDLE_GL_GLAPI_H
#define SPINDLE_GL_GLAPI_H

#define GL_GLEXT_PROTOTYPES 1
#define GLX_GLXEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <GL/glxext.h>

void glFrustumf(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f);
void glOrthof(GLfloat l, GLfloat r, GLfloat b, GLfloat t, GLfloat n, GLfloat f);

#endif
