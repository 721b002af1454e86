/* spindle-bench: renders the fixed benchmark scenes (bench/scenes.h) with
 * each renderer variant and prints Markdown tables: speed, the split into
 * stages, sparseness, and coverage against the exact reference; then
 * memcpy bandwidth and halftone+pack throughput. See bench/README.md. */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "coverage.h"
#include "halftone.h"
#include "log.h"
#include "micro.h"
#include "options.h"
#include "render.h"
#include "rng.h"
#include "scenes.h"
#include "section.h"
#include "svol.h"

/* What the measured volumes of one scene and variant gave. */
struct measurement {
	uint32_t n;
	double *ms;              /* per volume, sorted after measuring */
	double *cpu_ms;          /* per volume, process CPU time, sorted likewise */
	struct render_stats sum; /* render_stats summed over the volumes */
	uint64_t tiles, sparse_bytes;
	double total_s;
	double cpu_s; /* process CPU time over the measured volumes */
};

/* "1234567" -> "1,234,567". */
static const char *fmt_count(char *buf, size_t size, uint64_t v)
{
	char digits[32];
	int n = snprintf(digits, sizeof(digits), "%llu", (unsigned long long)v);
	size_t o = 0;
	for (int i = 0; i < n && o + 2 < size; i++) {
		if (i > 0 && (n - i) % 3 == 0)
			buf[o++] = ',';
		buf[o++] = digits[i];
	}
	buf[o] = '\0';
	return buf;
}

/* Three significant digits or so, at least one decimal below 100. */
static const char *fmt_num(char *buf, size_t size, double v)
{
	if (v < 10)
		snprintf(buf, size, "%.2f", v);
	else if (v < 100)
		snprintf(buf, size, "%.1f", v);
	else
		snprintf(buf, size, "%.0f", v);
	return buf;
}

static int variant_open(struct variant *v, const struct geometry *geom)
{
	struct geometry model = *geom, *g = &model;
	model.brightness = v->brightness;
	struct render_cpu_options o = { .threads = v->threads, .simd = v->simd, .keep = v->keep };
	struct render_gl_options gl = { .backend = v->gl, .naive = v->naive, .no_fallback = true, .keep = v->keep };
	v->r = v->gl[0] ? render_gl_create(g, &gl) : render_cpu_create_opts(g, &o);
	if (!v->r && v->gl[0]) {
		fprintf(stderr, "spindle-bench: variant %s: %s\n", v->name, strerror(errno));
		return -1;
	}
	if (!v->r) {
		fprintf(stderr, "spindle-bench: variant %s: %s\n", v->name,
			errno == ENOENT ? "halftone variant unknown or not runnable on this CPU" : strerror(errno));
		return -1;
	}
	v->out = volume_create(g);
	return v->out ? 0 : -1;
}

static void variant_close(struct variant *v)
{
	render_destroy(v->r);
	volume_destroy(v->out);
	v->r = NULL;
	v->out = NULL;
}

static unsigned cores(void)
{
	long n = sysconf(_SC_NPROCESSORS_ONLN);
	return n > 0 ? (unsigned)n : 1;
}

static void stats_add(struct render_stats *sum, const struct render_stats *s)
{
	sum->total_ns += s->total_ns;
	sum->bin_ns += s->bin_ns;
	sum->raster_ns += s->raster_ns;
	sum->pack_ns += s->pack_ns;
	sum->prims += s->prims;
	sum->prim_images += s->prim_images;
	sum->canvas_tiles += s->canvas_tiles;
	sum->tiles += s->tiles;
	sum->threads = s->threads;
}

/* Animates the scene to frame and renders it; the wall time of both in ms. */
static int render_frame(struct variant *v, struct bench_scene *s, uint64_t frame, double *ms)
{
	int64_t t0 = now_ns();
	bench_scene_animate(s, frame);
	int err = render_volume(v->r, &s->scene, v->out);
	*ms = (double)(now_ns() - t0) / 1e6;
	if (err < 0)
		fprintf(stderr, "spindle-bench: %s on %s: %s\n", v->name, s->info->name, strerror(-err));
	return err;
}

static double process_cpu_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
	return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

static int cmp_double(const void *a, const void *b)
{
	double x = *(const double *)a, y = *(const double *)b;
	return (x > y) - (x < y);
}

static int measure_start(const struct options *o, struct measurement *m)
{
	memset(m, 0, sizeof(*m));
	m->ms = calloc(o->volumes, sizeof(*m->ms));
	m->cpu_ms = calloc(o->volumes, sizeof(*m->cpu_ms));
	return m->ms && m->cpu_ms ? 0 : -1;
}

/* One measured volume (frame) of v into m. */
static int measure_volume(struct variant *v, struct bench_scene *s, uint64_t frame, struct measurement *m)
{
	double cpu = process_cpu_s();
	if (render_frame(v, s, frame, &m->ms[m->n]) < 0)
		return -1;
	m->cpu_ms[m->n] = (process_cpu_s() - cpu) * 1e3;
	m->cpu_s += m->cpu_ms[m->n] / 1e3;
	m->total_s += m->ms[m->n] / 1e3;
	stats_add(&m->sum, &v->r->stats);
	m->tiles += volume_tile_count(v->out);
	m->sparse_bytes += volume_sparse_bytes(v->out);
	m->n++;
	return 0;
}

static void measure_finish(struct measurement *m)
{
	qsort(m->ms, m->n, sizeof(*m->ms), cmp_double);
	qsort(m->cpu_ms, m->n, sizeof(*m->cpu_ms), cmp_double);
}

static void measure_free(struct measurement *m)
{
	free(m->ms);
	free(m->cpu_ms);
}

/* Warm-up volumes of each variant (fewer if one alone takes the whole
 * time budget). Frames start at 1: frame 0 is the coverage frame. */
static int warm_up(struct variant *v, int nvars, struct bench_scene *s, const struct options *o)
{
	double ms;
	for (int i = 0; i < nvars; i++)
		for (uint32_t f = 1; f <= o->warmup; f++) {
			if (render_frame(&v[i], s, f, &ms) < 0)
				return -1;
			if (ms > o->seconds * 1e3)
				break;
		}
	return 0;
}

/* order[0 .. n) a new random order of 0 .. n - 1 (Fisher-Yates). */
static void shuffle(struct rng *r, int *order, int n)
{
	for (int i = 0; i < n; i++)
		order[i] = i;
	for (int i = n - 1; i > 0; i--) {
		int j = (int)(rng_next(r) % (uint64_t)(i + 1)), t = order[i];
		order[i] = order[j];
		order[j] = t;
	}
}

/* Measured volumes until o->volumes or o->seconds, at least one: each
 * variant's run of them in turn, or (o->interleave) one volume of each
 * variant a round, the same frames for all, so that the drift of a shared
 * machine falls on every variant alike (o->seconds then is per variant).
 * Each round takes the variants in a new order (the same from run to run):
 * what one volume leaves the next (the second core idle through a
 * single-threaded one, which the host then runs slowly for a while; see
 * docs/performance.md) falls on every variant alike too, not always on
 * the one after it in the list. */
static int measure(struct variant *v, int nvars, struct bench_scene *s, const struct options *o, struct measurement *m)
{
	uint64_t first = o->warmup + 1;
	int order[MAX_VARIANTS];
	struct rng rng = rng_seed(0x5350494eu);
	for (int i = 0; i < nvars; i++)
		if (measure_start(o, &m[i]) < 0)
			return -1;
	int64_t start = now_ns();
	bool again = true;
	for (uint32_t n = 0; again && n < o->volumes; n++) {
		shuffle(&rng, order, nvars);
		for (int i = 0; i < nvars; i++)
			if (measure_volume(&v[order[i]], s, first + n, &m[order[i]]) < 0)
				return -1;
		again = (double)(now_ns() - start) < o->seconds * nvars * 1e9;
	}
	for (int i = 0; i < nvars; i++)
		measure_finish(&m[i]);
	return 0;
}

/* Nearest rank: the smallest sample with at least p of the samples at or
 * below it. */
static double percentile(const struct measurement *m, double p)
{
	uint32_t rank = (uint32_t)ceil(p * m->n);
	if (rank < 1)
		rank = 1;
	if (rank > m->n)
		rank = m->n;
	return m->ms[rank - 1];
}

static const char *fmt_prims(char *buf, size_t size, const struct bench_scene *s)
{
	char a[32], b[32];
	if (s->points)
		snprintf(buf, size, "%s points", fmt_count(a, sizeof(a), s->points));
	else if (s->segments)
		snprintf(buf, size, "%s segments", fmt_count(a, sizeof(a), s->segments));
	else if (s->triangles)
		snprintf(buf, size, "%s triangles", fmt_count(a, sizeof(a), s->triangles));
	else
		snprintf(buf, size, "none");
	if (s->scene.draw_count > 1) {
		size_t l = strlen(buf);
		snprintf(buf + l, size - l, " in %s draws", fmt_count(b, sizeof(b), s->scene.draw_count));
	}
	return buf;
}

static void print_table_header(void)
{
	printf("| scene | primitives | variant | volumes | vol/s | median ms | p99 ms | cores used | cpu ms "
	       "| bin ms | raster ms (sum) | pack ms (sum) | tiles/vol | occupancy "
	       "| sparse MB/vol | of dense | identical | coverage | stray |\n");
	printf("|---|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|:-:|--:|--:|\n");
}

/* "100.0000%", or "n/a" when there is nothing to take the fraction of. */
static const char *fmt_fraction(char *buf, size_t size, double f, const uint64_t of[3])
{
	if (of[0] + of[1] + of[2] == 0)
		snprintf(buf, size, "n/a");
	else
		snprintf(buf, size, "%.4f%%", 100 * f);
	return buf;
}

static void print_row(const struct bench_scene *s, const struct variant *v, const struct measurement *m,
		      const struct coverage *c, const struct volume *vol)
{
	char p[96], b[11][32];
	double n = m->n, images = vol->image_count * (double)volume_tiles_per_image(vol);
	double dense = vol->image_count * (double)volume_dense_image_bytes(vol);
	double tiles = m->tiles / n, sparse = m->sparse_bytes / n;
	printf("| %s | %s | %s | %u | %s | %s | %s | %.2f | %s | %s | %s | %s | %s | %.2f%% | %s | %.2f%% "
	       "| %s | %s | %s |\n",
	       s->info->name, fmt_prims(p, sizeof(p), s), v->name, m->n, fmt_num(b[0], 32, n / m->total_s),
	       fmt_num(b[1], 32, percentile(m, 0.5)), fmt_num(b[2], 32, percentile(m, 0.99)), m->cpu_s / m->total_s,
	       fmt_num(b[10], 32, m->cpu_ms[(m->n - 1) / 2]), fmt_num(b[3], 32, m->sum.bin_ns / n / 1e6),
	       fmt_num(b[4], 32, m->sum.raster_ns / n / 1e6), fmt_num(b[5], 32, m->sum.pack_ns / n / 1e6),
	       fmt_count(b[6], 32, (uint64_t)(tiles + 0.5)), 100 * tiles / images, fmt_num(b[7], 32, sparse / 1e6),
	       100 * sparse / dense, c->identical ? "yes" : "no", fmt_fraction(b[8], 32, coverage_score(c), c->ref_lit),
	       fmt_fraction(b[9], 32, coverage_stray(c), c->test_lit));
	fflush(stdout);
}

/* A scene's frame 0 as DIR/SCENE.svol (the reference) or
 * DIR/SCENE.VARIANT.svol (variant: NULL for the reference), for spindlectl
 * preview and for comparing outputs across builds (cmp). */
static int save_volume(const char *dir, const char *scene, const char *variant, const struct volume *vol)
{
	char path[4096];
	snprintf(path, sizeof(path), "%s/%s%s%s.svol", dir, scene, variant ? "." : "", variant ? variant : "");
	FILE *f = fopen(path, "wb");
	int r = f ? svol_write(f, vol) : -errno;
	if (f && fclose(f) != 0 && r == 0)
		r = -errno;
	if (r < 0)
		fprintf(stderr, "spindle-bench: %s: %s\n", path, strerror(-r));
	return r;
}

/* Compares variant v's frame 0 of scene s with ref and prints its row. */
static int report_variant(struct variant *v, struct bench_scene *s, const struct volume *ref, const struct options *o,
			  const struct measurement *m)
{
	struct coverage c;
	double ms;
	int err = render_frame(v, s, 0, &ms);
	if (err == 0 && o->save_dir)
		err = save_volume(o->save_dir, s->info->name, v->name, v->out);
	if (err == 0 && (err = coverage_compare(ref, v->out, &c)) < 0)
		fprintf(stderr, "spindle-bench: coverage: %s\n", strerror(-err));
	if (err == 0)
		print_row(s, v, m, &c, v->out);
	return err;
}

/* Measures variants (all of them together with --interleave, else one at
 * a time) on scene s and reports each. */
static int run_variants(struct variant *vars, int nvars, struct bench_scene *s, const struct volume *ref,
			const struct options *o)
{
	int group = o->interleave ? nvars : 1, err = 0;
	struct measurement *m = calloc((size_t)nvars, sizeof(*m));
	if (!m)
		return -1;
	for (int i = 0; err == 0 && i < nvars; i += group) {
		err = warm_up(&vars[i], group, s, o);
		if (err == 0)
			err = measure(&vars[i], group, s, o, &m[i]);
		for (int j = i; err == 0 && j < i + group; j++)
			err = report_variant(&vars[j], s, ref, o, &m[j]);
	}
	for (int i = 0; i < nvars; i++)
		measure_free(&m[i]);
	free(m);
	return err;
}

static int run_scene(const char *name, const struct geometry *g, struct variant *vars, int nvars, struct variant *ref,
		     const struct options *o, FILE *notes)
{
	struct bench_scene s;
	char err[256];
	int r = bench_scene_build(name, g, &o->files, &s, err, sizeof(err));
	if (r == -ENODATA) {
		fprintf(notes, "- %s: skipped, its model file was not given.\n", name);
		return 0;
	}
	if (r < 0) {
		fprintf(stderr, "spindle-bench: %s\n", err);
		fprintf(notes, "- %s: failed: %s.\n", name, err);
		return -1;
	}
	double ms;
	r = render_frame(ref, &s, 0, &ms);
	if (r == 0 && o->save_dir)
		r = save_volume(o->save_dir, name, NULL, ref->out);
	if (r == 0)
		r = run_variants(vars, nvars, &s, ref->out, o);
	bench_scene_free(&s);
	return r;
}

/* One variant's line of the preamble: its renderer, threads, halftone
 * and what it keeps. */
static void print_variant(const struct variant *v)
{
	char th[32];
	if (v->gl[0]) {
		printf("- %s: GL renderer%s on %s; binning on one thread per core%s\n", v->name,
		       v->naive ? " (the naive pipeline)" : "", render_gl_describe(v->r),
		       v->keep ? ", kept while the scene's draws stay the same" : "");
		return;
	}
	if (v->threads)
		snprintf(th, sizeof(th), "%u thread%s", v->threads, v->threads > 1 ? "s" : "");
	else
		snprintf(th, sizeof(th), "one thread per core");
	/* render_cpu.c: the eight-lane triangles go with auto and avx512 */
	bool lanes = (strcmp(v->simd, "auto") == 0 || strcmp(v->simd, "avx512") == 0) && section_batch_supported();
	const char *tris = lanes ? "triangles sectioned and staged eight at a time" : "triangles one at a time";
	const char *keep = v->keep ? "; binning kept while the scene's draws stay the same" : "";
	if (strcmp(v->simd, "auto") == 0)
		printf("- %s: %s, halftone auto (%s here), %s%s\n", v->name, th, halftone_variants()[0].name, tris,
		       keep);
	else
		printf("- %s: %s, halftone %s, %s%s\n", v->name, th, v->simd, tris, keep);
}

static void print_preamble(const char *profile, const struct geometry *g, const struct volume *vol,
			   const struct variant *vars, int nvars, const struct options *o)
{
	double dense = vol->image_count * (double)volume_dense_image_bytes(vol);
	printf("Profile %s: %ux%u, N = %u%s: %u images per volume, %u tiles of 32x32 per image, "
	       "dense volume %.2f MB.\n\n",
	       profile, g->width, g->height, g->images_per_rev, g->mirrored ? ", mirrored" : "", vol->image_count,
	       volume_tiles_per_image(vol), dense / 1e6);
	printf("Variants (%u cores here; the reference is %s):\n", cores(), REFERENCE_VARIANT);
	for (int i = 0; i < nvars; i++)
		print_variant(&vars[i]);
	printf("\nEach scene and variant: %u warm-up volume%s, then up to %u measured volumes or "
	       "%.3g s, whichever comes first (volumes). Times are wall ms per volume, animation "
	       "included; p99 is nearest rank. cores used = process CPU time / wall time while "
	       "measuring (below the thread count: serial parts, or other load on the machine). "
	       "bin / raster / pack: render_stats per volume; bin is "
	       "wall time, raster (sectioning + raster) and pack (halftone + pack + clear) are "
	       "summed over the renderer's threads. occupancy = tiles / (images x tiles per image). "
	       "sparse MB = volume_sparse_bytes (masks + tiles); of dense = that / the dense volume. "
	       "identical / coverage / stray: frame 0 against %s's (bench/coverage.h; coverage = "
	       "reference voxels with a lit voxel within one voxel, per channel; stray = lit voxels "
	       "farther than one voxel from any reference voxel).\n\n",
	       o->warmup, o->warmup == 1 ? "" : "s", o->volumes, o->seconds, REFERENCE_VARIANT);
}

static int run_renders(struct options *o)
{
	struct geometry g;
	struct variant *vars = o->vars, ref;
	int nvars = o->nvars;
	if (geometry_from_profile(o->profile, &g) < 0) {
		fprintf(stderr, "spindle-bench: no profile '%s'\n", o->profile);
		return -1;
	}
	variant_parse(REFERENCE_VARIANT, &ref);
	int r = variant_open(&ref, &g);
	for (int i = 0; r == 0 && i < nvars; i++)
		r = variant_open(&vars[i], &g);
	char *notes_buf = NULL;
	size_t notes_len = 0;
	FILE *notes = open_memstream(&notes_buf, &notes_len);
	if (r == 0 && notes) {
		print_preamble(o->profile, &g, ref.out, vars, nvars, o);
		print_table_header();
		for (int i = 0; i < o->scene_count; i++)
			if (run_scene(o->scenes[i], &g, vars, nvars, &ref, o, notes) < 0)
				r = -1;
	}
	if (notes) {
		fclose(notes);
		if (notes_len)
			printf("\n%s", notes_buf);
		free(notes_buf);
	}
	for (int i = 0; i < nvars; i++)
		variant_close(&vars[i]);
	variant_close(&ref);
	return r;
}

static void run_micro(const struct options *o)
{
	double mc = micro_memcpy_gbps(o->memcpy_bytes, (int)o->micro_runs);
	printf("\n| single thread | GB/s | of memcpy |\n|---|--:|--:|\n");
	printf("| memcpy, %zu MiB buffers (bytes copied) | %.2f | 100%% |\n", o->memcpy_bytes >> 20, mc);
	for (const struct halftone_variant *v = halftone_variants(); v->name; v++) {
		double ht = micro_halftone_gbps(v->fn, o->micro_tiles, (int)o->micro_runs);
		printf("| halftone+pack %s, %u random canvas tiles (3072 canvas bytes each) | %.2f | %.0f%% |\n",
		       v->name, o->micro_tiles, ht, 100 * ht / mc);
	}
	printf("\nMedian of %u runs each.\n", o->micro_runs);
	/* The calibration's axis offset: the pipeline shifts every volume
	 * rendered (calibration.h). */
	struct geometry g;
	if (geometry_from_profile("perspecta", &g) < 0)
		return;
	printf("\n| volume_shift(), perspecta, by (3, -2) px | stored tiles | ms per volume |\n|---|--:|--:|\n");
	static const double fills[] = { 0.001, 0.05, 0.25, 1.0 };
	for (size_t i = 0; i < sizeof(fills) / sizeof(fills[0]); i++) {
		uint64_t tiles = 0;
		double ms = micro_shift_ms(&g, fills[i], 3, -2, (int)o->micro_runs, &tiles);
		printf("| %.1f%% of the tiles stored | %llu | %.3f |\n", 100 * fills[i], (unsigned long long)tiles, ms);
	}
}

int main(int argc, char **argv)
{
	struct options o;
	int r = options_parse(argc, argv, &o);
	if (r != 0)
		return r < 0 ? 2 : 0;
	if (o.renders && run_renders(&o) < 0)
		r = 1;
	if (o.micro)
		run_micro(&o);
	return r;
}
