/* spindlectl show of a scan (spindlectl(1), docs/volumes.md "spindlectl
 * show of a scan"): a NIfTI file, a DICOM directory or a raw file read by
 * the sandboxed scan loader (scan_loader.h), laid out with superior up
 * (scan_display.h), fitted to the display and drawn as a volume (protocol
 * 6) through a window. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "ctl.h"
#include "scan_display.h"
#include "scan_loader.h"

/* Windows in Hounsfield units (centre, width), the conventional ones; mri
 * is taken from the data. */
static const struct preset {
	const char *name;
	double center, width;
	bool ct;
} presets[] = {
	{ "ct-bone", 400, 1800, true },
	{ "ct-soft", 40, 400, true },
	{ "ct-lung", -600, 1500, true },
	{ "mri", 0, 0, false },
};

#define PRESET_NAMES "ct-bone, ct-soft, ct-lung, mri"
/* The default threshold of CT data: air (-1000 HU) stays dark whatever
 * the window (the lung window's low end is -1350). */
#define CT_AIR_THRESHOLD -950.0

static const struct preset *find_preset(const char *name)
{
	for (size_t n = 0; n < sizeof(presets) / sizeof(presets[0]); n++)
		if (!strcmp(presets[n].name, name))
			return &presets[n];
	return NULL;
}

/* ---- the options ---- */

static bool parse_double(const char *s, char **end, double *out)
{
	errno = 0;
	*out = strtod(s, end);
	return *end != s && errno == 0 && isfinite(*out);
}

static int parse_window(const char *s, struct ctl_scan_args *o)
{
	char *end;
	if (!parse_double(s, &end, &o->window_center) || *end != '/' ||
	    !parse_double(end + 1, &end, &o->window_width) || *end || !(o->window_width > 0))
		return ctl_usage_error("bad window '%s' (want CENTRE/WIDTH, the width above 0)", s);
	o->has_window = true;
	return -1;
}

static int parse_dims(const char *s, struct ctl_scan_args *o)
{
	const char *p = s;
	for (int a = 0; a < 3; a++) {
		char *end;
		errno = 0;
		unsigned long v = *p >= '0' && *p <= '9' ? strtoul(p, &end, 10) : 0;
		if (errno || v < 1 || v > SCAN_MAX_DIM || *end != (a < 2 ? 'x' : '\0'))
			return ctl_usage_error("bad dims '%s' (want XxYxZ, each 1 to 4096)", s);
		o->raw.dims[a] = (uint32_t)v;
		p = end + 1;
	}
	o->has_dims = true;
	return -1;
}

static int parse_type(const char *s, struct ctl_scan_args *o)
{
	static const struct {
		const char *name;
		enum scan_type type;
	} types[] = { { "uint8", SCAN_U8 },
		      { "uint16", SCAN_U16 },
		      { "int16", SCAN_I16 },
		      { "float32", SCAN_F32 },
		      { "rgba8", SCAN_RGBA8 } };
	for (size_t n = 0; n < sizeof(types) / sizeof(types[0]); n++)
		if (!strcmp(types[n].name, s)) {
			o->raw.type = types[n].type;
			o->has_type = true;
			return -1;
		}
	return ctl_usage_error("bad type '%s' (one of: uint8, uint16, int16, float32, rgba8)", s);
}

/* SX,SY,SZ, or one value for all three. */
static int parse_spacing(const char *s, struct ctl_scan_args *o)
{
	const char *p = s;
	char *end = (char *)s;
	int n = 0;
	while (n < 3 && parse_double(p, &end, &o->raw.spacing[n]) && o->raw.spacing[n] > 0) {
		n++;
		if (*end != ',')
			break;
		p = end + 1;
	}
	if (*end || (n != 1 && n != 3) || s[strlen(s) - 1] == ',')
		return ctl_usage_error("bad spacing '%s' (want SX,SY,SZ in mm, each above 0)", s);
	if (n == 1)
		o->raw.spacing[1] = o->raw.spacing[2] = o->raw.spacing[0];
	o->has_spacing = true;
	return -1;
}

static int parse_offset(const char *s, struct ctl_scan_args *o)
{
	char *end = (char *)s;
	errno = 0;
	if (*s >= '0' && *s <= '9')
		o->raw.offset = strtoull(s, &end, 10);
	if (errno || end == s || *end)
		return ctl_usage_error("bad offset '%s' (want a byte count)", s);
	o->has_offset = true;
	return -1;
}

int ctl_scan_option(int opt, const char *arg, struct ctl_args *a)
{
	struct ctl_scan_args *o = &a->scan;
	char *end;
	switch (opt) {
	case CTL_OPT_WINDOW:
		return parse_window(arg, o);
	case CTL_OPT_PRESET:
		o->preset = arg;
		return find_preset(arg) ? -1 : ctl_usage_error("unknown preset '%s' (one of: " PRESET_NAMES ")", arg);
	case CTL_OPT_THRESHOLD:
		o->has_threshold = true;
		return parse_double(arg, &end, &o->threshold) && !*end
			       ? -1
			       : ctl_usage_error("bad threshold '%s'", arg);
	case CTL_OPT_SAMPLING:
		o->has_sampling = true;
		o->nearest = !strcmp(arg, "nearest");
		return o->nearest || !strcmp(arg, "trilinear")
			       ? -1
			       : ctl_usage_error("bad sampling '%s' (nearest or trilinear)", arg);
	case CTL_OPT_DIMS:
		return parse_dims(arg, o);
	case CTL_OPT_TYPE:
		return parse_type(arg, o);
	case CTL_OPT_SPACING:
		return parse_spacing(arg, o);
	case CTL_OPT_OFFSET:
		return parse_offset(arg, o);
	case CTL_OPT_BIG_ENDIAN:
		o->raw.big_endian = true;
		return -1;
	}
	return ctl_usage_error("%s", "unknown scan option");
}

static bool raw_given(const struct ctl_scan_args *o)
{
	return o->has_dims || o->has_type || o->has_spacing || o->has_offset || o->raw.big_endian;
}

bool ctl_scan_options_given(const struct ctl_args *a)
{
	const struct ctl_scan_args *o = &a->scan;
	return o->has_window || o->preset || o->has_threshold || o->has_sampling || raw_given(o);
}

static bool ends_with(const char *s, const char *suffix)
{
	size_t n = strlen(s), m = strlen(suffix);
	return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

bool ctl_is_scan(const struct ctl_args *a)
{
	struct stat st;
	const char *path = a->operand[0];
	return raw_given(&a->scan) || ends_with(path, ".nii") || ends_with(path, ".nii.gz") ||
	       (stat(path, &st) == 0 && S_ISDIR(st.st_mode));
}

/* The combinations getopt cannot see. -1 to go on, else CTL_USAGE. */
static int check_usage(const struct ctl_args *a)
{
	const struct ctl_scan_args *o = &a->scan;
	if (a->no_fit)
		return ctl_usage_error("%s", "--no-fit goes with models: a scan is always fitted to the display");
	if (raw_given(o) && !(o->has_dims && o->has_type && o->has_spacing))
		return ctl_usage_error("%s", "a raw file needs --dims, --type and --spacing (--offset and "
					     "--big-endian are optional)");
	if (o->has_window && o->preset)
		return ctl_usage_error("%s", "--window and --preset: give one");
	return -1;
}

/* ---- the window ---- */

struct shown_window {
	double center, width, threshold;
	const char *how; /* the preset's name, or "--window" */
};

/* A window from the 1st to the 99th percentile of the non-zero samples
 * (a constant scan: from 0 to its value). */
static void data_window(const struct scan_stats *st, struct shown_window *w)
{
	double lo = st->p1, hi = st->p99;
	if (st->nonzero == 0) {
		lo = 0;
		hi = 1;
	} else if (!(hi > lo)) {
		lo = hi > 0 ? 0 : hi - 1;
	}
	w->center = 0.5 * (lo + hi);
	w->width = hi - lo;
}

static int choose_window(const struct ctl_args *a, const struct scan_shown *s, struct shown_window *w)
{
	const struct ctl_scan_args *o = &a->scan;
	struct scan_stats st;
	int ret = scan_stats_of(s->type, s->data, s->size / scan_type_size(s->type), &st);
	if (ret < 0)
		return ret;
	const struct preset *p = o->preset ? find_preset(o->preset) : find_preset(st.looks_like_ct ? "ct-soft" : "mri");
	if (o->has_window) {
		w->center = o->window_center;
		w->width = o->window_width;
		w->how = "--window";
	} else if (p->ct) {
		w->center = p->center;
		w->width = p->width;
		w->how = p->name;
	} else {
		data_window(&st, w);
		w->how = "mri, the 1st to 99th percentile";
	}
	w->threshold = w->center - 0.5 * w->width;
	if ((p->ct || st.looks_like_ct) && !o->has_window && w->threshold < CT_AIR_THRESHOLD)
		w->threshold = CT_AIR_THRESHOLD;
	if (o->has_threshold)
		w->threshold = o->threshold;
	return 0;
}

/* One line on what is shown. */
static void describe(const struct ctl_args *a, const struct scan_shown *s, const struct shown_window *w)
{
	const char *sampling = a->scan.nearest ? "nearest" : "trilinear";
	printf("%s: %s; ", a->operand[0], s->what);
	if (s->type == SCAN_RGBA8)
		printf("its own colours, alpha threshold %g", w->threshold);
	else
		printf("window %g/%g (%s), threshold %g", w->center, w->width, w->how, w->threshold);
	printf(", %s sampling", sampling);
	if (s->layout.oblique_deg >= 0.5)
		printf("; %.0f degrees oblique, shown straight", s->layout.oblique_deg);
	printf("\n");
}

/* ---- showing it ---- */

static enum spindle_volume_type volume_type(enum scan_type t)
{
	switch (t) {
	case SCAN_U8:
		return SPINDLE_VOLUME_U8;
	case SCAN_U16:
		return SPINDLE_VOLUME_U16;
	case SCAN_I16:
		return SPINDLE_VOLUME_I16;
	case SCAN_F32:
		return SPINDLE_VOLUME_F32;
	case SCAN_RGBA8:
		break;
	}
	return SPINDLE_VOLUME_RGBA8;
}

/* The volume from the sealed memfd (the daemon copies it), placed by the
 * fit and drawn through the window by one list on one layer. */
static int draw_scan(struct spindle *sp, const struct ctl_args *a, const struct scan_shown *s,
		     const struct shown_window *w, struct spindle_volume **vol, struct spindle_list **list,
		     struct spindle_layer **layer)
{
	static const uint8_t white[3] = { 255, 255, 255 };
	const uint8_t *rgb = a->has_color ? a->color : white;
	float fit[16], spacing[3];
	for (int n = 0; n < 3; n++)
		spacing[n] = (float)s->layout.spacing[n];
	scan_layout_fit(&s->layout, spindle_get_device_info(sp)->half_height, CTL_FIT_MARGIN, fit);

	struct spindle_buffer *buf = spindle_buffer_create_from_fd(sp, s->fd, s->size);
	*vol = buf ? spindle_volume_create(sp, buf, 0, volume_type(s->type), s->layout.dims, spacing) : NULL;
	spindle_buffer_destroy(buf);
	*list = spindle_list_create(sp);
	*layer = spindle_layer_create(sp);
	if (!*vol || !*list || !*layer)
		return -errno;
	int ret = spindle_list_set_transform(*list, fit);
	if (ret == 0)
		ret = spindle_list_set_color(*list, rgb[0], rgb[1], rgb[2], 255);
	if (ret == 0)
		ret = spindle_list_draw_volume(*list, *vol, a->scan.nearest ? SPINDLE_NEAREST : SPINDLE_TRILINEAR,
					       (float)w->threshold, (float)w->center, (float)w->width);
	if (ret == 0)
		ret = spindle_layer_set_list(*layer, *list);
	return ret;
}

/* Shows s and holds it; s is freed once the daemon has its copy (a
 * roundtrip after create_volume), so that its samples are not held twice
 * while the scan is on the display. */
static int show(const struct ctl_args *a, struct scan_shown *s, const struct shown_window *w)
{
	struct spindle_volume *vol = NULL;
	struct spindle_list *list = NULL;
	struct spindle_layer *layer = NULL;
	struct spindle *sp = ctl_connect(a);
	if (!sp)
		return CTL_CONNECT;
	int status = CTL_FAILED;
	if (spindle_get_version(sp) < 6) {
		fprintf(stderr, "spindlectl: %s: the daemon speaks protocol %u; volumes need 6\n", a->operand[0],
			spindle_get_version(sp));
		goto out;
	}
	uint64_t bytes = s->size;
	int ret = draw_scan(sp, a, s, w, &vol, &list, &layer);
	if (ret == 0)
		ret = spindle_roundtrip(sp);
	scan_shown_free(s);
	if (ret < 0)
		ctl_report_failure(sp, "show", ret);
	else
		status = ctl_commit_and_hold(sp, "scan");
	if (spindle_get_error_code(sp) == SPINDLE_ERROR_QUOTA) {
		/* over max-buffer-bytes or memory-budget: said above, in the daemon's words */
		fprintf(stderr, "spindlectl: %s: the daemon refused the scan's %llu bytes of samples\n", a->operand[0],
			(unsigned long long)bytes);
		status = CTL_REFUSED;
	}
out:
	if (layer)
		spindle_layer_destroy(layer);
	if (list)
		spindle_list_destroy(list);
	if (vol)
		spindle_volume_destroy(vol);
	spindle_disconnect(sp);
	return status;
}

int cmd_show_scan(const struct ctl_args *a)
{
	struct scan_shown s;
	struct shown_window w = { 0 };
	char err[1400];
	int status = check_usage(a);
	if (status >= 0)
		return status;
	scan_load_set_progress(stderr); /* a large scan takes seconds */
	int ret = scan_load(a->operand[0], a->scan.has_dims ? &a->scan.raw : NULL, &s, err, sizeof(err));
	if (ret < 0) {
		fprintf(stderr, "spindlectl: %s\n", err);
		return CTL_INPUT;
	}
	if (s.type == SCAN_RGBA8) {
		if (a->scan.has_window || a->scan.preset)
			fprintf(stderr, "spindlectl: %s: an RGBA8 scan shows its own colours: no window\n",
				a->operand[0]);
		w = (struct shown_window){ 127.5, 255, a->scan.has_threshold ? a->scan.threshold : 1, "" };
	} else if ((ret = choose_window(a, &s, &w)) < 0) {
		fprintf(stderr, "spindlectl: %s: %s\n", a->operand[0], strerror(-ret));
		scan_shown_free(&s);
		return CTL_FAILED;
	}
	describe(a, &s, &w);
	fflush(stdout);
	status = show(a, &s, &w);
	scan_shown_free(&s);
	return status;
}
