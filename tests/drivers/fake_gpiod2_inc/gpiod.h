/* <gpiod.h> for code built against the libgpiod 2 fake (tests/drivers/
 * fake_gpiod2.c): this directory goes first on the include path of the test
 * that compiles drivers/sync_gpiod2.c, so that the v2 backend builds and
 * runs on a machine with libgpiod 1 or none. */
#ifndef SPINDLE_FAKE_GPIOD2_INC_GPIOD_H
#define SPINDLE_FAKE_GPIOD2_INC_GPIOD_H

#include "../fake_gpiod2.h"

#endif
