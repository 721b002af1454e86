/* spindle-bench-brightness's judgement and output (brightness_report.h):
 * the summary of what it measured, the checks of the brightness models
 * (bench/README.md, "Brightness"), the tables and the JSON object. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "brightness_report.h"

/* Limits of the checks (the acceptance). */
#define EVEN_LIMIT 1.25   /* brightest band or tube from 2 px to r0, over the r0 one */
#define UNIFORM_LIMIT 1.5 /* brightest / dimmest band or tube from 2 px to the rim */
#define EXACT_GLOW 3.0    /* the disk's 2-4 px band over its r0 band, at least */
#define FROM_PX 2.0       /* bands and tubes from here out are judged */

const char *const shape_names[SHAPE_COUNT] = { "disk", "wall", "tubes", "ring", "sphere" };
const char *const check_names[3] = { "exact", "even", "uniform" };

/* ---- the summary and the checks ---- */

struct summary {
	/* Per shape: the brightest band (tubes: tube) from FROM_PX to r0
	 * over the r0 one; 0 when unknown. */
	double peak[SHAPE_COUNT];
	int peak_index[SHAPE_COUNT]; /* band, or index into results for tubes */
	bool has_r0[SHAPE_COUNT];
	/* Over every surface's band and tube from FROM_PX to the rim. */
	double max, min, mean;
	const struct result *max_of, *min_of;
	int max_band, min_band; /* -1 for a tube */
	unsigned values;
};

static bool is_surface(enum shape s)
{
	return s != SHAPE_RING;
}

static void consider(struct summary *s, const struct result *res, int band, double value, double *sum)
{
	if (s->values == 0 || value > s->max) {
		s->max = value;
		s->max_of = res;
		s->max_band = band;
	}
	if (s->values == 0 || value < s->min) {
		s->min = value;
		s->min_of = res;
		s->min_band = band;
	}
	*sum += value;
	s->values++;
}

static void summarise(const struct run *run, struct summary *s)
{
	memset(s, 0, sizeof(*s));
	double r0 = run->dev.r0, sum = 0.0;
	/* The r0 tube: the one whose radius's column holds r0. */
	const struct result *r0_tube = NULL;
	for (size_t i = 0; i < run->count; i++) {
		const struct result *res = &run->results[i];
		if (res->shape == SHAPE_TUBES && res->radius_px == column_centre(r0))
			r0_tube = res;
	}
	for (size_t i = 0; i < run->count; i++) {
		struct result *res = &run->results[i];
		if (res->shape == SHAPE_TUBES) {
			res->relative = r0_tube && r0_tube->prof.value > 0 ? res->prof.value / r0_tube->prof.value : 0;
			s->has_r0[SHAPE_TUBES] = r0_tube && r0_tube->prof.value > 0;
			if (res->radius_px >= FROM_PX && res->radius_px <= column_centre(r0) &&
			    res->relative > s->peak[SHAPE_TUBES]) {
				s->peak[SHAPE_TUBES] = res->relative;
				s->peak_index[SHAPE_TUBES] = (int)i;
			}
			if (res->radius_px >= FROM_PX)
				consider(s, res, -1, res->prof.value, &sum);
			continue;
		}
		const struct light_profile *p = &res->prof;
		s->has_r0[res->shape] = p->r0_band >= 0 && p->band[p->r0_band].value > 0;
		for (unsigned b = 0; b < p->band_count; b++) {
			const struct light_band *band = &p->band[b];
			if (!(band->area > 0.0) || band->lo < FROM_PX)
				continue;
			if (band->lo <= r0 && band->relative > s->peak[res->shape]) {
				s->peak[res->shape] = band->relative;
				s->peak_index[res->shape] = (int)b;
			}
			if (is_surface(res->shape))
				consider(s, res, (int)b, band->value, &sum);
		}
	}
	s->mean = s->values ? sum / s->values : 0.0;
}

static void band_name(char *out, size_t size, const struct light_band *b)
{
	snprintf(out, size, "%g-%g", b->lo, b->hi);
}

static void where(char *out, size_t size, const struct result *res, int band)
{
	char b[32];
	if (!res) {
		snprintf(out, size, "none");
	} else if (band < 0) {
		snprintf(out, size, "tube %.1f px", res->radius_px);
	} else {
		band_name(b, sizeof(b), &res->prof.band[band]);
		snprintf(out, size, "%s %s px", shape_names[res->shape], b);
	}
}

/* Where shape sh's brightest band (or tube) from FROM_PX to r0 is, into
 * out. */
static void peak_where(const struct run *run, const struct summary *s, int sh, char *out, size_t size)
{
	if (sh == SHAPE_TUBES)
		snprintf(out, size, "tube %.1f px", run->results[s->peak_index[sh]].radius_px);
	else
		for (size_t i = 0; i < run->count; i++)
			if (run->results[i].shape == (enum shape)sh)
				where(out, size, &run->results[i], s->peak_index[sh]);
}

/* Appends to msg (size bytes) what the check says; len is what it holds. */
#define SAY(...)                                                                     \
	do {                                                                         \
		if (len < size)                                                      \
			len += (size_t)snprintf(msg + len, size - len, __VA_ARGS__); \
	} while (0)

/* The exact check: the disk glows at the axis. */
static bool check_exact(const struct run *run, char *msg, size_t size)
{
	size_t len = 0;
	const struct result *disk = NULL;
	for (size_t i = 0; i < run->count; i++)
		if (run->results[i].shape == SHAPE_DISK)
			disk = &run->results[i];
	const struct light_band *b = NULL;
	for (unsigned i = 0; disk && i < disk->prof.band_count; i++)
		if (disk->prof.band[i].lo == 2.0)
			b = &disk->prof.band[i];
	if (!b || !(b->relative >= EXACT_GLOW)) {
		SAY("disk: band 2-4 px is %.2fx its r0 band, exact mode gives at least %.1fx", b ? b->relative : 0.0,
		    EXACT_GLOW);
		return false;
	}
	return true;
}

/* The even check: no surface brighter inside r0 than at r0. */
static bool check_even(const struct run *run, const struct summary *s, unsigned shapes, char *msg, size_t size)
{
	size_t len = 0;
	bool ok = true;
	for (int sh = 0; sh < SHAPE_COUNT; sh++) {
		if (!(shapes & (1u << sh)) || !is_surface((enum shape)sh))
			continue;
		if (!s->has_r0[sh]) {
			SAY("%s%s: nothing lit at r0 to compare with", ok ? "" : "; ", shape_names[sh]);
			ok = false;
		} else if (s->peak[sh] > EVEN_LIMIT) {
			char w[64];
			peak_where(run, s, sh, w, sizeof(w));
			SAY("%s%s is %.2fx the r0 %s (at most %.2fx inside r0)", ok ? "" : "; ", w, s->peak[sh],
			    sh == SHAPE_TUBES ? "tube" : "band", EVEN_LIMIT);
			ok = false;
		}
	}
	return ok;
}

/* The uniform check: the spread over all surfaces is small. */
static bool check_uniform(const struct summary *s, char *msg, size_t size)
{
	size_t len = 0;
	double spread = s->min > 0.0 ? s->max / s->min : INFINITY;
	if (s->values == 0 || spread > UNIFORM_LIMIT) {
		char a[64], b[64];
		where(a, sizeof(a), s->max_of, s->max_band);
		where(b, sizeof(b), s->min_of, s->min_band);
		SAY("spread %.2f (brightest %s: %.3g, dimmest %s: %.3g), at most %.2f", spread, a, s->max, b, s->min,
		    UNIFORM_LIMIT);
		return false;
	}
	return true;
}

#undef SAY

/* Writes why the check failed into msg; returns true when it passed. */
static bool judge(const struct run *run, const struct summary *s, enum check c, unsigned shapes, char *msg, size_t size)
{
	msg[0] = '\0';
	if (c == CHECK_EXACT)
		return check_exact(run, msg, size);
	if (c == CHECK_EVEN)
		return check_even(run, s, shapes, msg, size);
	if (c == CHECK_UNIFORM)
		return check_uniform(s, msg, size);
	return true;
}

/* ---- output ---- */

/* The tubes' or the ring's table: a row per radius. */
static void print_radii(const struct run *run, enum shape shape)
{
	const struct light_device *d = &run->dev;
	if (shape == SHAPE_TUBES)
		printf("tubes: vertical cylinders about the axis, rows %u-%u (%.2f px high), each at the "
		       "centre of "
		       "its pixel column\n",
		       d->v0, d->v1 - 1, (d->y_top - d->y_bottom) / d->row);
	else
		printf("ring: horizontal circle, a line strip at the middle of row %u (light per pixel of "
		       "length)\n",
		       d->h / 2);
	printf("  %-18s %12s %12s %12s%s\n", "radius px", "lit voxels", "area px^2", "light/area",
	       shape == SHAPE_TUBES ? " rel. r0 tube" : "");
	for (size_t i = 0; i < run->count; i++) {
		const struct result *res = &run->results[i];
		if (res->shape != shape)
			continue;
		char name[40];
		bool is_r0 = shape == SHAPE_TUBES && res->radius_px == column_centre(d->r0);
		snprintf(name, sizeof(name), "%.1f (%.4g)%s", res->radius_px, res->nominal_px, is_r0 ? " r0" : "");
		printf("  %-18s %12llu %12.1f %12.4f", name, (unsigned long long)res->prof.lit, res->prof.area,
		       res->prof.value);
		if (shape == SHAPE_TUBES)
			printf(" %12.3f", res->relative);
		printf("\n");
	}
	printf("\n");
}

/* A profile's bands: the header and a row per band. */
static void print_bands(const struct light_profile *p)
{
	printf("  %-18s %12s %12s %12s %12s\n", "band px", "lit voxels", "area px^2", "light/area", "rel. r0 band");
	for (unsigned b = 0; b < p->band_count; b++) {
		const struct light_band *band = &p->band[b];
		char name[40];
		band_name(name, sizeof(name), band);
		if ((int)b == p->r0_band)
			strcat(name, " r0");
		if (band->area > 0.0)
			printf("  %-18s %12llu %12.1f %12.4f %12.3f\n", name, (unsigned long long)band->lit, band->area,
			       band->value, band->relative);
		else
			printf("  %-18s %12llu %12s %12s %12s\n", name, (unsigned long long)band->lit, "-", "-", "-");
	}
	printf("\n");
}

/* The last result of shape, or NULL. */
static const struct result *find_result(const struct run *run, enum shape shape)
{
	const struct result *res = NULL;
	for (size_t i = 0; i < run->count; i++)
		if (run->results[i].shape == shape)
			res = &run->results[i];
	return res;
}

static void print_table(const struct run *run, enum shape shape)
{
	const struct light_device *d = &run->dev;
	if (shape == SHAPE_TUBES || shape == SHAPE_RING) {
		print_radii(run, shape);
		return;
	}
	const struct result *res = find_result(run, shape);
	if (!res)
		return;
	switch (shape) {
	case SHAPE_DISK:
		printf("disk: horizontal disk of radius 1 (%.0f px) at the middle of row %u\n", res->radius_px,
		       d->h / 2);
		break;
	case SHAPE_WALL:
		printf("wall: vertical rectangle through the axis at the centre of image %.0f, s from -1 to 1, rows "
		       "%u-%u\n",
		       res->nominal_px, d->v0, d->v1 - 1);
		break;
	case SHAPE_SPHERE:
		printf("sphere: centred on the axis, radius %.1f px\n", res->radius_px);
		break;
	default:
		break;
	}
	print_bands(&res->prof);
}

static void print_summary(const struct run *run, const struct summary *s, unsigned shapes)
{
	printf("summary (r0 = %.2f px; bands and tubes from %g px):\n", run->dev.r0, FROM_PX);
	for (int sh = 0; sh < SHAPE_COUNT; sh++) {
		if (!(shapes & (1u << sh)) || !is_surface((enum shape)sh))
			continue;
		char w[64] = "";
		if (!s->has_r0[sh]) {
			printf("  %-6s brightest from %g px to r0: unknown (nothing lit at r0)\n", shape_names[sh],
			       FROM_PX);
			continue;
		}
		peak_where(run, s, sh, w, sizeof(w));
		printf("  %-6s brightest from %g px to r0: %.2fx the r0 %s (%s)\n", shape_names[sh], FROM_PX,
		       s->peak[sh], sh == SHAPE_TUBES ? "tube" : "band", w);
	}
	char a[64], b[64];
	where(a, sizeof(a), s->max_of, s->max_band);
	where(b, sizeof(b), s->min_of, s->min_band);
	printf("  spread over all shapes, %g px to the rim: %.2f (brightest %s: %.4f, dimmest %s: %.4f)\n", FROM_PX,
	       s->min > 0.0 ? s->max / s->min : INFINITY, a, s->max, b, s->min);
	printf("  mean light per area over those bands and tubes: %.4f voxels/px^2\n", s->mean);
}

static void json_number(double v)
{
	if (isfinite(v))
		printf("%.6g", v);
	else
		printf("null");
}

/* The device's object, its name first. */
static void json_device(const struct light_device *d)
{
	printf("\"device\":{\"width\":%u,\"height\":%u,\"images_per_rev\":%u,\"mirrored\":%s,\"half_height\":", d->w,
	       d->h, d->n, d->mirrored ? "true" : "false");
	json_number(d->half_height);
	printf(",\"r0_px\":");
	json_number(d->r0);
	printf("}");
}

/* The tubes' or the rings' array: an object per radius. */
static void json_radii(const struct run *run, int sh)
{
	printf("\"%s\":[", sh == SHAPE_TUBES ? "tubes" : "rings");
	bool first = true;
	for (size_t i = 0; i < run->count; i++) {
		const struct result *res = &run->results[i];
		if (res->shape != (enum shape)sh)
			continue;
		printf("%s{\"nominal_px\":", first ? "" : ",");
		first = false;
		json_number(res->nominal_px);
		printf(",\"radius_px\":");
		json_number(res->radius_px);
		printf(",\"lit\":%llu,\"area\":", (unsigned long long)res->prof.lit);
		json_number(res->prof.area);
		printf(",\"value\":");
		json_number(res->prof.value);
		printf(",\"relative\":");
		json_number(res->relative);
		printf("}");
	}
	printf("]");
}

/* A profile's numbers and its array of bands. */
static void json_bands(const struct light_profile *p)
{
	printf("\"r0_band\":%d,\"lit\":%llu,\"area\":", p->r0_band, (unsigned long long)p->lit);
	json_number(p->area);
	printf(",\"bands\":[");
	for (unsigned b = 0; b < p->band_count; b++) {
		const struct light_band *band = &p->band[b];
		printf("%s{\"lo\":", b ? "," : "");
		json_number(band->lo);
		printf(",\"hi\":");
		json_number(band->hi);
		printf(",\"lit\":%llu,\"area\":", (unsigned long long)band->lit);
		json_number(band->area);
		printf(",\"value\":");
		json_number(band->value);
		printf(",\"relative\":");
		json_number(band->relative);
		printf("}");
	}
	printf("]");
}

/* Shape sh's object, its name first. */
static void json_shape(const struct run *run, const struct summary *s, int sh, bool first)
{
	printf("%s\"%s\":{", first ? "" : ",", shape_names[sh]);
	if (sh == SHAPE_TUBES || sh == SHAPE_RING) {
		json_radii(run, sh);
	} else {
		const struct result *res = find_result(run, (enum shape)sh);
		if (!res) {
			printf("}");
			return;
		}
		json_bands(&res->prof);
	}
	if (is_surface((enum shape)sh)) {
		printf(",\"peak_to_r0\":");
		json_number(s->has_r0[sh] ? s->peak[sh] : NAN);
	}
	printf("}");
}

/* The check's object, its message escaped. */
static void json_check(int c, bool passed, const char *msg)
{
	printf(",\"check\":{\"mode\":\"%s\",\"passed\":%s,\"message\":\"", check_names[c], passed ? "true" : "false");
	for (const char *p = msg; *p; p++)
		printf(*p == '"' || *p == '\\' ? "\\%c" : "%c", *p);
	printf("\"}");
}

static void print_json(const struct run *run, const struct summary *s, unsigned shapes, int c, bool passed,
		       const char *msg)
{
	printf("{");
	json_device(&run->dev);
	printf(",\"shapes\":{");
	bool first_shape = true;
	for (int sh = 0; sh < SHAPE_COUNT; sh++) {
		if (!(shapes & (1u << sh)))
			continue;
		json_shape(run, s, sh, first_shape);
		first_shape = false;
	}
	printf("},\"spread\":");
	json_number(s->values && s->min > 0.0 ? s->max / s->min : NAN);
	printf(",\"mean\":");
	json_number(s->values ? s->mean : NAN);
	if (c != CHECK_NONE)
		json_check(c, passed, msg);
	printf("}\n");
}

bool report_run(const struct run *run, unsigned shapes, int check, bool json, char *msg, size_t size)
{
	const struct light_device *d = &run->dev;
	struct summary s;
	summarise(run, &s);
	bool passed = check == CHECK_NONE || judge(run, &s, (enum check)check, shapes, msg, size);
	if (json) {
		print_json(run, &s, shapes, check, passed, msg);
		return passed;
	}
	printf("%ux%u, N = %u%s, h = %g, r0 = %.2f px; light/area: lit voxels (any channel, every "
	       "image of the capture) per px^2 of surface\n\n",
	       d->w, d->h, d->n, d->mirrored ? " mirrored" : "", d->half_height, d->r0);
	for (int sh = 0; sh < SHAPE_COUNT; sh++)
		if (shapes & (1u << sh))
			print_table(run, (enum shape)sh);
	print_summary(run, &s, shapes);
	if (check != CHECK_NONE)
		printf("check %s: %s\n", check_names[check], passed ? "passed" : "FAILED");
	return passed;
}
