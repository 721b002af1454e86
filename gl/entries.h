/* spindle-gl: every entry point the layer defines (and so interposes), as
 * an X-macro list: E(name) each. real.c resolves the real ones by these
 * names, and glXGetProcAddress / eglGetProcAddress hand out the layer's
 * own for them. */
#ifndef SPINDLE_GL_ENTRIES_H
#define SPINDLE_GL_ENTRIES_H

/* clang-format off */
#define SGL_VERTEX_ENTRIES(E) \
	E(glVertex2d) E(glVertex2dv) E(glVertex2f) E(glVertex2fv) E(glVertex2i) E(glVertex2iv) \
	E(glVertex2s) E(glVertex2sv) E(glVertex3d) E(glVertex3dv) E(glVertex3f) E(glVertex3fv) \
	E(glVertex3i) E(glVertex3iv) E(glVertex3s) E(glVertex3sv) E(glVertex4d) E(glVertex4dv) \
	E(glVertex4f) E(glVertex4fv) E(glVertex4i) E(glVertex4iv) E(glVertex4s) E(glVertex4sv)

#define SGL_COLOR_ENTRIES(E) \
	E(glColor3b) E(glColor3bv) E(glColor3d) E(glColor3dv) E(glColor3f) E(glColor3fv) E(glColor3i) \
	E(glColor3iv) E(glColor3s) E(glColor3sv) E(glColor3ub) E(glColor3ubv) E(glColor3ui) E(glColor3uiv) \
	E(glColor3us) E(glColor3usv) E(glColor4b) E(glColor4bv) E(glColor4d) E(glColor4dv) E(glColor4f) \
	E(glColor4fv) E(glColor4i) E(glColor4iv) E(glColor4s) E(glColor4sv) E(glColor4ub) E(glColor4ubv) \
	E(glColor4ui) E(glColor4uiv) E(glColor4us) E(glColor4usv)

#define SGL_STATE_ENTRIES(E) \
	E(glBegin) E(glEnd) E(glNormal3b) E(glNormal3bv) E(glNormal3d) E(glNormal3dv) E(glNormal3f) \
	E(glNormal3fv) E(glNormal3i) E(glNormal3iv) E(glNormal3s) E(glNormal3sv) E(glMaterialf) \
	E(glMaterialfv) E(glMateriali) E(glMaterialiv) E(glColorMaterial) E(glShadeModel) E(glEnable) \
	E(glDisable) E(glPushAttrib) E(glPopAttrib) E(glRectd) E(glRectdv) E(glRectf) E(glRectfv) \
	E(glRecti) E(glRectiv) E(glRects) E(glRectsv)

#define SGL_LIST_ENTRIES(E) \
	E(glNewList) E(glEndList) E(glCallList) E(glCallLists) E(glDeleteLists) E(glListBase)

#define SGL_MATRIX_ENTRIES(E) \
	E(glMatrixMode) E(glLoadIdentity) E(glLoadMatrixf) E(glLoadMatrixd) E(glMultMatrixf) \
	E(glMultMatrixd) E(glLoadTransposeMatrixf) E(glLoadTransposeMatrixd) E(glMultTransposeMatrixf) \
	E(glMultTransposeMatrixd) E(glPushMatrix) E(glPopMatrix) E(glRotatef) E(glRotated) E(glTranslatef) \
	E(glTranslated) E(glScalef) E(glScaled) E(glFrustum) E(glOrtho) E(glFrustumf) E(glOrthof)

#define SGL_ARRAY_ENTRIES(E) \
	E(glVertexPointer) E(glColorPointer) E(glEnableClientState) E(glDisableClientState) \
	E(glArrayElement) E(glDrawArrays) E(glDrawElements) E(glDrawRangeElements) E(glInterleavedArrays) \
	E(glBindBuffer) E(glBufferData) E(glBufferSubData) E(glDeleteBuffers) E(glMapBuffer) \
	E(glMapBufferRange) E(glUnmapBuffer) E(glBindBufferARB) E(glBufferDataARB) E(glBufferSubDataARB) \
	E(glDeleteBuffersARB) E(glMapBufferARB) E(glUnmapBufferARB)

#define SGL_OTHER_ENTRIES(E) \
	E(glUseProgram) E(glUseProgramObjectARB) E(glBindTexture) E(glTexImage1D) E(glTexImage2D) \
	E(glTexImage3D) E(glRenderMode) E(glFeedbackBuffer) E(glSelectBuffer) E(glClear) E(glFlush) \
	E(glFinish) E(glXSwapBuffers) E(glXCreateContext) E(glXCreateNewContext) \
	E(glXCreateContextAttribsARB) E(glXDestroyContext) E(glXMakeCurrent) E(glXMakeContextCurrent) \
	E(glXGetProcAddress) E(glXGetProcAddressARB) E(eglSwapBuffers) E(eglCreateContext) \
	E(eglDestroyContext) E(eglMakeCurrent) E(eglGetProcAddress)

#define SGL_ENTRIES(E) \
	SGL_VERTEX_ENTRIES(E) SGL_COLOR_ENTRIES(E) SGL_STATE_ENTRIES(E) SGL_LIST_ENTRIES(E) \
	SGL_MATRIX_ENTRIES(E) SGL_ARRAY_ENTRIES(E) SGL_OTHER_ENTRIES(E)
/* clang-format on */

#define SGL_ENUM_ENTRY(name) SGL_E_##name,
enum sgl_entry { SGL_ENTRIES(SGL_ENUM_ENTRY) SGL_ENTRY_COUNT };
#undef SGL_ENUM_ENTRY

#endif
