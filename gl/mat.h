/* spindle-gl: 4x4 matrices, column-major as OpenGL stores them
 * (m[col * 4 + row]), single precision as the fixed-function pipeline. */
#ifndef SPINDLE_GL_MAT_H
#define SPINDLE_GL_MAT_H

#include <stdbool.h>

void sgl_mat_identity(float m[16]);
/* out = a * b (b applies first); out may alias a or b. */
void sgl_mat_mul(float out[16], const float a[16], const float b[16]);
void sgl_mat_from_double(float out[16], const double m[16]);
void sgl_mat_transpose(float out[16], const float m[16]);
/* The matrices glRotate, glTranslate, glScale, glFrustum and glOrtho
 * multiply the current one by. */
void sgl_mat_rotate(float out[16], float angle_deg, float x, float y, float z);
void sgl_mat_translate(float out[16], float x, float y, float z);
void sgl_mat_scale(float out[16], float x, float y, float z);
bool sgl_mat_frustum(float out[16], double l, double r, double b, double t, double n, double f);
bool sgl_mat_ortho(float out[16], double l, double r, double b, double t, double n, double f);
/* out = m * (x, y, z, w). */
void sgl_mat_apply(const float m[16], const float in[4], float out[4]);
/* Bottom row (0, 0, 0, 1) and every element finite. */
bool sgl_mat_is_affine(const float m[16]);
bool sgl_mat_equal(const float a[16], const float b[16]);

#endif
