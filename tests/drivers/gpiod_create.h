/* For the gpiod sync source's tests: sync_gpiod_create() run to fail, with
 * what it logs captured. */
#ifndef SPINDLE_TEST_GPIOD_CREATE_H
#define SPINDLE_TEST_GPIOD_CREATE_H

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include "check.h"
#include "sync.h"

/* Runs create(cfg) with stderr captured into log; returns its errno. */
static inline int create_fails(const struct sync_gpiod_config *cfg, char *log, size_t size)
{
	int p[2], saved = dup(2);
	CHECK(saved >= 0);
	CHECK_EQ(pipe2(p, O_CLOEXEC | O_NONBLOCK), 0);
	fflush(stderr);
	dup2(p[1], 2);
	errno = 0;
	struct sync_source *s = sync_gpiod_create(cfg);
	int err = errno;
	fflush(stderr);
	dup2(saved, 2);
	close(saved);
	close(p[1]);
	ssize_t n = read(p[0], log, size - 1);
	log[n > 0 ? n : 0] = '\0';
	close(p[0]);
	CHECK(!s);
	return err;
}

#endif
