/* One pixel column of an upright grid (grid_column.h). */
#include "grid_column.h"

#include <math.h>
#include <string.h>

void grid_column_setup(struct column *col, const struct scene_grid *gr, double fx, double fz, bool tri)
{
	if (!tri) {
		col->i[0] = grid_clamp_index((int64_t)floor(fx + 0.5), gr->n[0]);
		col->k[0] = grid_clamp_index((int64_t)floor(fz + 0.5), gr->n[2]);
		col->line[0] = ((size_t)col->k[0] * gr->n[0] + col->i[0]) * gr->n[1];
		col->lines = 1;
		return;
	}
	double lx = floor(fx), lz = floor(fz);
	col->t[0] = (float)(fx - lx);
	col->t[2] = (float)(fz - lz);
	for (int b = 0; b < 2; b++) {
		col->i[b] = grid_clamp_index((int64_t)lx + b, gr->n[0]);
		col->k[b] = grid_clamp_index((int64_t)lz + b, gr->n[2]);
	}
	for (int b = 0; b < 4; b++)
		col->line[b] = ((size_t)col->k[b >> 1] * gr->n[0] + col->i[b & 1]) * gr->n[1];
	col->lines = 4;
}

bool grid_column_dark(const struct column *col, const struct scene_grid *gr, const struct scene_transfer *tf,
		      uint32_t b0, uint32_t b1, bool *dark)
{
	if (!gr->brick_max) {
		memset(dark + b0, 0, (b1 - b0 + 1) * sizeof(*dark));
		return false;
	}
	uint32_t nb = scene_grid_bricks(gr->n[1]);
	const float *line[4];
	for (int l = 0; l < col->lines; l++)
		line[l] = gr->brick_max + col->line[l] / gr->n[1] * nb;
	bool all = true;
	for (uint32_t b = b0; b <= b1; b++) {
		float mx = line[0][b];
		for (int l = 1; l < col->lines; l++)
			mx = line[l][b] > mx ? line[l][b] : mx;
		dark[b] = (double)mx + fabs((double)mx) * 1e-5 < tf->threshold;
		all &= dark[b];
	}
	return all;
}

void grid_column_mix(const struct column *col, const struct scene_grid *gr, uint32_t j0, uint32_t j1, float *out,
		     size_t stride)
{
	float tx = col->t[0], tz = col->t[2];
#define MIX(T)                                                                                                      \
	do {                                                                                                        \
		const T *l00 = (const T *)gr->data + col->line[0];                                                  \
		if (col->lines == 1) {                                                                              \
			for (uint32_t j = j0; j <= j1; j++, out += stride)                                          \
				*out = (float)l00[j];                                                               \
			break;                                                                                      \
		}                                                                                                   \
		const T *l10 = (const T *)gr->data + col->line[1];                                                  \
		const T *l01 = (const T *)gr->data + col->line[2], *l11 = (const T *)gr->data + col->line[3];       \
		for (uint32_t j = j0; j <= j1; j++, out += stride)                                                  \
			*out = lerp(lerp((float)l00[j], (float)l10[j], tx), lerp((float)l01[j], (float)l11[j], tx), \
				    tz);                                                                            \
	} while (0)
	switch (gr->type) {
	case SCENE_GRID_U8:
		MIX(uint8_t);
		break;
	case SCENE_GRID_U16:
		MIX(uint16_t);
		break;
	case SCENE_GRID_I16:
		MIX(int16_t);
		break;
	default:
		MIX(float);
		break;
	}
#undef MIX
}
