#include "calibration.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const key_names[CALIBRATION_KEYS] = {
	[CALIBRATION_PHASE] = "phase-offset",
	[CALIBRATION_AXIS_U] = "axis-offset-u",
	[CALIBRATION_AXIS_V] = "axis-offset-v",
	[CALIBRATION_VERTICAL_SCALE] = "vertical-scale",
	[CALIBRATION_VERTICAL_OFFSET] = "vertical-offset",
};

void calibration_identity(struct calibration *c)
{
	*c = (struct calibration){ .vertical_scale = 1.0f };
}

const char *calibration_key_name(unsigned key)
{
	return key < CALIBRATION_KEYS ? key_names[key] : NULL;
}

int calibration_key_from_name(const char *name)
{
	for (unsigned k = 0; k < CALIBRATION_KEYS; k++)
		if (!strcmp(name, key_names[k]))
			return (int)k;
	return -ENOENT;
}

static bool whole_offset(double v)
{
	return v == floor(v) && fabs(v) <= CALIBRATION_MAX_OFFSET;
}

int calibration_set(struct calibration *c, unsigned key, double value)
{
	if (isnan(value))
		return -EINVAL;
	switch (key) {
	case CALIBRATION_PHASE:
		if (!(value >= -180.0 && value <= 180.0))
			return -EINVAL;
		c->phase_deg = (float)value;
		return 0;
	case CALIBRATION_AXIS_U:
	case CALIBRATION_AXIS_V:
		if (!whole_offset(value))
			return -EINVAL;
		*(key == CALIBRATION_AXIS_U ? &c->axis_u : &c->axis_v) = (int32_t)value;
		return 0;
	case CALIBRATION_VERTICAL_SCALE:
		if (!(value >= 0.5 && value <= 2.0))
			return -EINVAL;
		c->vertical_scale = (float)value;
		return 0;
	case CALIBRATION_VERTICAL_OFFSET:
		if (!(value >= -0.5 && value <= 0.5))
			return -EINVAL;
		c->vertical_offset = (float)value;
		return 0;
	}
	return -EINVAL;
}

int calibration_set_text(struct calibration *c, unsigned key, const char *value)
{
	char *end;
	errno = 0;
	double v = strtod(value, &end);
	if (errno || end == value || *end)
		return -EINVAL;
	return calibration_set(c, key, v);
}

double calibration_get(const struct calibration *c, unsigned key)
{
	switch (key) {
	case CALIBRATION_PHASE:
		return c->phase_deg;
	case CALIBRATION_AXIS_U:
		return c->axis_u;
	case CALIBRATION_AXIS_V:
		return c->axis_v;
	case CALIBRATION_VERTICAL_SCALE:
		return c->vertical_scale;
	case CALIBRATION_VERTICAL_OFFSET:
		return c->vertical_offset;
	}
	return 0.0;
}

void calibration_format(const struct calibration *c, unsigned key, char *out, size_t size)
{
	if (key == CALIBRATION_AXIS_U || key == CALIBRATION_AXIS_V)
		snprintf(out, size, "%d", (int)calibration_get(c, key));
	else
		snprintf(out, size, "%.9g", calibration_get(c, key));
}

int calibration_check(const struct calibration *c, const struct geometry *g)
{
	int64_t u = c->axis_u, v = c->axis_v;
	if (4 * llabs(u) > (int64_t)g->width || 4 * llabs(v) > (int64_t)g->height)
		return -EINVAL;
	return 0;
}

bool calibration_has_transform(const struct calibration *c)
{
	return c->phase_deg != 0.0f || c->vertical_scale != 1.0f || c->vertical_offset != 0.0f;
}

void calibration_transform(const struct calibration *c, float m[16])
{
	double a = c->phase_deg * (M_PI / 180.0);
	float cs = (float)cos(a), sn = (float)sin(a);
	memset(m, 0, 16 * sizeof(float));
	m[0] = cs; /* x' = x cos a + z sin a */
	m[8] = sn;
	m[2] = -sn; /* z' = -x sin a + z cos a */
	m[10] = cs;
	m[5] = c->vertical_scale;
	m[13] = c->vertical_offset;
	m[15] = 1.0f;
}
