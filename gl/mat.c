#include "mat.h"

#include <math.h>
#include <string.h>

void sgl_mat_identity(float m[16])
{
	static const float id[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
	memcpy(m, id, sizeof(id));
}

void sgl_mat_mul(float out[16], const float a[16], const float b[16])
{
	float r[16];
	for (int c = 0; c < 4; c++) {
		for (int row = 0; row < 4; row++) {
			float s = 0;
			for (int k = 0; k < 4; k++)
				s += a[k * 4 + row] * b[c * 4 + k];
			r[c * 4 + row] = s;
		}
	}
	memcpy(out, r, sizeof(r));
}

void sgl_mat_from_double(float out[16], const double m[16])
{
	for (int i = 0; i < 16; i++)
		out[i] = (float)m[i];
}

void sgl_mat_transpose(float out[16], const float m[16])
{
	float r[16];
	for (int c = 0; c < 4; c++)
		for (int row = 0; row < 4; row++)
			r[c * 4 + row] = m[row * 4 + c];
	memcpy(out, r, sizeof(r));
}

void sgl_mat_rotate(float out[16], float angle_deg, float x, float y, float z)
{
	sgl_mat_identity(out);
	float len = sqrtf(x * x + y * y + z * z);
	if (!(len > 0) || !isfinite(len))
		return;
	x /= len;
	y /= len;
	z /= len;
	double a = angle_deg * (M_PI / 180.0);
	float c = (float)cos(a), s = (float)sin(a), k = 1 - c;
	out[0] = x * x * k + c;
	out[1] = y * x * k + z * s;
	out[2] = x * z * k - y * s;
	out[4] = x * y * k - z * s;
	out[5] = y * y * k + c;
	out[6] = y * z * k + x * s;
	out[8] = x * z * k + y * s;
	out[9] = y * z * k - x * s;
	out[10] = z * z * k + c;
}

void sgl_mat_translate(float out[16], float x, float y, float z)
{
	sgl_mat_identity(out);
	out[12] = x;
	out[13] = y;
	out[14] = z;
}

void sgl_mat_scale(float out[16], float x, float y, float z)
{
	sgl_mat_identity(out);
	out[0] = x;
	out[5] = y;
	out[10] = z;
}

bool sgl_mat_frustum(float out[16], double l, double r, double b, double t, double n, double f)
{
	if (n <= 0 || f <= 0 || l == r || b == t || n == f)
		return false;
	memset(out, 0, 16 * sizeof(float));
	out[0] = (float)(2 * n / (r - l));
	out[5] = (float)(2 * n / (t - b));
	out[8] = (float)((r + l) / (r - l));
	out[9] = (float)((t + b) / (t - b));
	out[10] = (float)(-(f + n) / (f - n));
	out[11] = -1;
	out[14] = (float)(-2 * f * n / (f - n));
	return true;
}

bool sgl_mat_ortho(float out[16], double l, double r, double b, double t, double n, double f)
{
	if (l == r || b == t || n == f)
		return false;
	sgl_mat_identity(out);
	out[0] = (float)(2 / (r - l));
	out[5] = (float)(2 / (t - b));
	out[10] = (float)(-2 / (f - n));
	out[12] = (float)(-(r + l) / (r - l));
	out[13] = (float)(-(t + b) / (t - b));
	out[14] = (float)(-(f + n) / (f - n));
	return true;
}

void sgl_mat_apply(const float m[16], const float in[4], float out[4])
{
	float r[4];
	for (int row = 0; row < 4; row++)
		r[row] = m[row] * in[0] + m[4 + row] * in[1] + m[8 + row] * in[2] + m[12 + row] * in[3];
	memcpy(out, r, sizeof(r));
}

bool sgl_mat_is_affine(const float m[16])
{
	for (int i = 0; i < 16; i++)
		if (!isfinite(m[i]))
			return false;
	return m[3] == 0 && m[7] == 0 && m[11] == 0 && m[15] == 1;
}

bool sgl_mat_equal(const float a[16], const float b[16])
{
	return memcmp(a, b, 16 * sizeof(float)) == 0;
}
