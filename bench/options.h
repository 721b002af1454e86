/* spindle-bench's command line (bench/README.md): what to run and how long. */
#ifndef SPINDLE_BENCH_OPTIONS_H
#define SPINDLE_BENCH_OPTIONS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "render.h"
#include "scenes.h"

/* The exact reference every variant is compared with. */
#define REFERENCE_VARIANT "cpu-1t-scalar"
#define MAX_VARIANTS 16
#define MAX_SCENES 64

/* A renderer variant, "cpu[-<N>t][-<simd>]" or "egl|osmesa[-naive]", and,
 * while it runs, its renderer and output volume. */
struct variant {
	char name[32];
	unsigned threads;   /* 0: one per core */
	char simd[16];      /* "auto", "scalar", ... */
	char gl[8];         /* GL backend ("egl", "osmesa"), "" for the CPU */
	bool naive;         /* the GL baseline pipeline */
	uint8_t brightness; /* enum geometry_brightness: a "+even" or "+uniform" suffix */
	bool keep;          /* "+keep": render_cpu_options.keep */
	struct renderer *r;
	struct volume *out;
};

struct options {
	const char *profile;
	const char *scenes[MAX_SCENES]; /* names from bench_scene_list() */
	int scene_count;
	struct variant vars[MAX_VARIANTS];
	int nvars;
	uint32_t volumes; /* at most this many measured volumes ... */
	double seconds;   /* ... and no more measuring once this long has passed */
	uint32_t warmup;
	struct bench_files files;
	bool micro, renders;
	bool interleave; /* a volume of each variant in turn (bench.c: measure()) */
	uint32_t micro_tiles, micro_runs;
	size_t memcpy_bytes;
	const char *save_dir; /* write each scene's reference frame 0 here */
};

/* Parses a variant name into v (renderer and volume NULL). */
bool variant_parse(const char *spec, struct variant *v);

/* Returns 0 to run, 1 to exit successfully (--help, --list), -1 on a usage
 * error (already reported). */
int options_parse(int argc, char **argv, struct options *o);

#endif
