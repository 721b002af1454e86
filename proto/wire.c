#include "wire.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

_Static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the wire format is little-endian");

#define IN_CAP (2 * PROTO_MAX_MESSAGE)
#define OUT_FDS_PER_SEND 28

struct out_fd {
	int fd;
	size_t offset; /* start of the message it belongs to, in out[] */
};

struct proto_conn {
	int fd;
	/* Received bytes in in[head, tail). */
	uint8_t in[IN_CAP];
	size_t head, tail;
	int in_fds[PROTO_MAX_QUEUED_FDS];
	unsigned in_fd_count, max_in_fds;
	bool over_fd_cap;
	unsigned consumed_fds; /* fds of the last message handed out */
	/* Bytes to send in out[out_head, out_tail), with their fds. */
	uint8_t *out;
	size_t out_head, out_tail, out_cap, max_out;
	struct out_fd *out_fds;
	unsigned out_fd_count, out_fd_cap;
};

struct proto_conn *proto_conn_create(int fd, size_t max_out)
{
	struct proto_conn *conn = calloc(1, sizeof(*conn));
	if (!conn) {
		close(fd);
		return NULL;
	}
	conn->fd = fd;
	conn->max_out = max_out;
	conn->max_in_fds = PROTO_MAX_QUEUED_FDS;
	return conn;
}

void proto_conn_set_max_fds(struct proto_conn *conn, unsigned max)
{
	conn->max_in_fds = max < 1 ? 1 : max > PROTO_MAX_QUEUED_FDS ? PROTO_MAX_QUEUED_FDS : max;
}

bool proto_conn_over_fd_cap(const struct proto_conn *conn)
{
	return conn->over_fd_cap;
}

static void drop_in_fds(struct proto_conn *conn, unsigned n)
{
	for (unsigned i = 0; i < n; i++)
		if (conn->in_fds[i] >= 0)
			close(conn->in_fds[i]);
	memmove(conn->in_fds, conn->in_fds + n, (conn->in_fd_count - n) * sizeof(int));
	conn->in_fd_count -= n;
}

void proto_conn_destroy(struct proto_conn *conn)
{
	if (!conn)
		return;
	drop_in_fds(conn, conn->in_fd_count);
	for (unsigned i = 0; i < conn->out_fd_count; i++)
		close(conn->out_fds[i].fd);
	free(conn->out_fds);
	free(conn->out);
	close(conn->fd);
	free(conn);
}

int proto_conn_get_fd(const struct proto_conn *conn)
{
	return conn->fd;
}

int proto_fail(struct proto_error *err, uint32_t code, const char *fmt, ...)
{
	va_list ap;
	err->code = code;
	va_start(ap, fmt);
	vsnprintf(err->text, sizeof(err->text), fmt, ap);
	va_end(ap);
	return -EPROTO;
}

/* Queues the fds of one SCM_RIGHTS block; closes and refuses any past the
 * queue's room. */
static int take_rights(struct proto_conn *conn, struct cmsghdr *cmsg, struct proto_error *err)
{
	int *fds = (int *)CMSG_DATA(cmsg);
	size_t n = (cmsg->cmsg_len - CMSG_LEN(0)) / sizeof(int);
	int r = 0;
	for (size_t i = 0; i < n; i++) {
		if (conn->in_fd_count < conn->max_in_fds) {
			conn->in_fds[conn->in_fd_count++] = fds[i];
		} else {
			close(fds[i]);
			conn->over_fd_cap = true;
			r = proto_fail(err, PROTO_ERR_FD, "more than %u file descriptors ahead of their messages",
				       conn->max_in_fds);
		}
	}
	return r;
}

int proto_conn_read(struct proto_conn *conn, struct proto_error *err)
{
	if (conn->head > 0 && conn->tail > IN_CAP - PROTO_MAX_MESSAGE) {
		memmove(conn->in, conn->in + conn->head, conn->tail - conn->head);
		conn->tail -= conn->head;
		conn->head = 0;
	}
	if (conn->tail == IN_CAP)
		return 0;
	union {
		char buf[CMSG_SPACE(sizeof(int) * PROTO_MAX_QUEUED_FDS)];
		struct cmsghdr align;
	} control;
	struct iovec iov = { conn->in + conn->tail, IN_CAP - conn->tail };
	struct msghdr mh = { .msg_iov = &iov,
			     .msg_iovlen = 1,
			     .msg_control = control.buf,
			     .msg_controllen = sizeof(control.buf) };
	ssize_t n;
	do
		n = recvmsg(conn->fd, &mh, MSG_DONTWAIT | MSG_CMSG_CLOEXEC);
	while (n < 0 && errno == EINTR);
	if (n < 0)
		return (errno == EAGAIN || errno == EWOULDBLOCK) ? 0 : -errno;
	int r = 0;
	for (struct cmsghdr *c = CMSG_FIRSTHDR(&mh); c; c = CMSG_NXTHDR(&mh, c)) {
		if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
			if (take_rights(conn, c, err) < 0)
				r = -EPROTO;
		}
	}
	if (mh.msg_flags & MSG_CTRUNC)
		r = proto_fail(err, PROTO_ERR_FD, "truncated ancillary data (too many file descriptors)");
	if (r < 0)
		return r;
	if (n == 0)
		return -EPIPE;
	conn->tail += (size_t)n;
	return (int)n;
}

static uint32_t load32(const uint8_t *p)
{
	uint32_t v;
	memcpy(&v, p, 4);
	return v;
}

int proto_conn_next(struct proto_conn *conn, struct proto_message *msg, struct proto_error *err)
{
	drop_in_fds(conn, conn->consumed_fds);
	conn->consumed_fds = 0;
	size_t avail = conn->tail - conn->head;
	if (avail < PROTO_HEADER_SIZE)
		return 0;
	const uint8_t *p = conn->in + conn->head;
	uint16_t opcode, fd_count;
	memcpy(&opcode, p + 4, 2);
	memcpy(&fd_count, p + 6, 2);
	uint32_t size = load32(p + 8);
	if (size < PROTO_HEADER_SIZE || size > PROTO_MAX_MESSAGE || size % 4 != 0)
		return proto_fail(err, PROTO_ERR_MESSAGE, "bad message size %u", size);
	if (fd_count > PROTO_MAX_MESSAGE_FDS)
		return proto_fail(err, PROTO_ERR_FD, "message claims %u file descriptors", fd_count);
	if (avail < size)
		return 0;
	if (fd_count > conn->in_fd_count)
		return proto_fail(err, PROTO_ERR_FD, "message claims %u file descriptors, %u received", fd_count,
				  conn->in_fd_count);
	*msg = (struct proto_message){
		.object = load32(p),
		.opcode = opcode,
		.fd_count = fd_count,
		.size = size,
		.body = p + PROTO_HEADER_SIZE,
		.body_size = size - PROTO_HEADER_SIZE,
		.fds = conn->in_fds,
	};
	conn->consumed_fds = fd_count;
	conn->head += size;
	if (conn->head == conn->tail)
		conn->head = conn->tail = 0;
	return 1;
}

bool proto_conn_has_partial(const struct proto_conn *conn)
{
	return conn->tail > conn->head;
}

void proto_message_take_fds(struct proto_message *msg)
{
	for (unsigned i = 0; i < msg->fd_count; i++)
		msg->fds[i] = -1;
}

int proto_message_close_fds(struct proto_message *msg)
{
	for (unsigned i = 0; i < msg->fd_count; i++) {
		if (msg->fds[i] >= 0)
			close(msg->fds[i]);
		msg->fds[i] = -1;
	}
	return 0;
}

size_t proto_conn_pending_out(const struct proto_conn *conn)
{
	return conn->out_tail - conn->out_head;
}

/* Bytes that may go in one sendmsg with the first OUT_FDS_PER_SEND fds:
 * never a message whose fds are not among them. */
static size_t sendable(const struct proto_conn *conn, unsigned *nfds)
{
	size_t len = conn->out_tail - conn->out_head;
	*nfds = conn->out_fd_count;
	if (*nfds > OUT_FDS_PER_SEND) {
		*nfds = OUT_FDS_PER_SEND;
		len = conn->out_fds[OUT_FDS_PER_SEND].offset - conn->out_head;
	}
	return len;
}

static void sent(struct proto_conn *conn, size_t bytes, unsigned nfds)
{
	for (unsigned i = 0; i < nfds; i++)
		close(conn->out_fds[i].fd);
	if (nfds)
		memmove(conn->out_fds, conn->out_fds + nfds, (conn->out_fd_count - nfds) * sizeof(*conn->out_fds));
	conn->out_fd_count -= nfds;
	conn->out_head += bytes;
	if (conn->out_head == conn->out_tail) {
		for (unsigned i = 0; i < conn->out_fd_count; i++)
			conn->out_fds[i].offset -= conn->out_head;
		conn->out_head = conn->out_tail = 0;
	}
}

int proto_conn_flush(struct proto_conn *conn)
{
	while (conn->out_tail > conn->out_head) {
		unsigned nfds;
		size_t len = sendable(conn, &nfds);
		union {
			char buf[CMSG_SPACE(sizeof(int) * OUT_FDS_PER_SEND)];
			struct cmsghdr align;
		} control;
		struct iovec iov = { conn->out + conn->out_head, len };
		struct msghdr mh = { .msg_iov = &iov, .msg_iovlen = 1 };
		if (nfds) {
			mh.msg_control = control.buf;
			mh.msg_controllen = CMSG_SPACE(sizeof(int) * nfds);
			struct cmsghdr *c = CMSG_FIRSTHDR(&mh);
			c->cmsg_level = SOL_SOCKET;
			c->cmsg_type = SCM_RIGHTS;
			c->cmsg_len = CMSG_LEN(sizeof(int) * nfds);
			for (unsigned i = 0; i < nfds; i++)
				memcpy(CMSG_DATA(c) + i * sizeof(int), &conn->out_fds[i].fd, sizeof(int));
		}
		ssize_t n = sendmsg(conn->fd, &mh, MSG_DONTWAIT | MSG_NOSIGNAL);
		if (n < 0) {
			if (errno == EINTR)
				continue;
			return (errno == EAGAIN || errno == EWOULDBLOCK) ? -EAGAIN : -errno;
		}
		sent(conn, (size_t)n, nfds);
	}
	return 0;
}

static uint8_t *out_reserve(struct proto_writer *w, size_t n)
{
	struct proto_conn *conn = w->conn;
	if (w->error)
		return NULL;
	if (conn->out_tail + n - w->start > PROTO_MAX_MESSAGE) {
		w->error = -EMSGSIZE;
		return NULL;
	}
	if (conn->out_tail + n - conn->out_head > conn->max_out) {
		w->error = -ENOBUFS;
		return NULL;
	}
	if (conn->out_tail + n > conn->out_cap) {
		size_t cap = conn->out_cap ? conn->out_cap : 4096;
		while (cap < conn->out_tail + n)
			cap *= 2;
		uint8_t *out = realloc(conn->out, cap);
		if (!out) {
			w->error = -ENOMEM;
			return NULL;
		}
		conn->out = out;
		conn->out_cap = cap;
	}
	uint8_t *p = conn->out + conn->out_tail;
	conn->out_tail += n;
	return p;
}

/* Moves unsent bytes to the front, between messages only. */
static void out_compact(struct proto_conn *conn)
{
	size_t shift = conn->out_head;
	memmove(conn->out, conn->out + shift, conn->out_tail - shift);
	for (unsigned i = 0; i < conn->out_fd_count; i++)
		conn->out_fds[i].offset -= shift;
	conn->out_head = 0;
	conn->out_tail -= shift;
}

void proto_writer_begin(struct proto_writer *w, struct proto_conn *conn, uint32_t object, uint16_t opcode)
{
	if (conn->out_head > 0 && conn->out_head >= conn->out_cap / 2)
		out_compact(conn);
	*w = (struct proto_writer){ .conn = conn, .start = conn->out_tail };
	uint8_t *p = out_reserve(w, PROTO_HEADER_SIZE);
	if (!p)
		return;
	memcpy(p, &object, 4);
	memcpy(p + 4, &opcode, 2);
	memset(p + 6, 0, 6);
}

static void put(struct proto_writer *w, const void *data, size_t n)
{
	uint8_t *p = out_reserve(w, n);
	if (p)
		memcpy(p, data, n);
}

void proto_put_u32(struct proto_writer *w, uint32_t v)
{
	put(w, &v, 4);
}

void proto_put_i32(struct proto_writer *w, int32_t v)
{
	put(w, &v, 4);
}

void proto_put_u64(struct proto_writer *w, uint64_t v)
{
	put(w, &v, 8);
}

void proto_put_f32(struct proto_writer *w, float v)
{
	put(w, &v, 4);
}

void proto_put_matrix(struct proto_writer *w, const float m[16])
{
	put(w, m, 64);
}

void proto_put_string(struct proto_writer *w, const char *s)
{
	if (!s) {
		proto_put_u32(w, 0);
		return;
	}
	size_t len = strlen(s) + 1;
	if (len > PROTO_MAX_MESSAGE) {
		w->error = -EMSGSIZE;
		return;
	}
	proto_put_u32(w, (uint32_t)len);
	put(w, s, len);
	uint8_t *pad = out_reserve(w, (4 - len % 4) % 4);
	if (pad)
		memset(pad, 0, (4 - len % 4) % 4);
}

void proto_put_array(struct proto_writer *w, const void *data, uint32_t size)
{
	if (size > PROTO_MAX_MESSAGE) {
		w->error = -EMSGSIZE;
		return;
	}
	proto_put_u32(w, size);
	if (size)
		put(w, data, size);
	uint8_t *pad = out_reserve(w, (4 - size % 4) % 4);
	if (pad)
		memset(pad, 0, (4 - size % 4) % 4);
}

void proto_put_fd(struct proto_writer *w, int fd)
{
	struct proto_conn *conn = w->conn;
	if (w->error)
		return;
	if (w->fds >= PROTO_MAX_MESSAGE_FDS) {
		w->error = -EMSGSIZE;
		return;
	}
	if (conn->out_fd_count == conn->out_fd_cap) {
		unsigned cap = conn->out_fd_cap ? conn->out_fd_cap * 2 : 8;
		struct out_fd *fds = realloc(conn->out_fds, cap * sizeof(*fds));
		if (!fds) {
			w->error = -ENOMEM;
			return;
		}
		conn->out_fds = fds;
		conn->out_fd_cap = cap;
	}
	int dup = fcntl(fd, F_DUPFD_CLOEXEC, 3);
	if (dup < 0) {
		w->error = -errno;
		return;
	}
	conn->out_fds[conn->out_fd_count++] = (struct out_fd){ dup, w->start };
	w->fds++;
}

int proto_writer_end(struct proto_writer *w)
{
	struct proto_conn *conn = w->conn;
	if (w->error) {
		/* Drop the partial message and the fds queued for it. */
		while (w->fds > 0) {
			close(conn->out_fds[--conn->out_fd_count].fd);
			w->fds--;
		}
		conn->out_tail = w->start;
		return w->error;
	}
	uint32_t size = (uint32_t)(conn->out_tail - w->start);
	uint16_t fds = (uint16_t)w->fds;
	memcpy(conn->out + w->start + 6, &fds, 2);
	memcpy(conn->out + w->start + 8, &size, 4);
	return 0;
}

void proto_reader_init(struct proto_reader *r, const struct proto_message *msg)
{
	*r = (struct proto_reader){ .msg = msg };
}

static const uint8_t *get(struct proto_reader *r, uint32_t n)
{
	if (r->error)
		return NULL;
	if (n > r->msg->body_size - r->pos) {
		r->error = "message too short for its arguments";
		return NULL;
	}
	const uint8_t *p = r->msg->body + r->pos;
	r->pos += n;
	return p;
}

/* Copies n bytes of the next argument into out; zeroes after an error. */
static void get_copy(struct proto_reader *r, void *out, uint32_t n)
{
	const uint8_t *p = get(r, n);
	if (p)
		memcpy(out, p, n);
	else
		memset(out, 0, n);
}

uint32_t proto_get_u32(struct proto_reader *r)
{
	uint32_t v;
	get_copy(r, &v, 4);
	return v;
}

int32_t proto_get_i32(struct proto_reader *r)
{
	return (int32_t)proto_get_u32(r);
}

uint64_t proto_get_u64(struct proto_reader *r)
{
	uint64_t v;
	get_copy(r, &v, 8);
	return v;
}

float proto_get_f32(struct proto_reader *r)
{
	float v;
	get_copy(r, &v, 4);
	return v;
}

void proto_get_matrix(struct proto_reader *r, float m[16])
{
	get_copy(r, m, 64);
}

const char *proto_get_string(struct proto_reader *r, bool allow_null)
{
	uint32_t len = proto_get_u32(r);
	if (r->error)
		return NULL;
	if (len == 0) {
		if (!allow_null)
			r->error = "null string";
		return NULL;
	}
	if (len > PROTO_MAX_MESSAGE) {
		r->error = "string longer than its message";
		return NULL;
	}
	const char *s = (const char *)get(r, (len + 3) & ~3u);
	if (!s)
		return NULL;
	if (s[len - 1] != '\0' || memchr(s, '\0', len - 1)) {
		r->error = "string not NUL-terminated, or with a NUL inside";
		return NULL;
	}
	return s;
}

const void *proto_get_array(struct proto_reader *r, uint32_t *size)
{
	uint32_t len = proto_get_u32(r);
	*size = 0;
	if (r->error)
		return NULL;
	if (len > PROTO_MAX_MESSAGE) {
		r->error = "array longer than its message";
		return NULL;
	}
	const void *p = get(r, (len + 3) & ~3u);
	if (p)
		*size = len;
	return p;
}

int proto_get_fd(struct proto_reader *r)
{
	if (r->error)
		return -1;
	if (r->fd_index >= r->msg->fd_count) {
		r->error = "file descriptor missing";
		return -1;
	}
	return r->msg->fds[r->fd_index++];
}

int proto_reader_finish(struct proto_reader *r, struct proto_error *err, const char *what)
{
	if (r->error)
		return proto_fail(err, PROTO_ERR_MESSAGE, "%s: %s", what, r->error);
	if (r->pos != r->msg->body_size)
		return proto_fail(err, PROTO_ERR_MESSAGE, "%s: %u bytes of arguments, expected %u", what,
				  r->msg->body_size, r->pos);
	if (r->fd_index != r->msg->fd_count)
		return proto_fail(err, PROTO_ERR_FD, "%s: %u file descriptors, expected %u", what, r->msg->fd_count,
				  r->fd_index);
	return 0;
}
