/* Staging, shared by bin.c and the eight-lane triangle staging of
 * bin_tris.c: each segment or triangle is first written as a record and
 * its sort key, and counted; the scatter then moves the records to their
 * sorted places (bin.h). */
#ifndef SPINDLE_BIN_STAGE_H
#define SPINDLE_BIN_STAGE_H

#include <stdint.h>

#include "bin.h"

#define KEY_NONE UINT32_MAX
/* A staged primitive's key holds its sort key (class * M + first) in the
 * low KEY_BITS bits and its turn (mod N) above them: sort keys are below
 * 15 * 16384 < 2^18 (M <= 16384, so at most 15 classes) and turns below
 * N <= 16384 = 2^14, so no key is KEY_NONE. Point keys are images. */
#define KEY_BITS 18
#define KEY_MASK ((1u << KEY_BITS) - 1)
_Static_assert(BIN_MAX_CLASSES * 16384u <= (1u << KEY_BITS) && 16384u <= (1u << (32 - KEY_BITS)),
	       "sort key and turn share a staged key");

/* A record and its sort key (KEY_NONE: unused). */
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
		if (s[i].key != KEY_NONE)
			hist[s[i].key & KEY_MASK]++;
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

#endif
