/* Per-volume binning (docs/design.md section 5), shared by the renderers.
 *
 * Every draw's vertices are transformed to volume space once per volume and
 * primitives with a non-finite vertex are dropped. Each vertex gets its
 * azimuth slot from its outcode octant and slope (slot.h); a primitive's
 * slots give the closed arc of slots it spans, or "every image" when its
 * projection may touch the axis. Primitives are then sorted (a stable
 * counting sort, in parallel) by the length class of their image range and
 * by its first image, so image k finds everything it may need in a few
 * contiguous runs: for class c (ranges of at most 2^c images) the
 * primitives whose first image lies in [k - 2^c + 1, k]. Points are reduced
 * at binning time to the voxel they light, sorted by image.
 *
 * Conservative: a primitive is in the range of every image whose bow tie it
 * meets (sometimes one more); the renderer's sectioning decides exactly.
 *
 * Turns (scene.h, scene_draw.turn): a turned draw's primitives keep their
 * vertices; their image range is shifted by the turn (mod M) and the turn
 * is kept beside each (prim_turn), from which the renderer takes the image
 * whose wedge it sections by and whether it writes mirrored
 * (geometry_turn_source()). Points are shifted and mirrored at binning. */
#ifndef SPINDLE_BIN_H
#define SPINDLE_BIN_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "scene.h"
#include "slot.h"
#include "volume.h"

struct pool;

/* A segment (nverts 2) or triangle (3) in volume space, with the volume
 * images it may light: first, first + 1, ..., first + count - 1 (mod M),
 * already shifted by its draw's turn. rgb is its own colour: the draw's, or
 * its entry of the draw's prim_rgb. The GL renderer uploads these words as
 * they are (render_gl_priv.h); the turn, which only the CPU renderer draws,
 * is kept apart (bin_set.prim_turn). */
struct bin_prim {
	float v[3][3];
	uint8_t nverts;
	uint8_t rgb[3];
	uint16_t first;
	uint16_t count;
};

#define BIN_POINT_MAX_SIZE 16

/* A point, already reduced to the voxel (u, v) of its image. It lights the
 * size x size square of columns u - (size-1)/2 .. u + size/2 and rows
 * v - (size-1)/2 .. v + size/2 of that volume image, clipped to the image
 * (bin_point_span()); size is 1..BIN_POINT_MAX_SIZE. A point of a turned
 * draw shown mirrored has u mirrored already, and an even square the flag
 * BIN_POINT_MIRRORED in size: its columns are then the mirror of the
 * unturned square's, u - size/2 .. u + (size-1)/2 (bin_point_columns()).
 * Only the CPU renderer draws turned points. */
struct bin_point {
	uint16_t u, v;
	uint8_t rgb[3];
	uint8_t size;
};

#define BIN_POINT_MIRRORED 0x80

/* The voxels a run of one-pixel points of colour rgb lights, a bit each,
 * for a draw dense enough that a bit per voxel of the volume costs less
 * than a record per point (bin_points_maskable()): the same voxels as the
 * records of those points (bin_points_mask()). bits holds each volume
 * image's tiles in order (bin_mask_image()), each tile as VOLUME_TILE
 * rows of one 32-bit word with pixel x at bit x ^ 7: the layout of a
 * canvas's lit bits (section.h), so that a tile's rows AND the halftone
 * pattern of rgb are the bits those points light. */
struct bin_point_mask {
	uint8_t rgb[3];
	uint32_t *bits;
};

/* A contiguous run of b->prims that image k must look at; entries whose
 * range does not hold k are skipped with bin_prim_in_image(). */
struct bin_run {
	uint32_t begin, end;
};

#define BIN_MAX_CLASSES 16 /* 2^15 >= 16384 images */
/* Scenes of at most this many vertices are binned, and rendered by the
 * CPU renderer, on the calling thread alone: a small object (the object
 * cache renders them one by one) costs less than waking the workers. */
#define BIN_SERIAL_VERTICES 1024

/* The paths that bin points (bin_points.c): each gives exactly the
 * records of the scalar rule. */
enum bin_points_isa {
	BIN_POINTS_AUTO,   /* the fastest the CPU has */
	BIN_POINTS_SCALAR, /* the rule alone */
	BIN_POINTS_AVX2,   /* four points at a time */
	BIN_POINTS_AVX512, /* eight at a time, the rest as AVX2 does */
};

/* Storage is kept between builds and only grows. */
struct bin_set {
	struct geometry geom;
	uint32_t images;  /* M: images per volume */
	unsigned classes; /* length classes: 0 .. classes - 1 */
	struct slot_table slots;
	double *dir; /* per volume image: cos, sin of its angle */

	uint32_t prim_count;
	struct bin_prim *prims; /* sorted by (class, first) */
	/* Some segment or triangle has a turn: then prim_turn[i] is prims[i]'s
	 * turn mod N (0 for most), else prim_turn is not written. */
	bool turned;
	uint16_t *prim_turn;
	uint32_t *prim_start; /* classes * M + 1 offsets into prims */
	uint32_t point_count;
	struct bin_point *points; /* sorted by image */
	uint32_t *point_start;    /* M + 1 offsets into points */
	/* Set by the renderer that can light them (the CPU renderer): the
	 * dense draws of one-pixel points of one colour come as masks
	 * (struct bin_point_mask), not records. Those points are not in
	 * points; mask_points counts them. */
	bool point_masks;
	uint32_t mask_count;
	struct bin_point_mask *masks;
	uint64_t mask_points;
	/* Tests: the path that bins points (bin_points.c); every path gives
	 * the same records. 0 (BIN_POINTS_AUTO): the fastest there is. */
	enum bin_points_isa points_isa;
	/* Tests and the scalar renderer variant: triangles staged one at a
	 * time (bin.c), not eight at a time; the records are the same. */
	bool prims_scalar;
	/* Set by the renderer: a build keeps its result while the scene's
	 * draws stay the same, vertex data by number (scene_draw.data_id), and
	 * builds nothing then; kept tells the last build found it so. */
	bool keep, kept;

	/* Work space of a build. */
	struct bin_work *work;
};

/* Returns 0 or -ENOMEM. */
int bin_init(struct bin_set *b, const struct geometry *g);
void bin_finish(struct bin_set *b);

/* Transforms and bins scene on the pool's workers (with keep: unless b
 * holds the same binning already). Returns 0, or -ENOMEM or -E2BIG (more
 * than 2^31 primitives). */
int bin_build(struct bin_set *b, const struct scene *scene, struct pool *pool);

/* The runs of prims image k must look at; fills out (2 * BIN_MAX_CLASSES
 * entries at most) and returns how many. */
unsigned bin_runs(const struct bin_set *b, uint32_t k, struct bin_run *out);

/* The first and last of the n pixels a point of size `size` at pixel i
 * covers along one axis, clipped to 0 .. n - 1. */
static inline void bin_point_span(uint32_t i, uint32_t size, uint32_t n, uint32_t *lo, uint32_t *hi)
{
	uint32_t before = (size - 1) / 2, after = size / 2;
	*lo = i > before ? i - before : 0;
	*hi = i + after < n ? i + after : n - 1;
}

/* The columns of a binned point's square (size and BIN_POINT_MIRRORED),
 * clipped to 0 .. n - 1. */
static inline void bin_point_columns(const struct bin_point *p, uint32_t n, uint32_t *lo, uint32_t *hi)
{
	uint32_t size = p->size & ~(uint32_t)BIN_POINT_MIRRORED;
	if (!(p->size & BIN_POINT_MIRRORED)) {
		bin_point_span(p->u, size, n, lo, hi);
		return;
	}
	uint32_t before = size / 2, after = (size - 1) / 2;
	*lo = p->u > before ? p->u - before : 0;
	*hi = p->u + after < n ? p->u + after : n - 1;
}

/* Points at binning, for bin.c (bin_points.c; docs/rendering.md, "Points"
 * and "Binning"): one pass stages each point's record(s) and counts them
 * per image, a scatter moves them to their sorted place. The records are
 * exactly those of the scalar rule (transform in double, slot from the
 * slope table, atan2 near a slot boundary or on the axis); the AVX-512 and
 * AVX2 paths compute the same operations eight or four points at a time and
 * hand every point the table flags as near, on the axis or not finite to
 * the scalar rule. */

/* What binning points and primitives share: the draw's transform of a
 * vertex, column-major affine in double, false if the result is not a
 * finite float (primitives are stored in float: past FLT_MAX is inf); and
 * the draw's turn, mod N. */
static inline bool bin_transform(const float m[16], const float *xyz, double out[3])
{
	double x = xyz[0], y = xyz[1], z = xyz[2];
	for (int i = 0; i < 3; i++) {
		out[i] = (double)m[i] * x + (double)m[4 + i] * y + (double)m[8 + i] * z + m[12 + i];
		if (!(fabs(out[i]) <= FLT_MAX))
			return false;
	}
	return true;
}

/* Whether transform m is diagonal with no translation of -0: then
 * bin_transform()'s coordinate c of a finite point is m[5c] times its own
 * input plus m[12 + c], bit for bit. The terms left out are zeros, exact,
 * and the last sum adds a translation that is not -0, which makes a zero
 * +0 either way. (An input that is not finite makes its own coordinate
 * not finite too, as there.) The vector paths take the shorter sum. */
static inline bool bin_transform_diagonal(const float m[16])
{
	for (int c = 0; c < 3; c++)
		for (int i = 0; i < 3; i++)
			if (i != c && m[4 * i + c] != 0.0f)
				return false;
	return !signbit(m[12]) && !signbit(m[13]) && !signbit(m[14]);
}

static inline uint32_t bin_draw_turn(const struct bin_set *b, const struct scene_draw *d)
{
	return d->turn ? d->turn % b->geom.images_per_rev : 0;
}

/* Staged records per item (point, segment or triangle): 1 on a mirrored
 * device, where both lobes fold onto one volume image (a point's rare
 * second record of a rounding tie is made again by the scatter), else 2. */
static inline uint32_t bin_slots(const struct bin_set *b)
{
	return b->geom.mirrored ? 1 : 2;
}

/* Whether this CPU runs isa (AUTO and SCALAR: always). A path it lacks
 * bins with the scalar rule. */
bool bin_points_isa_supported(enum bin_points_isa isa);

/* Stages points j0 .. j1 - 1 of draw d: recs and keys point at point j0's
 * bin_slots() entries; counts each record's volume image in hist. */
void bin_points_stage(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
		      struct bin_point *recs, uint16_t *keys, uint32_t *hist);

/* Moves the staged records of points j0 .. j1 - 1 of draw d (as staged by
 * bin_points_stage()) to b->points[off[image]++], in point order. */
void bin_points_scatter(struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
			const struct bin_point *recs, const uint16_t *keys, uint32_t *off);

/* Words of a point mask: VOLUME_TILE a tile of every volume image. */
static inline size_t bin_mask_words(const struct bin_set *b)
{
	return (size_t)b->images * volume_geometry_tiles(&b->geom) * VOLUME_TILE;
}

/* Image k's tiles of a point mask's bits. */
static inline const uint32_t *bin_mask_image(const struct bin_set *b, const struct bin_point_mask *m, uint32_t k)
{
	return m->bits + (size_t)k * volume_geometry_tiles(&b->geom) * VOLUME_TILE;
}

/* Whether points lo .. hi - 1 of draw d may be binned as a mask: the
 * renderer takes masks, the CPU has the eight-lane path, the device is
 * mirrored, the draw unturned, of one colour and one-pixel points, and
 * the run has at least as many points as the mask has words. */
bool bin_points_maskable(const struct bin_set *b, const struct scene_draw *d, uint64_t lo, uint64_t hi);

/* Points j0 .. j1 - 1 of draw d ORed into bits (a mask's, bin_mask_words()
 * long): every voxel their records light (bin_points_stage()) has its bit
 * set. bin_points_maskable() must hold. */
void bin_points_mask(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1, uint32_t *bits);

/* Segments and triangles at binning, for bin.c and bin_tris.c (the
 * eight-lane triangle staging): each is first written as a record and its
 * sort key, and counted; the scatter then moves the records to their
 * sorted places. */
#define BIN_KEY_NONE UINT32_MAX
/* A staged primitive's key holds its sort key (class * M + first) in the
 * low BIN_KEY_BITS bits and its turn (mod N) above them: sort keys are below
 * 15 * 16384 < 2^18 (M <= 16384, so at most 15 classes) and turns below
 * N <= 16384 = 2^14, so no key is BIN_KEY_NONE. Point keys are images. */
#define BIN_KEY_BITS 18
#define BIN_KEY_MASK ((1u << BIN_KEY_BITS) - 1)
_Static_assert(BIN_MAX_CLASSES * 16384u <= (1u << BIN_KEY_BITS) && 16384u <= (1u << (32 - BIN_KEY_BITS)),
	       "sort key and turn share a staged key");

/* A record and its sort key (BIN_KEY_NONE: unused). */
struct stage_prim {
	struct bin_prim rec;
	uint32_t key;
};

/* Records (one or two: out has bin_slots() entries) of one segment or
 * triangle of n vertices at xyz, of draw d. */
void bin_one_prim(const struct bin_set *b, const struct scene_draw *d, const float *xyz, int n, const uint8_t rgb[3],
		  struct stage_prim *out);

/* Turns the staged records of a segment or triangle by turn (1 .. N-1):
 * the range shifts by turn mod M (every image stays 0 .. M-1), and the turn
 * goes above the sort key for the scatter to keep (bin_set.prim_turn). */
void bin_turn_prims(const struct bin_set *b, uint32_t turn, struct stage_prim *s);

/* Adds the keys of an item's staged records (slots of them) to a
 * histogram; their turn is masked off. */
static inline void bin_count_keys(uint32_t *hist, const struct stage_prim *s, uint32_t slots)
{
	for (uint32_t i = 0; i < slots; i++)
		if (s[i].key != BIN_KEY_NONE)
			hist[s[i].key & BIN_KEY_MASK]++;
}

/* A staged item's records turned by its draw's turn, and counted. */
static inline void bin_finish_item(const struct bin_set *b, uint32_t turn, struct stage_prim *s, uint32_t *hist)
{
	if (turn)
		bin_turn_prims(b, turn, s);
	bin_count_keys(hist, s, bin_slots(b));
}

/* bin_one_prim() and bin_finish_item() of triangles j0 .. j1 - 1 of d,
 * eight at a time, on a mirrored geometry where the CPU has AVX-512
 * (bin_points_isa_supported(BIN_POINTS_AVX512)); the same records. Returns
 * the first triangle not staged: j0 elsewhere. */
uint64_t bin_stage_tris8(const struct bin_set *b, const struct scene_draw *d, uint64_t j0, uint64_t j1,
			 struct stage_prim *out, uint32_t *hist);

static inline int bin_prim_in_image(const struct bin_set *b, const struct bin_prim *p, uint32_t k)
{
	uint32_t off = k >= p->first ? k - p->first : k + b->images - p->first;
	return off < p->count;
}

#endif
