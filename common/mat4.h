/* 4x4 matrices, column-major (element [c * 4 + r] is row r of column c), as
 * the protocol's transforms, the daemon's draws and spindle-view's camera
 * hold them. */
#ifndef SPINDLE_MAT4_H
#define SPINDLE_MAT4_H

/* out = a * b (b applied first). out may be a or b. */
void mat4_mul(float out[16], const float a[16], const float b[16]);

#endif
