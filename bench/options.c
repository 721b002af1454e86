#include "options.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry.h"

#ifndef BENCH_DATA_DIR
#define BENCH_DATA_DIR "tests/data"
#endif

static void usage(FILE *f)
{
	fprintf(f,
		"usage: spindle-bench [options]\n"
		"  --scene NAME[,NAME]  scenes or groups (S1, ...) to run, repeatable (default all)\n"
		"  --list               list the scenes and exit\n"
		"  --profile NAME       device profile (default perspecta)\n"
		"  --variants LIST      renderer variants, comma separated (default cpu,%s):\n"
		"                       cpu[-<N>t][-auto|scalar|sse2|avx2|avx512], egl[-naive],\n"
		"                       osmesa[-naive]; +even or +uniform after any of them\n"
		"                       renders in that brightness model (default exact); +keep\n"
		"                       keeps the binning while a scene's draws stay the same\n"
		"                       (render_cpu_options.keep, as the daemon's renderers do)\n"
		"  --volumes N          measure at most N volumes per scene and variant (default 100)\n"
		"  --seconds S          ... and stop measuring after S seconds (default 2)\n"
		"  --interleave         measure a scene's variants a volume each a round (in a new\n"
		"                       order each round), the same frames for all (S seconds per\n"
		"                       variant), so that the drift of a shared machine falls on\n"
		"                       each alike: for ratios\n"
		"  --warmup N           warm-up volumes before measuring (default 2)\n"
		"  --bunny PATH         bunny PLY (default %s/bunny.ply)\n"
		"  --dragon PATH        dragon_vrip.ply (S3-dragon and S3-dragon-x4 are skipped without it)\n"
		"  --dragon-res2 PATH   dragon_vrip_res2.ply (S3-dragon-res2 likewise)\n"
		"  --quick              tiny counts, for a smoke run\n"
		"  --no-micro           skip the memcpy and halftone table\n"
		"  --micro-only         only the memcpy and halftone table\n"
		"  --save DIR           write each scene's reference frame 0 as DIR/SCENE.svol,\n"
		"                       and each variant's as DIR/SCENE.VARIANT.svol\n",
		REFERENCE_VARIANT, BENCH_DATA_DIR);
}

/* The modifiers after a variant's first '+', '+' separated, into v: a
 * brightness model other than exact ("even", "uniform"), and "keep" (bins
 * kept while the scene stays). */
static bool parse_modifiers(char *m, struct variant *v)
{
	for (char *next; m; m = next) {
		next = strchr(m, '+');
		if (next)
			*next++ = '\0';
		if (!strcmp(m, "keep"))
			v->keep = true;
		else if (geometry_brightness_parse(m, &v->brightness) < 0)
			return false;
	}
	return true;
}

bool variant_parse(const char *spec, struct variant *v)
{
	memset(v, 0, sizeof(*v));
	if (strlen(spec) >= sizeof(v->name))
		return false;
	snprintf(v->name, sizeof(v->name), "%s", spec);
	char base[32];
	snprintf(base, sizeof(base), "%s", spec);
	char *plus = strchr(base, '+');
	if (plus) {
		*plus = '\0';
		spec = base;
		if (!parse_modifiers(plus + 1, v))
			return false;
	}
	static const char *const gl[] = { "egl", "osmesa" };
	for (size_t i = 0; i < sizeof(gl) / sizeof(gl[0]); i++) {
		size_t n = strlen(gl[i]);
		if (strncmp(spec, gl[i], n) == 0 && (!spec[n] || !strcmp(spec + n, "-naive"))) {
			snprintf(v->gl, sizeof(v->gl), "%s", gl[i]);
			v->naive = spec[n] != '\0';
			return true;
		}
	}
	if (strncmp(spec, "cpu", 3) != 0)
		return false;
	snprintf(v->simd, sizeof(v->simd), "auto");
	const char *p = spec + 3;
	if (*p == '-' && p[1] >= '1' && p[1] <= '9') {
		char *end;
		unsigned long t = strtoul(p + 1, &end, 10);
		if (*end != 't' || t > 1024)
			return false;
		v->threads = (unsigned)t;
		p = end + 1;
	}
	if (*p == '-' && strlen(p + 1) < sizeof(v->simd) && p[1])
		snprintf(v->simd, sizeof(v->simd), "%s", p + 1);
	else if (*p)
		return false;
	return true;
}

static int parse_variants(const char *list, struct variant *out)
{
	char buf[512];
	snprintf(buf, sizeof(buf), "%s", list);
	int n = 0;
	for (char *save, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
		if (n == MAX_VARIANTS || !variant_parse(tok, &out[n])) {
			fprintf(stderr, "spindle-bench: bad variant '%s'\n", tok);
			return -1;
		}
		n++;
	}
	return n;
}

/* Scene names matching spec: a name, a group ("S1"), or "all". */
static int add_matching(const char *spec, const char **out, int n)
{
	int found = 0;
	size_t l = strlen(spec);
	for (const struct bench_scene_info *i = bench_scene_list(); i->name; i++) {
		bool match = strcmp(spec, "all") == 0 || strcmp(spec, i->name) == 0 ||
			     (strncmp(spec, i->name, l) == 0 && i->name[l] == '-');
		if (match && n + found < MAX_SCENES)
			out[n + found++] = i->name;
	}
	if (!found)
		fprintf(stderr, "spindle-bench: no scene '%s' (--list)\n", spec);
	return found ? n + found : -1;
}

static int add_scenes(struct options *o, const char *list)
{
	char buf[512];
	snprintf(buf, sizeof(buf), "%s", list);
	for (char *save, *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
		/* Names point into the static scene list, not into buf. */
		int n = add_matching(tok, o->scenes, o->scene_count);
		if (n < 0)
			return -1;
		o->scene_count = n;
	}
	return 0;
}

static void list_scenes(void)
{
	for (const struct bench_scene_info *i = bench_scene_list(); i->name; i++)
		printf("%-16s %s\n", i->name, i->what);
}

enum {
	OPT_BUNNY = 256,
	OPT_DRAGON,
	OPT_DRAGON2,
	OPT_NO_MICRO,
	OPT_MICRO_ONLY,
	OPT_WARMUP,
	OPT_SAVE,
	OPT_INTERLEAVE,
};

static const struct option long_opts[] = {
	{ "scene", required_argument, NULL, 's' },
	{ "list", no_argument, NULL, 'l' },
	{ "profile", required_argument, NULL, 'p' },
	{ "variants", required_argument, NULL, 'V' },
	{ "volumes", required_argument, NULL, 'n' },
	{ "seconds", required_argument, NULL, 't' },
	{ "warmup", required_argument, NULL, OPT_WARMUP },
	{ "bunny", required_argument, NULL, OPT_BUNNY },
	{ "dragon", required_argument, NULL, OPT_DRAGON },
	{ "dragon-res2", required_argument, NULL, OPT_DRAGON2 },
	{ "quick", no_argument, NULL, 'q' },
	{ "no-micro", no_argument, NULL, OPT_NO_MICRO },
	{ "micro-only", no_argument, NULL, OPT_MICRO_ONLY },
	{ "save", required_argument, NULL, OPT_SAVE },
	{ "interleave", no_argument, NULL, OPT_INTERLEAVE },
	{ "help", no_argument, NULL, 'h' },
	{ NULL, 0, NULL, 0 },
};

static bool parse_uint(const char *s, uint32_t min, uint32_t *out)
{
	char *end;
	unsigned long v = strtoul(s, &end, 10);
	if (*s == '\0' || *end != '\0' || v < min || v > 10000000)
		return false;
	*out = (uint32_t)v;
	return true;
}

static void set_quick(struct options *o)
{
	o->volumes = 3;
	o->seconds = 0.25;
	o->warmup = 1;
	o->micro_tiles = 256;
	o->micro_runs = 3;
	o->memcpy_bytes = 16 << 20;
}

/* The counts the command line gave, which --quick leaves alone. */
struct given {
	bool volumes, seconds, warmup;
};

/* --quick: small counts but those given, before it or after it. */
static void quick(struct options *o, const struct given *g)
{
	struct options keep = *o;
	set_quick(o);
	if (g->volumes)
		o->volumes = keep.volumes;
	if (g->seconds)
		o->seconds = keep.seconds;
	if (g->warmup)
		o->warmup = keep.warmup;
}

/* Where an option that names something (a profile, a file, a
 * directory) keeps its argument, or NULL for another option. */
static const char **name_slot(int c, struct options *o)
{
	switch (c) {
	case 'p':
		return &o->profile;
	case OPT_BUNNY:
		return &o->files.bunny;
	case OPT_DRAGON:
		return &o->files.dragon;
	case OPT_DRAGON2:
		return &o->files.dragon_res2;
	case OPT_SAVE:
		return &o->save_dir;
	}
	return NULL;
}

/* getopt's option c (its argument in optarg): 0 to go on, 1 to exit
 * successfully, -1 on a usage error. */
static int parse_option(int c, struct options *o, struct given *g, const char **variants)
{
	const char **name = name_slot(c, o);
	if (name) {
		*name = optarg;
		return 0;
	}
	char *end = NULL;
	switch (c) {
	case 's':
		return add_scenes(o, optarg) == 0 ? 0 : -1;
	case 'l':
		list_scenes();
		return 1;
	case 'V':
		*variants = optarg;
		return 0;
	case 'n':
		return (g->volumes = parse_uint(optarg, 1, &o->volumes)) ? 0 : -1;
	case 't':
		o->seconds = strtod(optarg, &end);
		return (g->seconds = *end == '\0' && o->seconds > 0 && o->seconds < 1e5) ? 0 : -1;
	case OPT_WARMUP:
		return (g->warmup = parse_uint(optarg, 0, &o->warmup)) ? 0 : -1;
	case OPT_NO_MICRO:
		o->micro = false;
		return 0;
	case OPT_MICRO_ONLY:
		o->renders = false;
		return 0;
	case OPT_INTERLEAVE:
		o->interleave = true;
		return 0;
	case 'q':
		quick(o, g);
		return 0;
	case 'h':
		usage(stdout);
		return 1;
	}
	return -1;
}

/* Returns 0 to run, 1 to exit successfully, -1 on a usage error. */
int options_parse(int argc, char **argv, struct options *o)
{
	*o = (struct options){
		.profile = "perspecta",
		.volumes = 100,
		.seconds = 2,
		.warmup = 2,
		.files = { .bunny = BENCH_DATA_DIR "/bunny.ply" },
		.micro = true,
		.renders = true,
		.micro_tiles = 4096,
		.micro_runs = 7,
		.memcpy_bytes = 64 << 20,
	};
	const char *variants = "cpu," REFERENCE_VARIANT;
	struct given g = { 0 };
	int c;
	while ((c = getopt_long(argc, argv, "s:lp:V:n:t:qh", long_opts, NULL)) != -1) {
		int r = parse_option(c, o, &g, &variants);
		if (r != 0) {
			if (r < 0)
				usage(stderr);
			return r;
		}
	}
	if (optind < argc || (o->nvars = parse_variants(variants, o->vars)) <= 0) {
		usage(stderr);
		return -1;
	}
	if (o->scene_count == 0)
		add_scenes(o, "all");
	return 0;
}
