/* The assertion helper of every Spindle test program. A failed check
 * reports where and exits 1 at once (later code may rely on what it
 * checked), whatever the build's NDEBUG; check_done() prints the closing
 * "N passed, 0 failed" line and gives main()'s exit status. */
#ifndef SPINDLE_TEST_CHECK_H
#define SPINDLE_TEST_CHECK_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>

static int check_passed;

#define CHECK_MSG(cond, ...)                                                                                   \
	do {                                                                                                   \
		if (cond) {                                                                                    \
			check_passed++;                                                                        \
		} else {                                                                                       \
			fprintf(stderr, "%s:%d: %s: CHECK(%s) failed: ", __FILE__, __LINE__, __func__, #cond); \
			fprintf(stderr, __VA_ARGS__);                                                          \
			fprintf(stderr, "\n%d passed, 1 failed\n", check_passed);                              \
			exit(1);                                                                               \
		}                                                                                              \
	} while (0)

#define CHECK(cond) CHECK_MSG(cond, "%s", "")

#define CHECK_EQ(a, b)                                                                                 \
	do {                                                                                           \
		long long check_a_ = (long long)(a), check_b_ = (long long)(b);                        \
		CHECK_MSG(check_a_ == check_b_, "%s == %s: %lld != %lld", #a, #b, check_a_, check_b_); \
	} while (0)

static inline int check_done(void)
{
	printf("%d passed, 0 failed\n", check_passed);
	return 0;
}

/* Open fds of this process, to check that objects close what they open. */
static inline int count_fds(void)
{
	DIR *d = opendir("/proc/self/fd");
	int n = 0;
	if (!d)
		return -1;
	while (readdir(d))
		n++;
	closedir(d);
	return n;
}

#endif
