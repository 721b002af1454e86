/* Fuzz target "session": whole client sessions. The input is raw bytes
 * written to the client ends of socketpairs that an in-process spindled
 * serves, in chunks, with memfds and other fds passed along, and the event
 * loop run between chunks. Checks: no memory error, leak, hang or
 * undefined behaviour anywhere in the daemon (wire layer, dispatch,
 * objects, commit, snapshots, rendering), and no fd left open.
 *
 * Input: chunks until the input ends, each
 *   ctl: u8    bits 0-2: fds passed with the chunk (0-7)
 *              bit 3:    which client (0 or 1; connected when first used)
 *              bit 4:    close that client's socket after the chunk (a
 *                        later chunk for it connects a new one)
 *              bit 5:    do not run the loop after the chunk (chunks
 *                        coalesce)
 *   len: u16   bytes of the chunk
 *   per fd:    kind: u8 (enum fuzz_fd_kind), size: u16, plen: u8, then
 *              plen bytes repeated over a memfd's contents
 *   len bytes
 * fuzz/gen_corpus.py writes valid sessions in this form. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "daemon.h"
#include "harness.h"

#define CLIENTS 2
#define MAX_FDS 7
#define MAX_CONNECTIONS 8 /* per input: each costs a client set-up */

static int make_fd(struct fuzz_input *in)
{
	unsigned kind = fuzz_u8(in) % FUZZ_FD_KINDS;
	uint16_t size = fuzz_u16(in);
	size_t n;
	const uint8_t *pattern = fuzz_bytes(in, fuzz_u8(in), &n);
	if (kind > FUZZ_FD_MEMFD_UNSEALED)
		return fuzz_fd(kind, 0);
	uint8_t *buf = calloc(1, size ? size : 1);
	if (!buf)
		return -1;
	for (size_t i = 0; n && i < size; i++)
		buf[i] = pattern[i % n];
	int fd = fuzz_memfd((enum fuzz_fd_kind)kind, size, buf, size);
	free(buf);
	return fd;
}

struct session {
	struct fuzz_server fs;
	int socks[CLIENTS];
};

/* A full socket: the server reads, and the clients take what it wrote. */
static void pump(void *arg)
{
	struct session *s = arg;
	fuzz_server_run(&s->fs);
	for (int c = 0; c < CLIENTS; c++)
		if (s->socks[c] >= 0)
			fuzz_drain(s->socks[c]);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_input in = { data, size, 0 };
	struct session s = { .socks = { -1, -1 } };
	struct fuzz_server *fs = &s.fs;
	int *socks = s.socks;
	unsigned connections = 0;
	struct fuzz_resources before;
	fuzz_resources_take(&before);

	fuzz_server_start(fs, NULL);
	while (!fuzz_done(&in)) {
		uint8_t ctl = fuzz_u8(&in);
		uint16_t len = fuzz_u16(&in);
		int fds[MAX_FDS];
		unsigned n_fds = 0;
		for (unsigned i = 0; i < (ctl & 7u); i++) {
			int fd = make_fd(&in);
			if (fd >= 0)
				fds[n_fds++] = fd;
		}
		size_t n;
		const uint8_t *bytes = fuzz_bytes(&in, len, &n);
		int *sock = &socks[(ctl >> 3) & 1];
		if (*sock < 0 && connections < MAX_CONNECTIONS) {
			*sock = fuzz_server_connect(fs);
			connections++;
		}
		if (*sock >= 0 && (n || n_fds) && fuzz_send(*sock, bytes, n, fds, n_fds, pump, &s) < 0) {
			close(*sock); /* the server closed it */
			*sock = -1;
		}
		for (unsigned i = 0; i < n_fds; i++)
			close(fds[i]);
		if (*sock >= 0 && (ctl & 0x10)) {
			close(*sock);
			*sock = -1;
		}
		if (!(ctl & 0x20))
			fuzz_server_run(fs);
		for (int c = 0; c < CLIENTS; c++) {
			if (socks[c] >= 0 && !fuzz_drain(socks[c])) {
				close(socks[c]);
				socks[c] = -1;
			}
		}
	}
	for (int c = 0; c < CLIENTS; c++)
		if (socks[c] >= 0)
			close(socks[c]);
	fuzz_server_run(fs);
	fuzz_server_stop(fs);

	fuzz_resources_check(&before);
	return 0;
}
