/* A tiny assertion helper for Spindle's test programs: CHECK() counts and
 * reports, check_done() prints the tally and gives main()'s exit status. */
#ifndef SPINDLE_CHECK_H
#define SPINDLE_CHECK_H

#include <stdio.h>

static int check_passed, check_failed;

/* Reports the first few failures in full; a broken loop shouldn't flood. */
#define CHECK_MSG(cond, ...)                                                        \
	do {                                                                        \
		if (cond) {                                                         \
			check_passed++;                                             \
		} else if (check_failed++ < 25) {                                   \
			fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__,     \
				__LINE__, #cond);                                   \
			fprintf(stderr, __VA_ARGS__);                               \
			fputc('\n', stderr);                                        \
		}                                                                   \
	} while (0)

#define CHECK(cond) CHECK_MSG(cond, "%s", "")

static inline int check_done(void)
{
	printf("%d passed, %d failed\n", check_passed, check_failed);
	return check_failed ? 1 : 0;
}

#endif
