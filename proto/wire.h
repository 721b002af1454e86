/* The client protocol's wire layer, shared by spindled and libspindle:
 * buffered non-blocking I/O on a Unix stream socket with file descriptors
 * (SCM_RIGHTS), message framing, and the argument readers and writers the
 * generated codec (spindle-protocol.c) is made of. The framing is described
 * in docs/protocol.md. */
#ifndef SPINDLE_WIRE_H
#define SPINDLE_WIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define PROTO_HEADER_SIZE 12
#define PROTO_MAX_MESSAGE 65536
/* Most file descriptors one message may carry, and one connection may have
 * received ahead of their messages. */
#define PROTO_MAX_MESSAGE_FDS 4
#define PROTO_MAX_QUEUED_FDS 28

/* Error codes, the same numbers as the protocol's display.error enum. */
enum proto_err {
	PROTO_ERR_OBJECT = 1,
	PROTO_ERR_METHOD = 2,
	PROTO_ERR_MESSAGE = 3,
	PROTO_ERR_VALUE = 4,
	PROTO_ERR_FD = 5,
	PROTO_ERR_QUOTA = 6,
	PROTO_ERR_VERSION = 7,
	PROTO_ERR_NO_MEMORY = 8,
	PROTO_ERR_TOO_MANY_CLIENTS = 9,
};

/* Why a message was refused: the code and a readable reason. */
struct proto_error {
	uint32_t code;
	char text[160];
};

/* One received message. body and fds point into the connection and stay
 * valid until the next proto_conn_next() call. The fds belong to the
 * connection, which closes them unless the handler took them. */
struct proto_message {
	uint32_t object;
	uint16_t opcode;
	uint16_t fd_count;
	uint32_t size; /* whole message, header included */
	const uint8_t *body;
	uint32_t body_size;
	int *fds;
};

struct proto_conn;

/* Wraps a connected, non-blocking Unix stream socket; the connection owns
 * fd from now on, also on failure. max_out caps the bytes queued for
 * sending (a peer that does not read gets -ENOBUFS). NULL + errno. */
struct proto_conn *proto_conn_create(int fd, size_t max_out);
/* Closes the socket and every queued fd. Accepts NULL. */
void proto_conn_destroy(struct proto_conn *conn);
int proto_conn_get_fd(const struct proto_conn *conn);
/* How many received fds the connection may hold ahead of their messages
 * (1 to PROTO_MAX_QUEUED_FDS, the default; clamped). More is an error. */
void proto_conn_set_max_fds(struct proto_conn *conn, unsigned max);
/* Whether the peer sent more fds than that (the read then failed). */
bool proto_conn_over_fd_cap(const struct proto_conn *conn);

/* Receives what the socket has. Returns bytes received (> 0), 0 when
 * nothing was available, -EPIPE when the peer closed, -EPROTO for bad
 * ancillary data (error text in err), or another negative errno. */
int proto_conn_read(struct proto_conn *conn, struct proto_error *err);
/* Takes the next complete message. Returns 1 with *msg filled, 0 when more
 * bytes are needed, -EPROTO with err filled for a malformed header. */
int proto_conn_next(struct proto_conn *conn, struct proto_message *msg, struct proto_error *err);
/* True if received bytes are waiting that do not yet form a message. */
bool proto_conn_has_partial(const struct proto_conn *conn);

/* Sends queued messages. 0 when everything went, -EAGAIN when the socket
 * is full (wait for POLLOUT), or a negative errno. */
int proto_conn_flush(struct proto_conn *conn);
size_t proto_conn_pending_out(const struct proto_conn *conn);

/* Message writer: begin, put arguments, end. Errors are sticky and reported
 * by proto_writer_end(), which then drops the partial message. */
struct proto_writer {
	struct proto_conn *conn;
	size_t start;
	unsigned fds;
	int error;
};
void proto_writer_begin(struct proto_writer *w, struct proto_conn *conn, uint32_t object, uint16_t opcode);
void proto_put_u32(struct proto_writer *w, uint32_t v);
void proto_put_i32(struct proto_writer *w, int32_t v);
void proto_put_u64(struct proto_writer *w, uint64_t v);
void proto_put_f32(struct proto_writer *w, float v);
void proto_put_matrix(struct proto_writer *w, const float m[16]);
/* NULL writes the null string. */
void proto_put_string(struct proto_writer *w, const char *s);
/* A uint byte count, the bytes, zero padding to a multiple of 4. */
void proto_put_array(struct proto_writer *w, const void *data, uint32_t size);
/* The fd is duplicated; the caller keeps its own. */
void proto_put_fd(struct proto_writer *w, int fd);
/* 0, or -ENOBUFS (over max_out), -EMSGSIZE, -EBADF, -ENOMEM. */
int proto_writer_end(struct proto_writer *w);

/* Message reader, used by the generated decoders. Errors are sticky. */
struct proto_reader {
	const struct proto_message *msg;
	uint32_t pos;
	uint16_t fd_index;
	const char *error;
};
void proto_reader_init(struct proto_reader *r, const struct proto_message *msg);
uint32_t proto_get_u32(struct proto_reader *r);
int32_t proto_get_i32(struct proto_reader *r);
uint64_t proto_get_u64(struct proto_reader *r);
float proto_get_f32(struct proto_reader *r);
void proto_get_matrix(struct proto_reader *r, float m[16]);
const char *proto_get_string(struct proto_reader *r, bool allow_null);
/* The bytes of an array argument (NULL when empty or on error); *size
 * gets their count. */
const void *proto_get_array(struct proto_reader *r, uint32_t *size);
int proto_get_fd(struct proto_reader *r);
/* Checks that the message was read exactly, fds included; fills err and
 * returns -EPROTO if not. what names the message. */
int proto_reader_finish(struct proto_reader *r, struct proto_error *err, const char *what);

/* Fills err (printf-style) and returns -EPROTO. */
int proto_fail(struct proto_error *err, uint32_t code, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* The handler now owns the message's fds (the connection won't close them). */
void proto_message_take_fds(struct proto_message *msg);
/* Closes the message's fds now; returns 0. */
int proto_message_close_fds(struct proto_message *msg);

#endif
