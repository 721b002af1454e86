/* spindle-bench-brightness: light per unit area against the distance from
 * the axis, through a running spindled (issue "Even brightness";
 * bench/README.md, "Brightness").
 *
 * For each shape: show it alone as a white layer, commit and wait until it
 * is shown, capture the next volume shown, remove it, and profile the
 * capture (light_profile.h): lit voxels per px^2 of the shape's surface in
 * radial bands [0,1), [1,2), [2,4), ... pixels, and relative to the band
 * holding r0 = N / (2 pi). Prints a table per shape and a summary, or one
 * JSON object (--json); --check MODE tells whether the profile is what the
 * daemon's brightness model MODE must give.
 *
 *   spindle-bench-brightness [--socket PATH] [--shapes LIST] [--json] [--check exact|even|uniform]
 *
 * Exit: 0 done (and the check passed), 1 failed or the check failed, 2
 * usage, 3 no daemon. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include <spindle/spindle.h>

#include "brightness_shapes.h"
#include "light_profile.h"

static const char prog[] = "spindle-bench-brightness";

/* Limits of the checks (the acceptance). */
#define EVEN_LIMIT 1.25   /* brightest band or tube from 2 px to r0, over the r0 one */
#define UNIFORM_LIMIT 1.5 /* brightest / dimmest band or tube from 2 px to the rim */
#define EXACT_GLOW 3.0    /* the disk's 2-4 px band over its r0 band, at least */
#define FROM_PX 2.0       /* bands and tubes from here out are judged */

enum shape { SHAPE_DISK, SHAPE_WALL, SHAPE_TUBES, SHAPE_RING, SHAPE_SPHERE, SHAPE_COUNT };

static const char *const shape_names[SHAPE_COUNT] = { "disk", "wall", "tubes", "ring", "sphere" };
/* The default: the surfaces the checks are written for. `all` adds the
 * extras: the ring (a line: its value is light per pixel of length, left
 * out of the checks) and the sphere (a surface: checked like the others). */
#define DEFAULT_SHAPES ((1u << SHAPE_DISK) | (1u << SHAPE_WALL) | (1u << SHAPE_TUBES))
#define ALL_SHAPES ((1u << SHAPE_COUNT) - 1)

enum check { CHECK_NONE = -1, CHECK_EXACT, CHECK_EVEN, CHECK_UNIFORM };
static const char *const check_names[] = { "exact", "even", "uniform" };

/* ---- measuring ---- */

struct result {
	enum shape shape;
	double nominal_px, radius_px; /* tubes, ring, sphere: asked for and drawn */
	struct light_shape ls;
	struct light_profile prof;
	double relative; /* tubes: value / the r0 tube's value (0: unknown) */
};

struct run {
	struct spindle *sp;
	struct spindle_layer *layer;
	struct light_device dev;
	struct result *results;
	size_t count, cap;
};

static void report(struct spindle *sp, const char *what, int err)
{
	const char *why = sp ? spindle_get_error(sp) : NULL;
	fprintf(stderr, "%s: %s: %s\n", prog, what, why ? why : strerror(err));
}

/* Draws the mesh's vertices of buf in white as list's one draw, makes
 * list the layer's and commits it, until it is shown. 0 or -errno. */
static int show_list(struct run *run, struct spindle_list *list, struct spindle_buffer *buf, const struct vbuf *m,
		     enum spindle_mode mode)
{
	int r = spindle_list_set_color(list, 255, 255, 255, 255);
	if (r == 0)
		r = spindle_list_draw(list, mode, buf, 0, m->count, 0);
	if (r == 0)
		r = spindle_layer_set_list(run->layer, list);
	if (r == 0)
		r = spindle_commit_and_wait(run->sp, NULL);
	return r;
}

/* Captures the next volume shown into fd and size. 0 or -errno
 * (reported). */
static int capture(struct spindle *sp, int *fd, size_t *size)
{
	int r = spindle_capture(sp, fd, size);
	if (r == -EACCES)
		fprintf(stderr,
			"%s: capture refused: only root, the daemon's user and members of its admin group "
			"may capture\n",
			prog);
	else if (r < 0)
		report(sp, "capture", -r);
	return r;
}

/* Takes the shape off the layer and commits. 0 or -errno (reported). */
static int remove_shape(struct run *run)
{
	int r = spindle_layer_set_list(run->layer, NULL);
	if (r == 0)
		r = spindle_commit(run->sp);
	if (r < 0)
		report(run->sp, "removing a shape", -r);
	return r;
}

/* Maps the capture (fd, size bytes) and profiles it as ls. 0 or -errno
 * (reported). */
static int profile_capture(int fd, size_t size, const struct light_shape *ls, struct light_profile *prof)
{
	void *data = size ? mmap(NULL, size, PROT_READ, MAP_PRIVATE, fd, 0) : MAP_FAILED;
	if (data == MAP_FAILED) {
		report(NULL, "mapping the capture", size ? errno : EINVAL);
		return -EINVAL;
	}
	int r = light_profile_compute(data, size, ls, prof);
	if (r < 0)
		fprintf(stderr, "%s: the capture is no valid .svol file\n", prog);
	munmap(data, size);
	return r;
}

/* Shows the mesh alone (white), captures the next volume shown, removes
 * it and profiles the capture as ls. 0 or -errno (reported). */
static int measure(struct run *run, const struct vbuf *m, enum spindle_mode mode, const struct light_shape *ls,
		   struct light_profile *prof)
{
	struct spindle *sp = run->sp;
	if (m->oom || m->count == 0) {
		report(NULL, "building a shape", ENOMEM);
		return -ENOMEM;
	}
	int fd = -1;
	size_t size = 0;
	struct spindle_buffer *buf = spindle_buffer_create(sp, m->xyz, m->count * 3 * sizeof(float));
	struct spindle_list *list = buf ? spindle_list_create(sp) : NULL;
	int r = list ? 0 : -errno;
	if (r == 0)
		r = show_list(run, list, buf, m, mode);
	if (r < 0)
		report(sp, "showing a shape", -r);
	else
		r = capture(sp, &fd, &size);
	if (r == 0)
		r = remove_shape(run);
	if (r == 0)
		r = profile_capture(fd, size, ls, prof);
	if (fd >= 0)
		close(fd);
	spindle_list_destroy(list);
	spindle_buffer_destroy(buf);
	return r;
}

static struct result *add_result(struct run *run)
{
	if (run->count == run->cap) {
		size_t cap = run->cap ? 2 * run->cap : 16;
		struct result *r = realloc(run->results, cap * sizeof(*r));
		if (!r)
			return NULL;
		run->results = r;
		run->cap = cap;
	}
	struct result *res = &run->results[run->count++];
	memset(res, 0, sizeof(*res));
	return res;
}

/* Radius at the centre of the pixel column that holds r_px: a tube there
 * lights one column a row on each side of the axis, never two. */
static double column_centre(double r_px)
{
	return floor(r_px) + 0.5;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return x < y ? -1 : x > y;
}

/* The tubes' radii: 2.5, 4, 6, 10, 16, r0, 2 r0, 4 r0, ... below the rim,
 * sorted, each moved to its column's centre. */
static size_t tube_radii(const struct light_device *d, double nominal[], size_t max)
{
	static const double fixed[] = { 2.5, 4, 6, 10, 16 };
	size_t n = 0;
	for (size_t i = 0; i < sizeof(fixed) / sizeof(fixed[0]) && n < max; i++)
		if (column_centre(fixed[i]) < d->w / 2.0)
			nominal[n++] = fixed[i];
	for (double r = d->r0; column_centre(r) < d->w / 2.0 && n < max; r *= 2.0)
		nominal[n++] = r;
	qsort(nominal, n, sizeof(double), cmp_double);
	size_t out = 0;
	for (size_t i = 0; i < n; i++)
		if (out == 0 || column_centre(nominal[i]) != column_centre(nominal[out - 1]))
			nominal[out++] = nominal[i];
	return out;
}

/* Measures the tubes, one at a time, a result each. */
static int run_tubes(struct run *run)
{
	const struct light_device *d = &run->dev;
	struct vbuf m = { 0 };
	int r = 0;
	double nominal[32];
	size_t n = tube_radii(d, nominal, 32);
	for (size_t i = 0; i < n && r == 0; i++) {
		struct result *res = add_result(run);
		if (!res)
			return -ENOMEM;
		res->shape = SHAPE_TUBES;
		res->nominal_px = nominal[i];
		res->radius_px = column_centre(nominal[i]);
		res->ls = (struct light_shape){ LIGHT_SHAPE_TUBE, res->radius_px * d->px, d->y_top - d->y_bottom };
		m.count = 0;
		light_shape_tube(&m, d, res->radius_px);
		r = measure(run, &m, SPINDLE_TRIANGLES, &res->ls, &res->prof);
	}
	vbuf_free(&m);
	return r;
}

/* Builds the mesh of shape (not the tubes) into m and fills in what res
 * says of it. Returns the mode to draw the mesh in. */
static enum spindle_mode build_shape(const struct light_device *d, enum shape shape, struct result *res, struct vbuf *m)
{
	enum spindle_mode mode = SPINDLE_TRIANGLES;
	switch (shape) {
	case SHAPE_DISK:
		res->ls = (struct light_shape){ LIGHT_SHAPE_DISK, 1.0, 0.0 };
		res->radius_px = d->w / 2.0;
		light_shape_disk(m, d);
		break;
	case SHAPE_WALL: {
		/* The centre of image j: it lies in that one slice. */
		uint32_t j = d->n / 8 ? d->n / 8 : 1;
		res->ls = (struct light_shape){ LIGHT_SHAPE_WALL, 1.0, d->y_top - d->y_bottom };
		res->radius_px = d->w / 2.0;
		res->nominal_px = j; /* the image */
		light_shape_wall(m, d, 2.0 * M_PI * j / d->n);
		break;
	}
	case SHAPE_RING:
		res->nominal_px = 0.5 * d->w / 2.0;
		res->radius_px = column_centre(res->nominal_px);
		res->ls = (struct light_shape){ LIGHT_SHAPE_RING, res->radius_px * d->px, 0.0 };
		light_shape_ring(m, d, res->radius_px);
		mode = SPINDLE_LINE_STRIP;
		break;
	case SHAPE_SPHERE: {
		double radius = 0.5 < 0.9 * d->half_height ? 0.5 : 0.9 * d->half_height;
		res->nominal_px = radius * d->w / 2.0;
		res->radius_px = column_centre(res->nominal_px);
		res->ls = (struct light_shape){ LIGHT_SHAPE_SPHERE, res->radius_px * d->px, 0.0 };
		light_shape_sphere(m, d, res->radius_px);
		break;
	}
	default:
		break;
	}
	return mode;
}

static int run_shape(struct run *run, enum shape shape)
{
	if (shape == SHAPE_TUBES)
		return run_tubes(run);
	struct vbuf m = { 0 };
	struct result *res = add_result(run);
	if (!res)
		return -ENOMEM;
	res->shape = shape;
	enum spindle_mode mode = build_shape(&run->dev, shape, res, &m);
	int r = measure(run, &m, mode, &res->ls, &res->prof);
	vbuf_free(&m);
	return r;
}

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
static bool check(const struct run *run, const struct summary *s, enum check c, unsigned shapes, char *msg, size_t size)
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

/* ---- main ---- */

static void usage(FILE *f)
{
	fprintf(f,
		"usage: %s [--socket PATH] [--shapes LIST] [--json] [--check exact|even|uniform]\n"
		"  --shapes LIST   comma separated: disk, wall, tubes, ring, sphere, all\n"
		"                  (default disk,wall,tubes)\n"
		"  --json          one JSON object instead of the tables\n"
		"  --check MODE    exit 1 unless the profile is what brightness MODE gives\n"
		"Exit: 0 done, 1 failed or the check failed, 2 usage, 3 no daemon.\n",
		prog);
}

static int parse_shapes(const char *list, unsigned *out)
{
	char *copy = strdup(list), *save = NULL;
	if (!copy)
		return -ENOMEM;
	unsigned mask = 0;
	int r = 0;
	for (char *t = strtok_r(copy, ",", &save); t && r == 0; t = strtok_r(NULL, ",", &save)) {
		if (!strcmp(t, "all")) {
			mask |= ALL_SHAPES;
			continue;
		}
		int i = 0;
		while (i < SHAPE_COUNT && strcmp(t, shape_names[i]) != 0)
			i++;
		if (i == SHAPE_COUNT)
			r = -EINVAL;
		else
			mask |= 1u << i;
	}
	free(copy);
	*out = mask;
	return r < 0 ? r : mask ? 0 : -EINVAL;
}

/* The command line. */
struct args {
	const char *socket;
	unsigned shapes;
	bool json;
	int check; /* enum check */
};

/* Whether the shapes are what the check needs: -1 when they are, else
 * the exit status 2 (reported). */
static int check_needs(const struct args *a)
{
	if (a->check == CHECK_EXACT && !(a->shapes & (1u << SHAPE_DISK))) {
		fprintf(stderr, "%s: --check exact needs the disk among the shapes\n", prog);
		return 2;
	}
	if (a->check == CHECK_UNIFORM && !(a->shapes & ALL_SHAPES & ~(1u << SHAPE_RING))) {
		fprintf(stderr, "%s: --check uniform needs a surface among the shapes\n", prog);
		return 2;
	}
	return -1;
}

/* Returns -1 to run, or the exit status (0 for --help). */
static int parse_args(int argc, char **argv, struct args *a)
{
	static const struct option longopts[] = {
		{ "socket", required_argument, NULL, 's' }, { "shapes", required_argument, NULL, 'S' },
		{ "json", no_argument, NULL, 'j' },         { "check", required_argument, NULL, 'c' },
		{ "help", no_argument, NULL, 'h' },         { NULL, 0, NULL, 0 },
	};
	*a = (struct args){ .shapes = DEFAULT_SHAPES, .check = CHECK_NONE };
	int opt;
	while ((opt = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
		if (opt == 's') {
			a->socket = optarg;
		} else if (opt == 'S') {
			if (parse_shapes(optarg, &a->shapes) < 0) {
				fprintf(stderr, "%s: --shapes: unknown shape in '%s'\n", prog, optarg);
				return 2;
			}
		} else if (opt == 'j') {
			a->json = true;
		} else if (opt == 'c') {
			for (a->check = 2; a->check >= 0 && strcmp(optarg, check_names[a->check]); a->check--)
				;
			if (a->check < 0) {
				fprintf(stderr, "%s: --check: one of exact, even, uniform\n", prog);
				return 2;
			}
		} else {
			usage(opt == 'h' ? stdout : stderr);
			return opt == 'h' ? 0 : 2;
		}
	}
	if (optind < argc)
		return usage(stderr), 2;
	return check_needs(a);
}

/* Prints what was measured and checks it; 0, or 1 when the check failed. */
static int report_run(const struct run *run, const struct args *a)
{
	const struct light_device *d = &run->dev;
	struct summary s;
	char msg[1024] = "";
	summarise(run, &s);
	bool passed = a->check == CHECK_NONE || check(run, &s, (enum check)a->check, a->shapes, msg, sizeof(msg));
	if (a->json) {
		print_json(run, &s, a->shapes, a->check, passed, msg);
	} else {
		printf("%ux%u, N = %u%s, h = %g, r0 = %.2f px; light/area: lit voxels (any channel, every "
		       "image of the capture) per px^2 of surface\n\n",
		       d->w, d->h, d->n, d->mirrored ? " mirrored" : "", d->half_height, d->r0);
		for (int sh = 0; sh < SHAPE_COUNT; sh++)
			if (a->shapes & (1u << sh))
				print_table(run, (enum shape)sh);
		print_summary(run, &s, a->shapes);
		if (a->check != CHECK_NONE)
			printf("check %s: %s\n", check_names[a->check], passed ? "passed" : "FAILED");
	}
	if (passed)
		return 0;
	fprintf(stderr, "%s: check %s failed: %s\n", prog, check_names[a->check], msg);
	return 1;
}

int main(int argc, char **argv)
{
	struct args a;
	int status = parse_args(argc, argv, &a);
	if (status >= 0)
		return status;
	struct run run = { 0 };
	run.sp = spindle_connect(a.socket);
	if (!run.sp) {
		const char *env = getenv("SPINDLE_SOCKET");
		fprintf(stderr, "%s: cannot connect to spindled at %s: %s\n", prog,
			a.socket      ? a.socket
			: env && *env ? env
				      : SPINDLE_DEFAULT_SOCKET,
			errno == EPROTO ? "no common protocol version" : strerror(errno));
		return 3;
	}
	light_shape_device(&run.dev, spindle_get_device_info(run.sp));
	status = 0;
	run.layer = spindle_layer_create(run.sp);
	if (!run.layer) {
		report(run.sp, "creating a layer", errno);
		status = 1;
	}
	for (int sh = 0; sh < SHAPE_COUNT && status == 0; sh++)
		if (a.shapes & (1u << sh) && run_shape(&run, (enum shape)sh) < 0)
			status = 1;
	if (status == 0)
		status = report_run(&run, &a);
	spindle_layer_destroy(run.layer);
	spindle_disconnect(run.sp);
	free(run.results);
	return status;
}
