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

#include "brightness_report.h"

static const char prog[] = "spindle-bench-brightness";

/* ---- measuring ---- */

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
	char msg[1024] = "";
	if (status == 0 && !report_run(&run, a.shapes, a.check, a.json, msg, sizeof(msg))) {
		fprintf(stderr, "%s: check %s failed: %s\n", prog, check_names[a.check], msg);
		status = 1;
	}
	spindle_layer_destroy(run.layer);
	spindle_disconnect(run.sp);
	free(run.results);
	return status;
}
