/* Fuzz target "framing": the wire layer (proto/wire.c) and the generated
 * codec (spindle-protocol.c), without a daemon. The input's bytes and fds
 * go through a socketpair into proto_conn_read() / proto_conn_next(); each
 * message is decoded by one of the generated dispatchers (picked by its
 * object id: every interface's requests and events), whose handlers send
 * the decoded arguments again with the generated senders (the writer side).
 * Checks, besides memory errors, leaks and undefined behaviour:
 * - errors come with a code and a reason; no fd is leaked;
 * - a message that decodes comes back from the writer with the same
 *   header (object, opcode, fd count, size), it decodes again, and encoding
 *   that gives the same bytes (the writer's output is canonical: padding is
 *   zeroed, which a received message's need not be).
 *
 * Input: version: u8 (1 + v % 3: a version past the newest too), then
 * chunks until the input ends, each
 *   ctl: u8   bits 0-4: fds sent with the chunk (0-31: past what one
 *             connection may queue); bits 5-6: the kind of the first
 *             (enum fuzz_fd_kind, the next ones cycle); bit 7: do not read
 *             after this chunk (chunks coalesce)
 *   len: u16, then len bytes (the fds go with the first byte: a chunk of
 *             no bytes passes none).
 * The writer end is closed at the end: a message cut short stays partial. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "echo.h"
#include "harness.h"

#define MAX_OUT (1u << 20)
/* Echoes queued before they are read back and compared: what the
 * socketpair holds, sent in one flush. */
#define MAX_PENDING 64
#define MAX_PENDING_BYTES (64u << 10)

struct header {
	uint32_t object;
	uint16_t opcode, fd_count;
	uint32_t size;
};

struct framing {
	uint32_t version;
	int sock;              /* the input's end */
	struct proto_conn *in; /* reads the input */
	/* Echoes of the input's messages: written to echo_out, read back
	 * from echo_in; those echoed again go through echo2_*. */
	struct proto_conn *echo_out, *echo_in, *echo2_out, *echo2_in;
	struct header pending[MAX_PENDING];
	unsigned n_pending;
	bool broken; /* the input connection hit a framing error */
};

static void conn_pair(struct proto_conn **out, struct proto_conn **in)
{
	int sv[2];
	if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0, sv) < 0)
		fuzz_fail("socketpair: %s", strerror(errno));
	*out = proto_conn_create(sv[0], MAX_OUT);
	*in = proto_conn_create(sv[1], MAX_OUT);
	if (!*out || !*in)
		fuzz_fail("proto_conn_create: %s", strerror(errno));
}

static void check_error(const struct proto_error *err, const char *what)
{
	if (err->code < PROTO_ERR_OBJECT || err->code > PROTO_ERR_NO_MEMORY || !err->text[0])
		fuzz_fail("%s: error code %u, reason '%s'", what, err->code, err->text);
}

static struct header header_of(const struct proto_message *m)
{
	return (struct header){ m->object, m->opcode, m->fd_count, m->size };
}

static bool same_header(struct header a, struct header b)
{
	return a.object == b.object && a.opcode == b.opcode && a.fd_count == b.fd_count && a.size == b.size;
}

static unsigned route_of(uint32_t object)
{
	return object % echo_route_count;
}

/* Sends everything queued on out (the peer's socket buffer holds it: the
 * callers read it back before queueing more than a few messages). */
static void flush(struct proto_conn *out)
{
	int r = proto_conn_flush(out);
	if (r < 0)
		fuzz_fail("flush: %s", strerror(-r));
}

/* The next message on in, which must be there. */
static void next_echo(struct proto_conn *in, struct proto_message *m, const char *what)
{
	struct proto_error err = { 0 };
	for (int tries = 0; tries < 2; tries++) {
		int r = proto_conn_next(in, m, &err);
		if (r == 1)
			return;
		if (r < 0)
			fuzz_fail("%s: %s", what, err.text);
		r = proto_conn_read(in, &err);
		if (r < 0)
			fuzz_fail("%s: read: %s", what, r == -EPROTO ? err.text : strerror(-r));
	}
	fuzz_fail("%s: missing", what);
}

/* An echo e of an input message: decodes again, and encodes to the same
 * bytes. */
static void check_echo(struct framing *f, struct proto_message *e, struct header expect)
{
	if (!same_header(header_of(e), expect))
		fuzz_fail("echo of object %u opcode %u: header %u/%u/%u/%u, expected size %u, %u fds", expect.object,
			  expect.opcode, e->object, e->opcode, e->fd_count, e->size, expect.size, expect.fd_count);
	struct echo_target t = { .out = f->echo2_out, .id = e->object };
	struct proto_error err = { 0 };
	int r = echo_dispatch(route_of(e->object), &t, e, f->version, &err);
	if (r < 0 || !t.handled || t.error < 0)
		fuzz_fail("echo of object %u opcode %u (%s) does not decode again: %d %d %s", e->object, e->opcode,
			  echo_route_name(route_of(e->object)), r, t.error, err.text);
	flush(f->echo2_out);
	struct proto_message e2;
	next_echo(f->echo2_in, &e2, "second echo");
	if (!same_header(header_of(&e2), header_of(e)) || memcmp(e2.body, e->body, e->body_size) != 0)
		fuzz_fail("object %u opcode %u: encoding is not canonical", e->object, e->opcode);
}

/* Reads back the echoes queued, in order. */
static void check_pending(struct framing *f)
{
	if (!f->n_pending)
		return;
	flush(f->echo_out);
	for (unsigned i = 0; i < f->n_pending; i++) {
		struct proto_message e;
		next_echo(f->echo_in, &e, "echo");
		check_echo(f, &e, f->pending[i]);
	}
	f->n_pending = 0;
	if (proto_conn_has_partial(f->echo_in) || proto_conn_has_partial(f->echo2_in))
		fuzz_fail("bytes left over after the echoes");
}

static void handle(struct framing *f, struct proto_message *m)
{
	struct echo_target t = { .out = f->echo_out, .id = m->object };
	struct proto_error err = { 0 };
	struct header h = header_of(m);
	if (proto_conn_pending_out(f->echo_out) + m->size > MAX_PENDING_BYTES)
		check_pending(f);
	int r = echo_dispatch(route_of(m->object), &t, m, f->version, &err);
	if (fuzz_verbose())
		fprintf(stderr, "object %u opcode %u, %u bytes, %u fds, as %s: %s\n", m->object, m->opcode, m->size,
			m->fd_count, echo_route_name(route_of(m->object)), r < 0 ? err.text : "echoed");
	if (r < 0) {
		if (r != -EPROTO || t.handled)
			fuzz_fail("dispatch returned %d, handled %d", r, t.handled);
		check_error(&err, "dispatch");
		return;
	}
	if (!t.handled)
		fuzz_fail("dispatch returned 0 without calling the handler");
	if (t.error < 0)
		fuzz_fail("object %u opcode %u: re-encoding failed: %s", m->object, m->opcode, strerror(-t.error));
	f->pending[f->n_pending++] = h;
	if (f->n_pending == MAX_PENDING)
		check_pending(f);
}

/* Takes every complete message the input connection has. */
static void read_input(void *arg)
{
	struct framing *f = arg;
	struct proto_error err = { 0 };
	while (!f->broken) {
		int n = proto_conn_read(f->in, &err);
		if (n == -EPROTO) {
			if (err.code != PROTO_ERR_FD)
				fuzz_fail("read: error code %u", err.code);
			check_error(&err, "read");
			if (fuzz_verbose())
				fprintf(stderr, "read: %s\n", err.text);
			f->broken = true;
			break;
		}
		if (n < 0 && n != -EPIPE)
			fuzz_fail("read: %s", strerror(-n));
		struct proto_message m;
		int r, got = 0;
		while ((r = proto_conn_next(f->in, &m, &err)) == 1) {
			handle(f, &m);
			got++;
		}
		if (r < 0) {
			check_error(&err, "next");
			if (fuzz_verbose())
				fprintf(stderr, "next: %s\n", err.text);
			f->broken = true;
		}
		check_pending(f);
		if (n == -EPIPE) {
			f->broken = true; /* nothing more comes */
			break;
		}
		if (n == 0 && !got)
			break;
	}
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_input in = { data, size, 0 };
	struct fuzz_resources before;
	fuzz_resources_take(&before);
	struct framing f = { .version = 1 + fuzz_u8(&in) % (PROTO_VERSION + 1) };
	int sv[2];
	if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0, sv) < 0)
		fuzz_fail("socketpair: %s", strerror(errno));
	f.sock = sv[0];
	f.in = proto_conn_create(sv[1], MAX_OUT);
	if (!f.in)
		fuzz_fail("proto_conn_create: %s", strerror(errno));
	conn_pair(&f.echo_out, &f.echo_in);
	conn_pair(&f.echo2_out, &f.echo2_in);

	while (!fuzz_done(&in) && !f.broken) {
		uint8_t ctl = fuzz_u8(&in);
		uint16_t len = fuzz_u16(&in);
		size_t n;
		const uint8_t *bytes = fuzz_bytes(&in, len, &n);
		int fds[31];
		unsigned n_fds = 0;
		for (unsigned i = 0; i < (ctl & 31u); i++) {
			int fd = fuzz_fd(((ctl >> 5) & 3u) + i, 64);
			if (fd >= 0)
				fds[n_fds++] = fd;
		}
		if (n || n_fds) {
			int r = fuzz_send(f.sock, bytes, n, fds, n_fds, read_input, &f);
			if (r < 0 && !(f.broken && (r == -EAGAIN || r == -EPIPE)))
				fuzz_fail("send: %s", strerror(-r));
		}
		for (unsigned i = 0; i < n_fds; i++)
			close(fds[i]);
		if (!(ctl & 0x80))
			read_input(&f);
	}
	close(f.sock);
	read_input(&f);

	proto_conn_destroy(f.in);
	proto_conn_destroy(f.echo_out);
	proto_conn_destroy(f.echo_in);
	proto_conn_destroy(f.echo2_out);
	proto_conn_destroy(f.echo2_in);
	fuzz_resources_check(&before);
	return 0;
}
