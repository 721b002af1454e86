/* The device suite: spindled on the simulated device at the small profile,
 * with the projector's link rate and the simulated faults of sim-faults
 * (spindled.8): what reaches the projector (deltas, underruns) and the
 * safety rules around the rotor and the projector (stall, jitter, unplug).
 * Usage: test-devices NAME. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "projwire.h"
#include "scenes.h"
#include "volume_diff.h"

/* A small sphere moving past a large one: each volume is sent as a delta
 * against the free buffer's content, the volume two back, and costs
 * exactly the projector protocol's delta of the two (computed here from
 * captures); about as large a share of the whole as the share of tiles
 * that changed. An unchanged scene sends nothing. */
static void test_delta(void)
{
	struct daemon d;
	daemon_start(&d);
	struct spindle *sp = client_connect(&d);
	static float big[48 * 24 * 18], ball[24 * 12 * 18];
	struct spindle_frame f;
	show_triangles(sp, &f, big, sphere(big, 0.85, 48, 24), 0, 0, 255);
	struct spindle_layer *layer = show_triangles(sp, &f, ball, sphere(ball, 0.16, 24, 12), 255, 0, 0);
	struct volume *shown[8];
	for (int i = 0; i < 8; i++) {
		struct spindle_status before = status_of(sp);
		float m[16];
		shift_x(m, 0.1f + 0.08f * (float)i);
		CHECK(spindle_layer_set_transform(layer, m) == 0);
		CHECK(spindle_commit_and_wait(sp, &f) == 0);
		shown[i] = capture_volume(sp);
		uint64_t sent = status_of(sp).bytes_uploaded - before.bytes_uploaded;
		if (i < 3)
			continue; /* until every buffer holds a volume of this scene */
		const struct volume *base = shown[i - 2];
		size_t whole = projwire_volume_size(shown[i]);
		struct projwire_delta plan = { 0 };
		size_t size;
		CHECK(projwire_upload_plan(shown[i], base, NULL, &plan, &size) == 0);
		CHECK_EQ(sent, size);
		CHECK(plan.delta);
		projwire_delta_free(&plan);
		double tiles = (double)volume_differences(shown[i], base, NULL, NULL, NULL) /
			       (double)volume_tile_count(shown[i]);
		double bytes = (double)sent / (double)whole;
		printf("volume %d: %.1f%% of %llu tiles changed, %llu of %zu bytes sent (%.1f%%)\n", i, 100 * tiles,
		       (unsigned long long)volume_tile_count(shown[i]), (unsigned long long)sent, whole, 100 * bytes);
		CHECK(tiles > 0.05 && tiles < 0.2);
		CHECK(bytes < tiles * 1.1 + 0.01);
	}
	struct spindle_status before = status_of(sp);
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	CHECK_EQ(status_of(sp).bytes_uploaded, before.bytes_uploaded);
	for (int i = 0; i < 8; i++)
		volume_destroy(shown[i]);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* A daemon with config, a client, and an axis line shown: the projector
 * is lit from here on. */
static struct spindle *start_lit(struct daemon *d, const char *config)
{
	daemon_start_config(d, config);
	struct spindle *sp = client_connect(d);
	static float axis[6];
	show_vertices(sp, 1, axis, axis_line(axis), 255, 255, 255);
	return sp;
}

/* The big sphere shown on a lit projector, by a daemon with this config;
 * its frame, the time it was committed, and what was shown. */
static struct volume *show_big_sphere(const char *config, struct spindle_frame *f, uint64_t *committed,
				      struct spindle_status *st)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, config);
	static float big[48 * 24 * 18];
	uint32_t n = sphere(big, 0.85, 48, 24);
	struct spindle_status before = status_of(sp);
	*committed = mono_ns();
	show_triangles(sp, f, big, n, 0, 0, 255);
	struct volume *vol = capture_volume(sp);
	*st = status_of(sp);
	st->underruns -= before.underruns;
	spindle_disconnect(sp);
	daemon_stop(&d);
	return vol;
}

/* A volume that takes 1.5 revolutions to cross the link misses the
 * revolution start after its swap request (one underrun), and is shown
 * later and whole: bit for bit what an unlimited link shows. */
static void test_underrun(void)
{
	struct spindle_frame f;
	uint64_t committed;
	struct spindle_status st;
	struct volume *ref = show_big_sphere("sim-link-rate = 0\n", &f, &committed, &st);
	CHECK_EQ(st.underruns, 0);
	struct geometry g = small();
	double period = 60.0 / g.rpm;
	uint64_t rate = (uint64_t)((double)projwire_volume_size(ref) / (1.5 * period));
	char config[64];
	snprintf(config, sizeof(config), "sim-link-rate = %llu\n", (unsigned long long)rate);
	struct volume *late = show_big_sphere(config, &f, &committed, &st);
	printf("link %llu bytes/s: shown %.1f ms after the commit, %llu underruns\n", (unsigned long long)rate,
	       (double)(f.time_ns - committed) / 1e6, (unsigned long long)st.underruns);
	CHECK_EQ(st.underruns, 1);
	CHECK((double)(f.time_ns - committed) >= 1.5 * period * 1e9);
	CHECK_EQ(volume_differences(late, ref, NULL, NULL, NULL), 0);
	CHECK_EQ(volume_tile_count(late), volume_tile_count(ref));
	volume_destroy(ref);
	volume_destroy(late);
}

/* Polls status for ms milliseconds: never lit while unlocked. Returns
 * whether it saw the projector dark, and (if lit_again) lit again. */
static void watch_light(struct spindle *sp, int ms, bool *dark, bool *relit)
{
	uint64_t end = mono_ns() + (uint64_t)ms * 1000000u;
	while (mono_ns() < end) {
		struct spindle_status st = status_of(sp);
		CHECK_MSG(st.blanked || st.locked, "lit while unlocked");
		if (st.blanked)
			*dark = true;
		else if (*dark)
			*relit = true;
		struct timespec ts = { 0, 2000000 };
		nanosleep(&ts, NULL);
	}
}

/* The number after key in the daemon's log, or -1. */
static double log_number(struct daemon *d, const char *key)
{
	FILE *f = fopen(d->log, "r");
	char line[1024];
	double v = -1;
	while (f && fgets(line, sizeof(line), f)) {
		const char *p = strstr(line, key);
		if (p)
			v = atof(p + strlen(key));
	}
	if (f)
		fclose(f);
	return v;
}

/* The rotor stops dead 1.5 s after start and turns again 1 s later: the
 * projector goes dark within 2 revolution periods of the last true index
 * pulse (the simulated projector measures it against the true rotor), is
 * never lit while unlocked, is lit again after the restart, and what is
 * committed meanwhile is shown once it is. */
static void test_stall(void)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, "sim-faults = stall=1.5+1.0/0.2\n");
	bool dark = false, relit = false;
	watch_light(sp, 2800, &dark, &relit);
	CHECK(dark && relit);
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	spindle_disconnect(sp);
	daemon_stop_keep_log(&d);
	double stalls = log_number(&d, "simulated projector: ");
	double delay = log_number(&d, "dark at most ");
	printf("stalls %.0f, dark %.2f periods after the last true index pulse\n", stalls, delay);
	CHECK(stalls == 1 && delay > 0 && delay < 2.0);
	CHECK_EQ(log_number(&d, "ms while stopped and "), 0);
	daemon_remove_files(&d);
}

/* 0.1 % period jitter on the index pulse: the daemon lights once its fit
 * has settled, and the simulated projector's slice angle error stays
 * under a quarter of a slice (status reports it, with the jitter). */
static void test_jitter(void)
{
	struct daemon d;
	struct spindle *sp = start_lit(&d, "sim-faults = jitter=0.001,seed=7\n");
	struct timespec ts = { 3, 0 };
	nanosleep(&ts, NULL);
	struct spindle_status st = status_of(sp);
	struct geometry g = small();
	double period_us = 60e6 / g.rpm;
	printf("jitter %.1f us (%.3f%% of a period), index error %.1f us, slice angle error p99 %.3f max %.3f\n",
	       st.jitter_us, 100 * st.jitter_us / period_us, st.index_error_us, st.angle_error_p99, st.angle_error_max);
	CHECK(st.locked && !st.blanked);
	/* RMS over the last 16 periods: a small sample of a 0.1 % spread. */
	CHECK(st.jitter_us > 0.0002 * period_us && st.jitter_us < 0.003 * period_us);
	CHECK(st.index_error_us > 0);
	CHECK(st.angle_error_p99 >= 0 && st.angle_error_p99 < 0.25);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* The simulated projector is unplugged four times for 0.3 s: status
 * answers throughout and says it is gone (and dark), the daemon sets the
 * new one up and lights it within 2 s of each re-plug, and a commit made
 * while it is away is shown, whole, once it is back. */
static void test_unplug(void)
{
	struct daemon d;
	struct spindle *sp =
		start_lit(&d, "sim-faults = unplug=1.0+0.3,unplug=1.8+0.3,unplug=2.6+0.3,unplug=3.4+0.3\n");
	int gone = 0, back = 0;
	uint64_t gone_at = 0, end = mono_ns() + 4200000000u, worst = 0;
	bool present = true;
	while (mono_ns() < end) {
		struct spindle_status st = status_of(sp);
		CHECK_MSG(st.blanked || (st.locked && st.projector_present), "lit while unlocked or absent");
		if (present && !st.projector_present) {
			gone++, gone_at = mono_ns();
			CHECK(spindle_commit(sp) == 0); /* shown once it is back */
		} else if (!present && st.projector_present) {
			back++;
		}
		present = st.projector_present;
		if (gone_at && present && !st.blanked) {
			uint64_t t = mono_ns() - gone_at;
			worst = t > worst ? t : worst;
			gone_at = 0;
		}
		struct timespec ts = { 0, 2000000 };
		nanosleep(&ts, NULL);
	}
	printf("unplugged %d times, back %d; lit again at most %.0f ms after the unplug (0.3 s away)\n", gone, back,
	       worst / 1e6);
	CHECK(gone == 4 && back == 4 && present);
	CHECK(worst > 0 && worst < 2300000000u); /* gone is seen a poll late: no lower bound */
	struct spindle_frame f;
	CHECK(spindle_commit_and_wait(sp, &f) == 0);
	check_shows_axis_line(sp);
	CHECK(daemon_alive(&d));
	spindle_disconnect(sp);
	daemon_stop(&d);
}

/* No projector when the daemon starts ("unplug=0+0.5"): it starts and
 * serves anyway, says the projector is missing, and shows what was
 * committed once one is plugged in. */
static void test_late_projector(void)
{
	struct daemon d;
	daemon_start_config(&d, "sim-faults = unplug=0+0.5\n");
	struct spindle *sp = client_connect(&d);
	struct spindle_status st = status_of(sp);
	CHECK(!st.projector_present && st.blanked);
	static float v[6];
	uint64_t t0 = mono_ns();
	show_vertices(sp, 1, v, axis_line(v), 255, 255, 255);
	printf("shown %.0f ms after the commit, the projector arriving 500 ms after start\n", (mono_ns() - t0) / 1e6);
	st = status_of(sp);
	CHECK(st.projector_present && !st.blanked);
	check_shows_axis_line(sp);
	spindle_disconnect(sp);
	daemon_stop(&d);
}

static const struct named_test tests[] = {
	{ "delta", test_delta },   { "underrun", test_underrun }, { "stall", test_stall },
	{ "jitter", test_jitter }, { "unplug", test_unplug },     { "late-projector", test_late_projector },
};

int main(int argc, char **argv)
{
	return run_named_tests(tests, sizeof(tests) / sizeof(tests[0]), argc, argv);
}
