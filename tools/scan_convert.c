/* Stored voxels to a struct scan's (scan_priv.h, scan_finish()): the
 * rescale, the choice of the result type and the conversion, done in the
 * buffer the reader filled: forwards when a voxel shrinks or keeps its
 * size, backwards after growing the buffer when it grows, so that no
 * voxel is overwritten before it is read and no second copy of the volume
 * is made. */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scan_priv.h"

size_t scan_stored_size(enum scan_stored stored)
{
	switch (stored) {
	case SCAN_STORED_U8:
	case SCAN_STORED_I8:
		return 1;
	case SCAN_STORED_U16:
	case SCAN_STORED_I16:
		return 2;
	case SCAN_STORED_RGB24:
		return 3;
	case SCAN_STORED_U32:
	case SCAN_STORED_I32:
	case SCAN_STORED_F32:
	case SCAN_STORED_RGBA32:
		return 4;
	case SCAN_STORED_F64:
		return 8;
	}
	return 0;
}

void scan_swap_bytes(void *data, size_t count, size_t width)
{
	uint8_t *p = data;
	for (size_t n = 0; n < count; n++, p += width)
		for (size_t a = 0, b = width - 1; a < b; a++, b--) {
			uint8_t t = p[a];
			p[a] = p[b];
			p[b] = t;
		}
}

static bool is_integer(enum scan_stored stored)
{
	return stored != SCAN_STORED_F32 && stored != SCAN_STORED_F64 && stored != SCAN_STORED_RGB24 &&
	       stored != SCAN_STORED_RGBA32;
}

/* Stored voxel n as a whole number (integer types only). */
static int64_t get_int(const void *buf, enum scan_stored stored, size_t n)
{
	const uint8_t *p = (const uint8_t *)buf + n * scan_stored_size(stored);
	union {
		uint8_t u8;
		int8_t i8;
		uint16_t u16;
		int16_t i16;
		uint32_t u32;
		int32_t i32;
	} v;
	memcpy(&v, p, scan_stored_size(stored));
	switch (stored) {
	case SCAN_STORED_U8:
		return v.u8;
	case SCAN_STORED_I8:
		return v.i8;
	case SCAN_STORED_U16:
		return v.u16;
	case SCAN_STORED_I16:
		return v.i16;
	case SCAN_STORED_U32:
		return v.u32;
	case SCAN_STORED_I32:
		return v.i32;
	default:
		return 0;
	}
}

/* Stored voxel n as a number (scalar types). */
static double get_real(const void *buf, enum scan_stored stored, size_t n)
{
	const uint8_t *p = (const uint8_t *)buf + n * scan_stored_size(stored);
	if (stored == SCAN_STORED_F32) {
		float f;
		memcpy(&f, p, sizeof(f));
		return f;
	}
	if (stored == SCAN_STORED_F64) {
		double d;
		memcpy(&d, p, sizeof(d));
		return d;
	}
	return (double)get_int(buf, stored, n);
}

/* The rescale of slice k (r has count entries: 1, or one per slice). */
static struct scan_rescale rescale_of(const struct scan_rescale *r, uint32_t count, uint32_t k)
{
	if (count == 0)
		return (struct scan_rescale){ 1, 0 };
	return r[count == 1 ? 0 : k];
}

static int check_rescale(const struct scan_rescale *r, uint32_t count, uint32_t slices, const char *path, char *err,
			 size_t err_size)
{
	if (count > 1 && count != slices)
		return scan_fail(err, err_size, -EINVAL, path, "%u rescales for %u slices", count, slices);
	for (uint32_t n = 0; n < count; n++)
		if (!isfinite(r[n].slope) || r[n].slope == 0 || !isfinite(r[n].inter))
			return scan_fail(err, err_size, -EINVAL, path, "a rescale slope of %g and intercept of %g",
					 r[n].slope, r[n].inter);
	return 0;
}

/* What the rescale is: every slope 1 and intercept 0 (identity), every
 * slope 1 and intercept whole and small (shift), or anything else. */
enum rescale_kind { RESCALE_IDENTITY, RESCALE_SHIFT, RESCALE_REAL };

static enum rescale_kind rescale_kind(const struct scan_rescale *r, uint32_t count)
{
	enum rescale_kind kind = RESCALE_IDENTITY;
	for (uint32_t n = 0; n < count; n++) {
		if (r[n].slope != 1 || r[n].inter != floor(r[n].inter) || fabs(r[n].inter) > 65536)
			return RESCALE_REAL;
		if (r[n].inter != 0)
			kind = RESCALE_SHIFT;
	}
	return kind;
}

/* The range of the rescaled values of an integer volume (shift only). */
static void shifted_range(const void *buf, enum scan_stored stored, const struct scan *s, const struct scan_rescale *r,
			  uint32_t count, int64_t *lo, int64_t *hi)
{
	size_t per_slice = (size_t)s->dims[0] * s->dims[1];
	*lo = INT64_MAX;
	*hi = INT64_MIN;
	for (uint32_t k = 0; k < s->dims[2]; k++) {
		int64_t inter = (int64_t)rescale_of(r, count, k).inter, mn = INT64_MAX, mx = INT64_MIN;
		size_t n0 = k * per_slice, n1 = (k + 1) * per_slice;
		/* The 16-bit types of CT (a whole intercept, e.g. -1024) typed;
		 * the rest through get_int(). */
		if (stored == SCAN_STORED_U16 || stored == SCAN_STORED_I16) {
			for (size_t n = n0; n < n1; n++) {
				int64_t v = stored == SCAN_STORED_U16 ? ((const uint16_t *)buf)[n]
								      : ((const int16_t *)buf)[n];
				mn = v < mn ? v : mn;
				mx = v > mx ? v : mx;
			}
		} else {
			for (size_t n = n0; n < n1; n++) {
				int64_t v = get_int(buf, stored, n);
				mn = v < mn ? v : mn;
				mx = v > mx ? v : mx;
			}
		}
		if (n1 > n0) {
			*lo = mn + inter < *lo ? mn + inter : *lo;
			*hi = mx + inter > *hi ? mx + inter : *hi;
		}
	}
}

/* Grows buf to n voxels of out_size bytes when they are wider than in_size
 * (NULL when that fails; buf is then still the caller's). */
static void *grow(void *buf, size_t n, size_t in_size, size_t out_size)
{
	if (out_size <= in_size)
		return buf;
	return realloc(buf, n * out_size);
}

/* Voxel index m of n in the order that converts in place. */
static size_t order(size_t m, size_t n, size_t in_size, size_t out_size)
{
	return out_size > in_size ? n - 1 - m : m;
}

/* In place: int16 = stored + the slice's whole intercept. */
static void to_i16(void *buf, enum scan_stored stored, const struct scan *s, const struct scan_rescale *r,
		   uint32_t count, size_t n)
{
	size_t in = scan_stored_size(stored), per_slice = (size_t)s->dims[0] * s->dims[1];
	for (size_t m = 0; m < n; m++) {
		size_t i = order(m, n, in, 2);
		int16_t v = (int16_t)(get_int(buf, stored, i) +
				      (int64_t)rescale_of(r, count, (uint32_t)(i / per_slice)).inter);
		memcpy((uint8_t *)buf + 2 * i, &v, 2);
	}
}

/* In place: uint16 = stored (a 32-bit integer whose values fit). */
static void to_u16(void *buf, enum scan_stored stored, size_t n)
{
	for (size_t i = 0; i < n; i++) {
		uint16_t v = (uint16_t)get_int(buf, stored, i);
		memcpy((uint8_t *)buf + 2 * i, &v, 2);
	}
}

/* In place: float32 = stored * slope + intercept of the slice. */
static void to_f32(void *buf, enum scan_stored stored, const struct scan *s, const struct scan_rescale *r,
		   uint32_t count, size_t n)
{
	size_t in = scan_stored_size(stored), per_slice = (size_t)s->dims[0] * s->dims[1];
	for (size_t m = 0; m < n; m++) {
		size_t i = order(m, n, in, 4);
		struct scan_rescale rs = rescale_of(r, count, (uint32_t)(i / per_slice));
		float v = (float)(get_real(buf, stored, i) * rs.slope + rs.inter);
		memcpy((uint8_t *)buf + 4 * i, &v, 4);
	}
}

/* In place, backwards: RGBA = RGB and an opaque alpha. */
static void rgb_to_rgba(uint8_t *buf, size_t n)
{
	for (size_t m = 0; m < n; m++) {
		size_t i = n - 1 - m;
		uint8_t rgb[3];
		memcpy(rgb, buf + 3 * i, 3);
		memcpy(buf + 4 * i, rgb, 3);
		buf[4 * i + 3] = 255;
	}
}

/* The result type, as scan_finish() says. */
static enum scan_type result_type(const void *buf, enum scan_stored stored, const struct scan *s,
				  const struct scan_rescale *r, uint32_t count)
{
	if (stored == SCAN_STORED_RGB24 || stored == SCAN_STORED_RGBA32)
		return SCAN_RGBA8;
	enum rescale_kind kind = rescale_kind(r, count);
	if (!is_integer(stored) || kind == RESCALE_REAL)
		return SCAN_F32;
	if (kind == RESCALE_IDENTITY && stored == SCAN_STORED_U8)
		return SCAN_U8;
	if (kind == RESCALE_IDENTITY && stored == SCAN_STORED_U16)
		return SCAN_U16;
	if (kind == RESCALE_IDENTITY && (stored == SCAN_STORED_I16 || stored == SCAN_STORED_I8))
		return SCAN_I16; /* fits whatever the values: no need to look */
	int64_t lo, hi;
	shifted_range(buf, stored, s, r, count, &lo, &hi);
	if (lo >= INT16_MIN && hi <= INT16_MAX)
		return SCAN_I16;
	if (kind == RESCALE_IDENTITY && lo >= 0 && hi <= UINT16_MAX)
		return SCAN_U16;
	return SCAN_F32;
}

/* Converts buf (n voxels) to type in place; the buffer, moved maybe, or
 * NULL when growing it failed (buf then freed). */
static void *convert(void *buf, enum scan_stored stored, enum scan_type type, const struct scan *s,
		     const struct scan_rescale *r, uint32_t count, size_t n)
{
	size_t in = scan_stored_size(stored), out = scan_type_size(type);
	void *p = grow(buf, n, in, out);
	if (!p) {
		free(buf);
		return NULL;
	}
	if (type == SCAN_RGBA8 && stored == SCAN_STORED_RGB24)
		rgb_to_rgba(p, n);
	else if (type == SCAN_I16 && stored != SCAN_STORED_I16)
		to_i16(p, stored, s, r, count, n);
	else if (type == SCAN_I16 && rescale_kind(r, count) != RESCALE_IDENTITY)
		to_i16(p, stored, s, r, count, n);
	else if (type == SCAN_U16 && stored != SCAN_STORED_U16)
		to_u16(p, stored, n);
	else if (type == SCAN_F32 && (stored != SCAN_STORED_F32 || rescale_kind(r, count) != RESCALE_IDENTITY))
		to_f32(p, stored, s, r, count, n);
	if (out < in) {
		void *q = realloc(p, n * out);
		p = q ? q : p;
	}
	return p;
}

int scan_finish(struct scan *s, enum scan_stored stored, void *buf, const struct scan_rescale *r, uint32_t count,
		const char *path, char *err, size_t err_size)
{
	uint64_t voxels;
	int ret = scan_check_dims(path, s->dims, &voxels, err, err_size);
	bool rgb = stored == SCAN_STORED_RGB24 || stored == SCAN_STORED_RGBA32;
	if (ret == 0 && !rgb)
		ret = check_rescale(r, count, s->dims[2], path, err, err_size);
	if (ret != 0) {
		free(buf);
		return ret;
	}
	if (rgb)
		count = 0;
	s->type = result_type(buf, stored, s, r, count);
	s->data = convert(buf, stored, s->type, s, r, count, (size_t)voxels);
	if (!s->data)
		return scan_fail(err, err_size, -ENOMEM, path, "out of memory converting %s voxels",
				 scan_type_name(s->type));
	s->size = (size_t)voxels * scan_type_size(s->type);
	return 0;
}
