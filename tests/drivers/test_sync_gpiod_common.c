/* The parts of the gpiod sync source that do not depend on its backend,
 * against whichever backend this build has (libgpiod 1: sync_gpiod.c, or 2:
 * sync_gpiod2.c, on the real library either way): the clock picker, and
 * sync_gpiod_create()'s failures. With a gpiochip on the machine, the
 * missing-chip case is skipped. */
#include <errno.h>
#include <glob.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gpiod_create.h"
#include "sync.h"
#include "sync_gpiod_priv.h"

#define NSEC 1000000000LL

static void test_pick_clock(void)
{
	int64_t mono = 1000 * NSEC, real = 1700000000 * NSEC;
	bool sure;
	/* Clocks far apart: any recent edge settles it. */
	CHECK_EQ(sync_gpiod_pick_clock(mono - 1000, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	CHECK(sure);
	CHECK_EQ(sync_gpiod_pick_clock(real - 1000, mono, real, &sure), SYNC_GPIOD_CLOCK_REALTIME);
	CHECK(sure);
	CHECK_EQ(sync_gpiod_pick_clock(mono, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	/* Ahead of both clocks, or negative: no timestamp at all. */
	CHECK_EQ(sync_gpiod_pick_clock(real + 1, mono, real, &sure), SYNC_GPIOD_CLOCK_UNKNOWN);
	CHECK(!sure);
	CHECK_EQ(sync_gpiod_pick_clock(-5, mono, real, &sure), SYNC_GPIOD_CLOCK_UNKNOWN);
	CHECK(!sure);
	/* Just ahead of MONOTONIC: only REALTIME fits, but an edge 1.7e9 s
	 * old is garbage, never the kernel's: nothing settled. */
	CHECK_EQ(sync_gpiod_pick_clock(mono + 1, mono, real, &sure), SYNC_GPIOD_CLOCK_REALTIME);
	CHECK(!sure);
	/* Clocks 50 ms apart (no RTC, before NTP). A MONOTONIC edge is
	 * picked right at any age but never rules REALTIME out... */
	real = mono + 50000000;
	CHECK_EQ(sync_gpiod_pick_clock(mono - 5000000, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	CHECK(!sure);
	CHECK_EQ(sync_gpiod_pick_clock(mono - 5 * NSEC, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	/* ...a young REALTIME edge lies ahead of MONOTONIC: sure... */
	CHECK_EQ(sync_gpiod_pick_clock(real - 5000000, mono, real, &sure), SYNC_GPIOD_CLOCK_REALTIME);
	CHECK(sure);
	/* ...and one older than the clocks' distance is misread, unsure. */
	CHECK_EQ(sync_gpiod_pick_clock(real - 80000000, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	CHECK(!sure);
	/* REALTIME behind MONOTONIC, the mirror case. */
	real = mono - 50000000;
	CHECK_EQ(sync_gpiod_pick_clock(mono - 5000000, mono, real, &sure), SYNC_GPIOD_CLOCK_MONOTONIC);
	CHECK(sure);
}

static void test_create_fails(void)
{
	char log[2048];
	struct sync_gpiod_config cfg = { .chip = "/dev/null", .line = "17" };
	/* Not a GPIO chip at all: libgpiod's ioctl fails. */
	CHECK(create_fails(&cfg, log, sizeof(log)) != 0);
	CHECK_MSG(strstr(log, "/dev/null") && strstr(log, "17"), "log: %s", log);
	memset(&cfg, 0, sizeof(cfg));
	strcpy(cfg.chip, "gpiochip0");
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), EINVAL); /* no line */
	CHECK_EQ(create_fails(NULL, log, sizeof(log)), EINVAL);
	memset(cfg.line, 'x', sizeof(cfg.line)); /* not terminated */
	CHECK_EQ(create_fails(&cfg, log, sizeof(log)), EINVAL);

	glob_t g;
	int chips = glob("/dev/gpiochip*", 0, NULL, &g);
	globfree(&g);
	if (chips == 0) {
		printf("skipped: a GPIO chip exists, no chip is sure to be missing\n");
		return;
	}
	struct sync_gpiod_config missing = { .chip = "gpiochip-spindle-test", .line = "ROTOR_INDEX" };
	CHECK_EQ(create_fails(&missing, log, sizeof(log)), ENOENT);
	CHECK_MSG(strstr(log, "gpiochip-spindle-test") && strstr(log, "ROTOR_INDEX"), "log: %s", log);
	strcpy(missing.chip, "/dev/gpiochip7");
	strcpy(missing.line, "17");
	CHECK_EQ(create_fails(&missing, log, sizeof(log)), ENOENT);
}

int main(void)
{
	int fds = count_fds();
	test_pick_clock();
	test_create_fails();
	CHECK_EQ(count_fds(), fds);
	return check_done();
}
