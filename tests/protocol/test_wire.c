/* The generated codec and the wire layer over a socketpair: round trips of
 * every argument type, fds, framing, and strict rejects. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include "check.h"
#include "spindle-protocol.h"

static struct proto_conn *a, *b;

static void pair(size_t max_out)
{
	int sv[2];
	CHECK(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0, sv) == 0);
	a = proto_conn_create(sv[0], max_out);
	b = proto_conn_create(sv[1], max_out);
	CHECK(a && b);
}

static void unpair(void)
{
	proto_conn_destroy(a);
	proto_conn_destroy(b);
}

/* Flushes a, reads everything into b and takes one message. */
static int transfer(struct proto_message *m, struct proto_error *err)
{
	CHECK(proto_conn_flush(a) == 0);
	int r = proto_conn_next(b, m, err);
	if (r != 0)
		return r;
	r = proto_conn_read(b, err);
	if (r < 0)
		return r;
	return proto_conn_next(b, m, err);
}

/* ---- round trips ---- */

static struct proto_list_draw_args got_draw;
static float got_matrix[16];
static int got_fd = -1;
static uint64_t got_size;

static int on_draw(void *t, const struct proto_list_draw_args *x)
{
	got_draw = *x;
	return 0;
}

static int on_transform(void *t, const struct proto_list_set_transform_args *x)
{
	memcpy(got_matrix, x->matrix, sizeof(got_matrix));
	return 0;
}

static int on_create_buffer(void *t, const struct proto_display_create_buffer_args *x)
{
	got_fd = x->fd;
	got_size = x->size;
	return 0;
}

static char got_text[256];
static uint32_t got_code;

static int on_error(void *t, const struct proto_display_error_args *x)
{
	got_code = x->code;
	snprintf(got_text, sizeof(got_text), "%s", x->message);
	return 0;
}

static const struct proto_list_requests list_h = { .draw = on_draw, .set_transform = on_transform };
static const struct proto_display_requests display_h = { .create_buffer = on_create_buffer };
static const struct proto_display_events display_ev = { .error = on_error };

static void test_round_trips(void)
{
	struct proto_message m;
	struct proto_error err;
	pair(1 << 20);
	CHECK(proto_req_list_draw(a, 9, 2, 7, 0x123456789abcull, 33, 16) == 0);
	CHECK(transfer(&m, &err) == 1 && m.object == 9 && m.size == 12 + 24);
	CHECK(proto_list_dispatch_request(&list_h, NULL, &m, 1, &err) == 0);
	CHECK(got_draw.mode == 2 && got_draw.buffer == 7 && got_draw.offset == 0x123456789abcull);
	CHECK(got_draw.count == 33 && got_draw.stride == 16);

	float mat[16];
	for (int i = 0; i < 16; i++)
		mat[i] = (float)i * 0.5f - 3.0f;
	CHECK(proto_req_list_set_transform(a, 9, mat) == 0);
	CHECK(transfer(&m, &err) == 1 && proto_list_dispatch_request(&list_h, NULL, &m, 1, &err) == 0);
	CHECK(memcmp(mat, got_matrix, sizeof(mat)) == 0);

	const char *texts[] = { "", "abc", "four", "a longer message with odd length!" };
	for (int i = 0; i < 4; i++) {
		CHECK(proto_ev_display_error(a, 1, 5, 3, texts[i]) == 0);
		CHECK(transfer(&m, &err) == 1 && m.size % 4 == 0);
		CHECK(proto_display_dispatch_event(&display_ev, NULL, &m, 1, &err) == 0);
		CHECK(got_code == 3 && strcmp(got_text, texts[i]) == 0);
	}
	unpair();
}

/* More fds than one sendmsg carries, each arriving with its message. */
static void test_fds(void)
{
	struct proto_message m;
	struct proto_error err;
	pair(1 << 20);
	int mfd = memfd_create("t", MFD_CLOEXEC);
	CHECK(ftruncate(mfd, 100) == 0);
	for (int i = 0; i < 40; i++)
		CHECK(proto_req_display_create_buffer(a, 1, (uint32_t)(2 + i), 100 + (uint64_t)i, mfd) == 0);
	close(mfd);
	CHECK(proto_conn_flush(a) == 0);
	int seen = 0;
	while (seen < 40) {
		int r = proto_conn_next(b, &m, &err);
		if (r == 0) {
			CHECK(proto_conn_read(b, &err) > 0);
			continue;
		}
		CHECK(r == 1 && m.fd_count == 1);
		CHECK(proto_display_dispatch_request(&display_h, NULL, &m, 1, &err) == 0);
		CHECK(got_size == 100 + (uint64_t)seen && got_fd >= 0);
		CHECK(lseek(got_fd, 0, SEEK_END) == 100);
		close(got_fd);
		seen++;
	}
	unpair();
}

/* A message trickling in byte by byte is taken only once complete. */
static void test_partial(void)
{
	struct proto_message m;
	struct proto_error err;
	int sv[2];
	CHECK(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, sv) == 0);
	b = proto_conn_create(sv[1], 4096);
	uint8_t msg[16] = { 1, 0, 0, 0, 0, 0, 0, 0, 16, 0, 0, 0, 1, 0, 0, 0 };
	for (int i = 0; i < 16; i++) {
		CHECK(write(sv[0], msg + i, 1) == 1);
		CHECK(proto_conn_read(b, &err) == 1);
		CHECK(proto_conn_next(b, &m, &err) == (i == 15 ? 1 : 0));
	}
	CHECK(m.object == 1 && m.opcode == 0 && m.body_size == 4);
	close(sv[0]);
	CHECK(proto_conn_read(b, &err) == -EPIPE);
	proto_conn_destroy(b);
}

/* ---- rejects ---- */

static uint32_t reject_code(const void *bytes, size_t n, int dispatch_version)
{
	struct proto_message m;
	struct proto_error err = { 0 };
	int sv[2];
	CHECK(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, sv) == 0);
	b = proto_conn_create(sv[1], 4096);
	CHECK(write(sv[0], bytes, n) == (ssize_t)n);
	close(sv[0]);
	int r = proto_conn_read(b, &err);
	CHECK(r > 0);
	r = proto_conn_next(b, &m, &err);
	if (r == 1) {
		static const struct proto_list_requests none = { 0 };
		r = proto_list_dispatch_request(&none, NULL, &m, (uint32_t)dispatch_version, &err);
	}
	proto_conn_destroy(b);
	return r == -EPROTO ? err.code : 0;
}

static void put_header(uint8_t *p, uint32_t obj, uint16_t op, uint16_t fds, uint32_t size)
{
	memcpy(p, &obj, 4), memcpy(p + 4, &op, 2), memcpy(p + 6, &fds, 2), memcpy(p + 8, &size, 4);
}

static void test_rejects(void)
{
	uint8_t m[64] = { 0 };
	put_header(m, 3, 2, 0, 8); /* size below the header */
	CHECK(reject_code(m, 12, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 0, 0); /* zero */
	CHECK(reject_code(m, 12, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 0, 18); /* not a multiple of 4 */
	CHECK(reject_code(m, 20, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 0, 70000); /* above the maximum */
	CHECK(reject_code(m, 12, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 2, 16); /* claims fds it did not send */
	CHECK(reject_code(m, 16, 1) == PROTO_ERR_FD);
	put_header(m, 3, 2, 9, 16); /* more fds than a message may have */
	CHECK(reject_code(m, 16, 1) == PROTO_ERR_FD);
	put_header(m, 3, 42, 0, 12); /* unknown opcode */
	CHECK(reject_code(m, 12, 1) == PROTO_ERR_METHOD);
	put_header(m, 3, 2, 0, 12); /* list.set_color without its argument */
	CHECK(reject_code(m, 12, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 0, 20); /* ... with a stray extra word */
	CHECK(reject_code(m, 20, 1) == PROTO_ERR_MESSAGE);
	put_header(m, 3, 2, 0, 16); /* newer than the version agreed */
	CHECK(reject_code(m, 16, 0) == PROTO_ERR_METHOD);
	put_header(m, 3, 2, 0, 16); /* well-formed but nobody handles it */
	CHECK(reject_code(m, 16, 1) == PROTO_ERR_METHOD);
}

static void test_strings(void)
{
	struct proto_message m;
	struct proto_error err;
	uint8_t buf[40] = { 0 };
	uint32_t obj = 1, zero = 0, len;
	/* display.error(object, code, message) with a bad message string. */
	const struct {
		uint32_t len;
		char text[4];
		bool ok;
	} cases[] = { { 4, "abc", true },
		      { 4, { 'a', 'b', 'c', 'd' }, false },
		      { 0, "", false },
		      { 4, { 'a', 0, 'b', 0 }, false },
		      { 200, "abc", false } };
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		int sv[2];
		CHECK(socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, sv) == 0);
		b = proto_conn_create(sv[1], 4096);
		memset(buf, 0, sizeof(buf));
		put_header(buf, 1, 2, 0, 28);
		memcpy(buf + 12, &obj, 4), memcpy(buf + 16, &zero, 4);
		len = cases[i].len;
		memcpy(buf + 20, &len, 4);
		memcpy(buf + 24, cases[i].text, 4);
		CHECK(write(sv[0], buf, 28) == 28);
		CHECK(proto_conn_read(b, &err) == 28 && proto_conn_next(b, &m, &err) == 1);
		int r = proto_display_dispatch_event(&display_ev, NULL, &m, 1, &err);
		CHECK(cases[i].ok ? r == 0 : (r == -EPROTO && err.code == PROTO_ERR_MESSAGE));
		close(sv[0]);
		proto_conn_destroy(b);
	}
}

/* A peer that does not read: the writer refuses past max_out. */
static void test_backpressure(void)
{
	pair(4096);
	int r = 0, n = 0;
	while ((r = proto_req_display_commit(a, 1)) == 0)
		n++;
	CHECK(r == -ENOBUFS && n == 4096 / 12);
	unpair();
}

int main(void)
{
	test_round_trips();
	test_fds();
	test_partial();
	test_rejects();
	test_strings();
	test_backpressure();
	return check_done();
}
