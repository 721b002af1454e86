/* daemon/stage: what it shows and in which order (priority, then age),
 * the exclusive owner, removal, and that every change reaches the
 * listener through stage_changed() only. */
#include <string.h>

#include "check.h"
#include "stage.h"

static int changes;

static void on_changed(void *data)
{
	changes++;
}

static const struct stage_listener listener = { .version = STAGE_LISTENER_VERSION, .changed = on_changed };

static const struct draw_array some_draws = { .prims = 1 };

static void layer_init(struct stage_layer *y, const void *owner, int32_t priority)
{
	memset(y, 0, sizeof(*y));
	link_init(&y->link);
	y->owner = owner;
	y->visible = true;
	y->draws = &some_draws;
	y->priority = priority;
}

/* The layers stage_shown_layers() gives, as indices into ys. */
static int shown(const struct stage *s, const struct stage_layer *ys, int *out)
{
	static const struct stage_layer **layers;
	static uint32_t cap;
	int n = stage_shown_layers(s, &layers, &cap);
	CHECK(n >= 0);
	for (int i = 0; i < n; i++)
		out[i] = (int)(layers[i] - ys);
	return n;
}

static void test_order(void)
{
	struct stage s;
	stage_init(&s, &listener, NULL);
	int a, b;
	struct stage_layer ys[5];
	layer_init(&ys[0], &a, 0);
	layer_init(&ys[1], &b, 5);
	layer_init(&ys[2], &a, 5);
	layer_init(&ys[3], &b, -3);
	layer_init(&ys[4], &b, 0);
	for (int i = 0; i < 5; i++)
		stage_add(&s, &ys[i]);
	CHECK(ys[0].serial < ys[1].serial && ys[3].serial < ys[4].serial);
	int out[5];
	/* Highest priority first; of equal ones, the one added first. */
	CHECK_EQ(shown(&s, ys, out), 5);
	int want[] = { 1, 2, 0, 4, 3 };
	for (int i = 0; i < 5; i++)
		CHECK_EQ(out[i], want[i]);
	/* Hidden, or without a list: not shown. */
	ys[1].visible = false;
	ys[4].draws = NULL;
	CHECK_EQ(shown(&s, ys, out), 3);
	CHECK_EQ(out[0], 2);
	CHECK_EQ(out[1], 0);
	CHECK_EQ(out[2], 3);
	CHECK(stage_exclusive_owner(&s) == NULL);
}

static void test_exclusive_and_removal(void)
{
	struct stage s;
	stage_init(&s, &listener, NULL);
	int a, b;
	struct stage_layer ys[3];
	layer_init(&ys[0], &a, 0);
	layer_init(&ys[1], &b, 9);
	layer_init(&ys[2], &b, 0);
	for (int i = 0; i < 3; i++)
		stage_add(&s, &ys[i]);
	/* An exclusive layer with no list still shows its owner alone. */
	ys[2].exclusive = true;
	ys[2].draws = NULL;
	CHECK(stage_exclusive_owner(&s) == &b);
	int out[3];
	CHECK_EQ(shown(&s, ys, out), 1);
	CHECK_EQ(out[0], 1);
	/* Hidden, it is not exclusive. */
	ys[2].visible = false;
	CHECK(stage_exclusive_owner(&s) == NULL);
	CHECK_EQ(shown(&s, ys, out), 2);
	ys[2].visible = true;

	/* Removal says whether the scene changed; a second removal is harmless. */
	changes = 0;
	CHECK(stage_remove(&ys[2]));  /* exclusive: the others come back */
	CHECK(!stage_remove(&ys[2])); /* off the stage already */
	CHECK(stage_exclusive_owner(&s) == NULL);
	CHECK_EQ(shown(&s, ys, out), 2);
	ys[0].visible = false;
	CHECK(!stage_remove(&ys[0])); /* showed nothing */
	CHECK(stage_remove(&ys[1]));
	CHECK_EQ(shown(&s, ys, out), 0);
	CHECK_EQ(changes, 0); /* the caller decides when to say so */
	stage_changed(&s);
	CHECK_EQ(changes, 1);
}

int main(void)
{
	test_order();
	test_exclusive_and_removal();
	return check_done();
}
