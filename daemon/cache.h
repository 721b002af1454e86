/* The object cache and compositor (docs/design.md section 5: the seed thesis'
 * automatic impostors, in volume form).
 *
 * Each object of a scene (a layer: its list placed by its transform, struct
 * scene_object) has an entry that follows it from volume to volume through
 * the thesis' states:
 *
 * - analyse: the entry counts the volumes in a row the object came
 *   unchanged (draw for draw the same vertex data, by identity, transform,
 *   colour and point size), in a saturating counter;
 * - create: once that count says reuse is likely (or at once when it
 *   changes but its last cached volume paid), the object is rendered on
 *   its own and its volume kept, run-length coded (compose.h);
 * - use: while it stays unchanged the volume is composed from the entry
 *   and the object is not rendered; an object that only turns about the
 *   axis by whole images or moves along it by whole rows (its layer's turn
 *   and lift, turn.h, scene_draw.turn and .lift) is composed from its
 *   canvas, its render unturned and unlifted before the halftone, which
 *   compose_turned() shifts to the turn and lift and halftones at each
 *   image's own phase (made once, when the object is seen moving so, by a
 *   renderer that renders canvases: the CPU renderer);
 * - idle: a changed object loses its volume; if that volume did not pay
 *   (not a single hit), the object must stay unchanged longer before
 *   it is cached again (a saturating back-off that doubles the wait, and
 *   wears off by one each time a cached volume pays), so an object that
 *   keeps changing stops being cached; the budget's evictions back off the
 *   same way; an object gone from the scene for a while loses its entry.
 *
 * The volume shown is the OR of the cached volumes and the render of every
 * object not composed from the cache (compose.h says why that is exact:
 * bit for bit the renderer's render of the whole scene). The cache makes
 * each composition in the volume it hands out, by patching
 * (compose_patch()) the composition that volume already holds: a volume
 * handed out before (the pipeline passes a few round) is known by its
 * origin mark (volume.h), and it is composed anew only where the
 * compositions since changed: where an object left (changed, hidden,
 * gone, evicted), where the objects rendered were and now are, and where
 * a cached object came back. So a change costs the tiles it touches in
 * each volume it reaches. An unknown volume is composed whole.
 * Many small objects to cache at once are rendered side by side on the
 * pool's workers (batch.h).
 *
 * A calibration's axis offset (cache_set_offset()) moves every volume by
 * whole pixels after the halftone (volume_shift()). Moving commutes with
 * the OR, so the cache moves each part it renders (the rest, a new
 * entry's volume, the turned objects) and keeps its entries moved: the
 * compositions are made and patched moved, as without one, and a volume
 * rendered whole is moved after. A new offset drops the entries' volumes
 * (their canvases, unmoved, stay).
 *
 * Entries stay within a byte budget (cache_set_budget()): past it the
 * least recently used entries lose their volumes and canvases. The cache
 * never composes volumes of two engines (render_stats.engine): a scene a
 * GL renderer would hand to its CPU fallback (a turn, too many primitives)
 * is rendered whole, and so is one where a part went to it (grids over the
 * GL renderer's texture budget). The cache is driven from the
 * daemon's loop (cache_plan(), cache_done()) and runs its renders and
 * compositions on the render thread (cache_render()), never both at once. */
#ifndef SPINDLE_CACHE_H
#define SPINDLE_CACHE_H

#include <stdbool.h>
#include <stdint.h>

#include "cache_stats.h"
#include "geometry.h"

struct pool;
struct renderer;
struct scene;
struct snapshot;
struct tile_set;
struct volume;

struct cache;

/* A cache for volumes of geom, holding at most budget bytes. pool (may be
 * NULL) runs the compositions, and renders small new entries side by side
 * where the renderer has a serial form (batch.h); it stays the caller's
 * and must outlive the cache. turns: the renderer renders canvases (renderer_impl.render_canvas),
 * so an object that only turns about the axis by whole images is composed
 * from its canvas, turned. NULL + errno. */
struct cache *cache_create(const struct geometry *geom, uint64_t budget, struct pool *pool, bool turns);
/* Accepts NULL. */
void cache_destroy(struct cache *c);

/* The axis offset (calibration.h) every volume is to be moved by, from
 * the next plan on (the loop's thread, before cache_plan()): du columns
 * and dv rows, as volume_shift() moves. A change drops every entry's
 * volume (made moved by the last), as a change of the object would: the
 * next composition renders them and composes anew where they were and
 * where they now are. */
void cache_set_offset(struct cache *c, int32_t du, int32_t dv);
/* Before a render (the loop's thread): decides, object by object of snap,
 * whether it is composed from its entry, rendered into a new one, or
 * rendered with the rest. Takes references to the vertex data of the
 * objects it follows. 0, or -ENOMEM: then cache_render() renders the
 * whole scene as it is. */
int cache_plan(struct cache *c, const struct snapshot *snap);
/* The render (the render thread): renders with r what the plan says and
 * composes the result into out. scene is the planned snapshot's. 0 or
 * negative errno (out is then unusable). */
int cache_render(struct cache *c, struct renderer *r, const struct scene *scene, struct volume *out);
/* After the render (the loop's thread): takes the new entries in, or, when
 * result < 0, forgets what the render was to make; keeps the budget. */
void cache_done(struct cache *c, int result);
/* Forgets, now, the objects missing from the last plan whose draws' data
 * only the cache still holds (the loop's thread, outside a plan and its
 * render: once the scene before it is released). No scene can draw that
 * data again, and waiting for IDLE_VOLUMES more plans would keep it (a
 * gone client's volume, say) as long as the display stays idle. */
void cache_forget_orphans(struct cache *c);
/* Marks in differ (empty, of the volumes' tiling) the tiles where volumes a
 * and b may differ, when each is a volume the cache handed out, unchanged
 * since (its origin mark), holding one of its last compositions: where
 * objects cached changed between the two, and where what was rendered
 * with them lit in either (as a volume handed back is patched); tiles
 * outside are equal. Whether it could (differ untouched when not). The
 * loop's thread, between renders: an upload's delta need not compare the
 * rest. */
bool cache_may_differ(const struct cache *c, const struct volume *a, const struct volume *b, struct tile_set *differ);

void cache_get_stats(const struct cache *c, struct cache_stats *out);
/* A new budget (the loop's thread): new entries are made only within it,
 * and the cache evicts down to it when the next render is planned and
 * done. */
void cache_set_budget(struct cache *c, uint64_t bytes);

#endif
