/* daemon/snapshot: where a layer's lift (turn.h) is drawn as a row shift
 * (scene_draw.lift) and where it goes back into the transform: lifted only
 * while every draw's box lies 10 rows inside the image both unlifted and
 * lifted, the calibration does not scale rows, and the renderer takes
 * turns at all; a turn always stays a turn. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "draw.h"
#include "geometry.h"
#include "snapshot.h"
#include "stage.h"

static void on_changed(void *data)
{
	(void)data;
}

static const struct stage_listener listener = { .version = STAGE_LISTENER_VERSION, .changed = on_changed };

/* A triangle from y = lo to y = hi (model space), bounded as draw.c
 * bounds built vertex data. */
static struct vdata *triangle(float lo, float hi, bool finite)
{
	struct vdata *v = calloc(1, sizeof(*v) + 9 * sizeof(float));
	CHECK(v);
	const float xyz[9] = { 0.1f, lo, 0.0f, 0.3f, hi, 0.0f, 0.2f, lo, 0.1f };
	*v = (struct vdata){ .refs = 1, .prim = SCENE_TRIANGLES, .count = 3, .prims = 1 };
	memcpy(v->xyz, xyz, sizeof(xyz));
	v->bounded = finite;
	const float box_lo[3] = { 0.1f, lo, 0.0f }, box_hi[3] = { 0.3f, hi, 0.1f };
	memcpy(v->lo, box_lo, sizeof(box_lo));
	memcpy(v->hi, box_hi, sizeof(box_hi));
	return v;
}

struct one {
	struct stage stage;
	struct list_item item;
	struct draw_array draws;
	struct stage_layer layer;
	struct snapshot snap;
};

static void identity(float m[16])
{
	memset(m, 0, 16 * sizeof(float));
	m[0] = m[5] = m[10] = m[15] = 1;
}

/* A stage of one layer over v: base at height y, lifted lift rows, turned
 * turn images. */
static void one_init(struct one *o, struct vdata *v, double y, int32_t lift, uint32_t turn, const struct geometry *g)
{
	memset(o, 0, sizeof(*o));
	stage_init(&o->stage, &listener, NULL);
	o->item = (struct list_item){ .data = v, .rgba = { 255, 255, 255, 255 } };
	identity(o->item.transform);
	o->draws = (struct draw_array){ .items = &o->item, .count = 1, .cap = 1, .vertices = 3, .prims = 1 };
	link_init(&o->layer.link);
	o->layer.draws = &o->draws;
	o->layer.visible = true;
	identity(o->layer.base);
	o->layer.base[13] = (float)y;
	memcpy(o->layer.transform, o->layer.base, sizeof(o->layer.base));
	o->layer.transform[13] += (float)(lift * 2.0 * g->half_height / g->height);
	o->layer.lift = lift;
	o->layer.turn = turn;
	stage_add(&o->stage, &o->layer);
}

/* The snapshot's one draw. */
static const struct scene_draw *build(struct one *o, const struct geometry *turns, const float *pre)
{
	snapshot_release(&o->snap);
	CHECK_EQ(snapshot_build(&o->snap, &o->stage, UINT64_MAX, turns, pre), 0);
	CHECK_EQ(o->snap.scene.draw_count, 1u);
	return &o->snap.draws[0];
}

static void one_finish(struct one *o)
{
	snapshot_finish(&o->snap);
	stage_remove(&o->layer);
}

int main(void)
{
	struct geometry g;
	CHECK_EQ(geometry_from_profile("small", &g), 0);
	double h = g.half_height, row = 2.0 * h / g.height;
	struct vdata *inside = triangle((float)(-0.5 * h), (float)(0.5 * h), true);
	struct one o;

	/* Well inside: lifted, the base's transform, the turn kept. */
	one_init(&o, inside, 0.1 * h, 7, 3, &g);
	const struct scene_draw *d = build(&o, &g, NULL);
	/* Vertex data is numbered when first drawn, and keeps its number
	 * (scene_draw.data_id); other data gets another. */
	uint64_t id = d->data_id;
	CHECK(id != 0);
	CHECK_EQ(build(&o, &g, NULL)->data_id, id);
	struct vdata *other = triangle((float)(-0.5 * h), (float)(0.5 * h), true);
	o.item.data = other;
	CHECK(build(&o, &g, NULL)->data_id > id);
	o.item.data = inside;
	d = build(&o, &g, NULL);
	CHECK_EQ(d->data_id, id);
	CHECK_EQ(d->lift, 7);
	CHECK_EQ(d->turn, 3);
	CHECK(d->transform[13] == o.layer.base[13]);
	/* The renderer takes no turns: the client's transform as it is. */
	d = build(&o, NULL, NULL);
	CHECK(d->lift == 0 && d->turn == 0);
	CHECK(d->transform[13] == o.layer.transform[13]);
	/* A calibration that scales rows: the move goes back into the
	 * transform (before the calibration's). */
	float pre[16];
	identity(pre);
	pre[5] = 0.9f;
	d = build(&o, &g, pre);
	CHECK(d->lift == 0 && d->turn == 3);
	CHECK(fabs(d->transform[13] - 0.9 * (o.layer.base[13] + 7 * row)) < 1e-6);
	/* One that only moves volume space up: still a shift. */
	identity(pre);
	pre[13] = 0.05f;
	d = build(&o, &g, pre);
	CHECK(d->lift == 7 && fabs(d->transform[13] - (o.layer.base[13] + 0.05)) < 1e-6);
	one_finish(&o);

	/* Lifted to within 10 rows of the top, and 11 rows from it. */
	double top = 0.5 * h; /* the box's top, at base height 0 */
	int32_t room = (int32_t)floor((h - top) / row);
	one_init(&o, inside, 0, room - 9, 0, &g);
	d = build(&o, &g, NULL);
	CHECK_EQ(d->lift, 0);
	CHECK(fabs(d->transform[13] - (room - 9) * row) < 1e-6);
	one_finish(&o);
	one_init(&o, inside, 0, room - 11, 0, &g);
	CHECK_EQ(build(&o, &g, NULL)->lift, room - 11);
	one_finish(&o);
	/* Downwards likewise; and a base already too low. */
	one_init(&o, inside, 0, -(room - 11), 0, &g);
	CHECK_EQ(build(&o, &g, NULL)->lift, -(room - 11));
	one_finish(&o);
	one_init(&o, inside, -(h - 0.5 * h - 5 * row), 2, 0, &g);
	CHECK_EQ(build(&o, &g, NULL)->lift, 0);
	one_finish(&o);

	/* Vertices not all finite: no box, no shift. */
	struct vdata *unbounded = triangle(0, 0.1f, false);
	one_init(&o, unbounded, 0, 4, 0, &g);
	d = build(&o, &g, NULL);
	CHECK(d->lift == 0 && fabs(d->transform[13] - 4 * row) < 1e-6);
	one_finish(&o);

	/* A grid: its box is n times its spacing. */
	struct vgrid grid = { .refs = 1,
			      .grid = { .type = SCENE_GRID_U8, .n = { 4, 8, 4 }, .spacing = { 0.1f, 0.1f, 0.1f } } };
	struct vdata *gv = calloc(1, sizeof(*gv));
	CHECK(gv);
	*gv = (struct vdata){ .refs = 1, .prim = SCENE_GRID, .count = 1, .grid = &grid };
	one_init(&o, gv, -0.4, 5, 0, &g); /* y from -0.4 to 0.4 */
	d = build(&o, &g, NULL);
	CHECK(d->prim == SCENE_GRID && d->lift == 5);
	one_finish(&o);
	grid.grid.n[1] = 9 * (uint32_t)(h / 0.1); /* taller than the volume */
	one_init(&o, gv, -0.4, 5, 0, &g);
	CHECK_EQ(build(&o, &g, NULL)->lift, 0);
	one_finish(&o);

	free(inside);
	free(other);
	free(unbounded);
	free(gv);
	return check_done();
}
