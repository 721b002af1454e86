/* Shared by the fuzz targets (docs/fuzzing.md): reading the input as
 * numbers, the file descriptors an input may pass, sending on sockets, and
 * the checks every target makes. daemon.h has the in-process spindled. */
#ifndef SPINDLE_FUZZ_HARNESS_H
#define SPINDLE_FUZZ_HARNESS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* libFuzzer's entry point, which every target defines. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The input, consumed from the front. Past its end every number reads as
 * 0 and every byte string as empty. */
struct fuzz_input {
	const uint8_t *data;
	size_t size, pos;
};

static inline bool fuzz_done(const struct fuzz_input *in)
{
	return in->pos >= in->size;
}

uint8_t fuzz_u8(struct fuzz_input *in);
uint16_t fuzz_u16(struct fuzz_input *in);
uint32_t fuzz_u32(struct fuzz_input *in);
uint64_t fuzz_u64(struct fuzz_input *in);
/* Numbers as the targets' structured inputs write them: one byte below
 * 0x80 is that value; 0x80-0xfe is followed by a u32 (u64) taken whole;
 * 0xff is all ones. Small values cost one byte, any value is reachable. */
uint32_t fuzz_num(struct fuzz_input *in);
uint64_t fuzz_num64(struct fuzz_input *in);
/* Up to max bytes of the input (fewer at its end); *n gets their count. */
const uint8_t *fuzz_bytes(struct fuzz_input *in, size_t max, size_t *n);

/* The kinds of file descriptor an input may pass (fuzz_fd()). */
enum fuzz_fd_kind {
	FUZZ_FD_MEMFD_SEALED,    /* sealed against shrinking: a valid buffer */
	FUZZ_FD_MEMFD_ALL_SEALS, /* shrink, grow, write and seal */
	FUZZ_FD_MEMFD_UNSEALED,
	FUZZ_FD_PIPE, /* the read end of an empty pipe */
	FUZZ_FD_SOCKET,
	FUZZ_FD_DEV_NULL,
	FUZZ_FD_KINDS
};

/* A memfd of size bytes starting with data (len bytes, the rest zero),
 * sealed as kind says (one of the MEMFD kinds). -errno on failure. */
int fuzz_memfd(enum fuzz_fd_kind kind, uint64_t size, const void *data, size_t len);
/* A new fd of the kind (kind % FUZZ_FD_KINDS); memfds hold size zero
 * bytes. -errno on failure. */
int fuzz_fd(unsigned kind, uint64_t size);

/* The open fds and the threads of this process, taken before an input and
 * checked after it: an input leaves none behind. */
struct fuzz_resources {
	int fds, threads;
};
void fuzz_resources_take(struct fuzz_resources *r);
/* Aborts if there are more or fewer fds or threads than in before. */
void fuzz_resources_check(const struct fuzz_resources *before);
/* Whether SPINDLE_FUZZ_VERBOSE is set: targets say what they do, and the
 * daemon logs at its info level. */
bool fuzz_verbose(void);
/* Aborts with the message (what the fuzzer reports as a crash). */
void fuzz_fail(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));

/* Writes all of data to a socket, the n_fds fds (at most 64) with its
 * first byte, calling pump(arg) whenever the socket is full (pump makes the
 * peer read). 0 or -errno (-EPIPE: the peer closed it; -EAGAIN: still full
 * after many pumps). */
int fuzz_send(int sock, const void *data, size_t len, const int *fds, unsigned n_fds, void (*pump)(void *), void *arg);
/* Reads and drops what the server sent on sock; returns false once the
 * server has closed it. */
bool fuzz_drain(int sock);

#endif
