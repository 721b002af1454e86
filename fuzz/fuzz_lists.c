/* Fuzz target "lists": the display-list validator. A client session
 * reduced to buffers, lists and a layer: the input is a sequence of
 * requests with their arguments, which the target encodes with the
 * generated senders and sends to an in-process spindled, so that
 * daemon/objects.c's checks and copies run as they do for a real client.
 * Besides memory errors, leaks and undefined behaviour, it checks after
 * every request that the client's accounting holds (vertices, primitives,
 * buffer bytes and objects within the quotas, and equal to the sums of
 * what its lists and buffers hold; vertices pending and committed at most
 * twice the quota), and that no fd is left open after the input.
 *
 * Volumes (protocol 6) count their copied samples as buffer bytes.
 *
 * Input: v: u8 (version 1 + (v & 15) % PROTO_VERSION; exclusive layers
 * policy (v >> 4) % 3: none, admin (the fuzzer's user is), any), then
 * requests until the
 * input ends: op: u8 (op % OPS, below), then its arguments. Object ids are
 * one byte each (2 + b % 16), shared by buffers, lists and layers; numbers
 * are fuzz_num() / fuzz_num64(); floats one byte each (read_float()),
 * matrices as read_matrix() says. fuzz/gen_corpus.py writes valid
 * sequences in this form. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "client.h"
#include "daemon.h"
#include "harness.h"

enum op {
	OP_BUFFER,        /* id, kind u8, size u16, declared: num64 (0: size), plen u8, pattern */
	OP_BUFFER_INLINE, /* id, size u16, plen u8, pattern */
	OP_LIST,          /* id */
	OP_DESTROY,       /* id */
	OP_CLEAR,         /* list */
	OP_COLOR,         /* list, rgba u32 */
	OP_TRANSFORM,     /* list, matrix */
	OP_DRAW,          /* list, mode num, buffer, offset num64, count num, stride num */
	OP_DRAW_INDEXED,  /* list, mode, vertices, offset, vertex_count, stride, indices,
			   * index_offset num64, index_count num, index_type num */
	OP_FORMAT,        /* list, format num */
	OP_POINT_SIZE,    /* list, size num */
	OP_PUSH,          /* list */
	OP_POP,           /* list */
	OP_MULTIPLY,      /* list, matrix */
	OP_LAYER,         /* layer id, list id (0: none): create if new, set_list */
	OP_COMMIT,        /* - */
	OP_RAW,           /* object id, opcode u8, len u8, len bytes: any message */
	OP_LAYER_STATE,   /* layer, what u8 % 4: visible num, transform matrix,
			   * priority (int32_t)num, exclusive num */
	OP_VOLUME,        /* id, buffer, offset num64, type num, sizes 3 x u8, spacing 3 floats */
	OP_DRAW_VOLUME,   /* list, volume, sampling num, threshold, centre, width: floats */
	OP_VOLUME_LUT,    /* list, buffer, offset num64, count num */
	OPS
};

struct lists {
	struct fuzz_server fs;
	int sock;
	struct proto_conn *conn; /* the client's end, for the senders */
	uint32_t version;
};

static uint32_t read_id(struct fuzz_input *in)
{
	return 2 + fuzz_u8(in) % 16u;
}

/* One byte: multiples of 1/16 from -7.75 to 7.69, or a value a check must
 * catch or must bear. */
static float read_float(struct fuzz_input *in)
{
	uint8_t b = fuzz_u8(in);
	switch (b) {
	case 0xf8:
		return NAN;
	case 0xf9:
		return INFINITY;
	case 0xfa:
		return -INFINITY;
	case 0xfb:
		return 1e6f;
	case 0xfc:
		return -1.0000001e6f;
	case 0xfd:
		return 1e-40f; /* subnormal */
	case 0xfe: {
		uint32_t bits = fuzz_u32(in);
		float f;
		memcpy(&f, &bits, 4);
		return f;
	}
	case 0xff:
		return -0.0f;
	default:
		return (b - 124) / 16.0f;
	}
}

/* kind u8: 0 identity, 1 translation (3 floats), 2 scale (3 floats),
 * 3 affine (12 floats, bottom row 0 0 0 1), else any 16 floats. */
static void read_matrix(struct fuzz_input *in, float m[16])
{
	static const float identity[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1 };
	memcpy(m, identity, sizeof(identity));
	switch (fuzz_u8(in)) {
	case 0:
		break;
	case 1:
		for (int i = 12; i < 15; i++)
			m[i] = read_float(in);
		break;
	case 2:
		for (int i = 0; i < 3; i++)
			m[5 * i] = read_float(in);
		break;
	case 3:
		for (int col = 0; col < 4; col++)
			for (int row = 0; row < 3; row++)
				m[4 * col + row] = read_float(in);
		break;
	default:
		for (int i = 0; i < 16; i++)
			m[i] = read_float(in);
		break;
	}
}

/* size bytes: the pattern (plen u8, then plen bytes) repeated. */
static uint8_t *read_contents(struct fuzz_input *in, size_t size)
{
	size_t n;
	const uint8_t *pattern = fuzz_bytes(in, fuzz_u8(in), &n);
	uint8_t *buf = calloc(1, size ? size : 1);
	if (!buf)
		fuzz_fail("out of memory");
	for (size_t i = 0; n && i < size; i++)
		buf[i] = pattern[i % n];
	return buf;
}

static int op_buffer(struct lists *s, struct fuzz_input *in)
{
	uint32_t id = read_id(in);
	unsigned kind = fuzz_u8(in) % FUZZ_FD_KINDS;
	uint16_t size = fuzz_u16(in);
	uint64_t declared = fuzz_num64(in);
	uint8_t *buf = read_contents(in, size);
	int fd = kind <= FUZZ_FD_MEMFD_UNSEALED ? fuzz_memfd((enum fuzz_fd_kind)kind, size, buf, size)
						: fuzz_fd(kind, 0);
	free(buf);
	if (fd < 0)
		fuzz_fail("fd: %s", strerror(-fd));
	int r = proto_req_display_create_buffer(s->conn, 1, id, declared ? declared : size, fd);
	close(fd);
	return r;
}

static int op_buffer_inline(struct lists *s, struct fuzz_input *in)
{
	uint32_t id = read_id(in);
	uint16_t size = fuzz_u16(in) % (PROTO_MAX_MESSAGE - PROTO_HEADER_SIZE - 8 + 1);
	uint8_t *buf = read_contents(in, size);
	int r = proto_req_display_create_buffer_inline(s->conn, 1, id, buf, size);
	free(buf);
	return r;
}

static int op_draw(struct lists *s, struct fuzz_input *in)
{
	uint32_t list = read_id(in);
	uint32_t mode = fuzz_num(in);
	uint32_t buffer = read_id(in);
	uint64_t offset = fuzz_num64(in);
	uint32_t count = fuzz_num(in);
	uint32_t stride = fuzz_num(in);
	return proto_req_list_draw(s->conn, list, mode, buffer, offset, count, stride);
}

static int op_draw_indexed(struct lists *s, struct fuzz_input *in)
{
	uint32_t list = read_id(in);
	/* Read in the order of the arguments: the corpus depends on it. */
	struct proto_list_draw_indexed_args d;
	d.mode = fuzz_num(in);
	d.vertices = read_id(in);
	d.offset = fuzz_num64(in);
	d.vertex_count = fuzz_num(in);
	d.stride = fuzz_num(in);
	d.indices = read_id(in);
	d.index_offset = fuzz_num64(in);
	d.index_count = fuzz_num(in);
	d.index_type = fuzz_num(in);
	return proto_req_list_draw_indexed(s->conn, list, &d);
}

static int op_layer(struct lists *s, struct fuzz_input *in)
{
	uint32_t layer = read_id(in);
	uint8_t list = fuzz_u8(in);
	struct client *c = link_entry(s->fs.srv.clients.next, struct client, link);
	if (!idmap_get(&c->objects, layer)) {
		int r = proto_req_display_create_layer(s->conn, 1, layer);
		if (r < 0)
			return r;
	}
	return proto_req_layer_set_list(s->conn, layer, list ? 2 + list % 16u : 0);
}

static int op_layer_state(struct lists *s, struct fuzz_input *in)
{
	uint32_t layer = read_id(in);
	float m[16];
	switch (fuzz_u8(in) % 4) {
	case 0:
		return proto_req_layer_set_visible(s->conn, layer, fuzz_num(in));
	case 1:
		read_matrix(in, m);
		return proto_req_layer_set_transform(s->conn, layer, m);
	case 2:
		return proto_req_layer_set_priority(s->conn, layer, (int32_t)fuzz_num(in));
	default:
		return proto_req_layer_set_exclusive(s->conn, layer, fuzz_num(in));
	}
}

/* Volumes (protocol 6): sizes of a byte each, so that most fit the
 * buffers the input makes. */
static int op_volume(struct lists *s, struct fuzz_input *in)
{
	struct proto_display_create_volume_args a;
	a.id = read_id(in);
	a.buffer = read_id(in);
	a.offset = fuzz_num64(in);
	a.type = fuzz_num(in);
	a.nx = fuzz_u8(in);
	a.ny = fuzz_u8(in);
	a.nz = fuzz_u8(in);
	a.sx = read_float(in);
	a.sy = read_float(in);
	a.sz = read_float(in);
	return proto_req_display_create_volume(s->conn, 1, &a);
}

static int op_draw_volume(struct lists *s, struct fuzz_input *in)
{
	uint32_t list = read_id(in), volume = read_id(in), sampling = fuzz_num(in);
	float threshold = read_float(in), centre = read_float(in), width = read_float(in);
	return proto_req_list_draw_volume(s->conn, list, volume, sampling, threshold, centre, width);
}

static int op_volume_lut(struct lists *s, struct fuzz_input *in)
{
	uint32_t list = read_id(in), buffer = read_id(in);
	uint64_t offset = fuzz_num64(in);
	return proto_req_list_set_volume_lut(s->conn, list, buffer, offset, fuzz_num(in));
}

static int op_raw(struct lists *s, struct fuzz_input *in)
{
	struct proto_writer w;
	uint32_t object = fuzz_u8(in) % 18u; /* 0, the display, and the ids */
	uint16_t opcode = fuzz_u8(in);
	size_t n;
	const uint8_t *body = fuzz_bytes(in, fuzz_u8(in) & ~3u, &n);
	proto_writer_begin(&w, s->conn, object, opcode);
	for (size_t i = 0; i + 4 <= n; i += 4) {
		uint32_t v;
		memcpy(&v, body + i, 4);
		proto_put_u32(&w, v);
	}
	return proto_writer_end(&w);
}

static int send_op(struct lists *s, struct fuzz_input *in)
{
	float m[16];
	uint32_t id;
	switch ((enum op)(fuzz_u8(in) % OPS)) {
	case OP_BUFFER:
		return op_buffer(s, in);
	case OP_BUFFER_INLINE:
		return op_buffer_inline(s, in);
	case OP_LIST:
		return proto_req_display_create_list(s->conn, 1, read_id(in));
	case OP_DESTROY:
		/* Opcode 0 is destroy for buffers, lists and layers alike. */
		return proto_req_list_destroy(s->conn, read_id(in));
	case OP_CLEAR:
		return proto_req_list_clear(s->conn, read_id(in));
	case OP_COLOR:
		id = read_id(in);
		return proto_req_list_set_color(s->conn, id, fuzz_u32(in));
	case OP_TRANSFORM:
		id = read_id(in);
		read_matrix(in, m);
		return proto_req_list_set_transform(s->conn, id, m);
	case OP_DRAW:
		return op_draw(s, in);
	case OP_DRAW_INDEXED:
		return op_draw_indexed(s, in);
	case OP_FORMAT:
		id = read_id(in);
		return proto_req_list_set_vertex_format(s->conn, id, fuzz_num(in));
	case OP_POINT_SIZE:
		id = read_id(in);
		return proto_req_list_set_point_size(s->conn, id, fuzz_num(in));
	case OP_PUSH:
		return proto_req_list_push(s->conn, read_id(in));
	case OP_POP:
		return proto_req_list_pop(s->conn, read_id(in));
	case OP_MULTIPLY:
		id = read_id(in);
		read_matrix(in, m);
		return proto_req_list_multiply_transform(s->conn, id, m);
	case OP_LAYER:
		return op_layer(s, in);
	case OP_COMMIT:
		return proto_req_display_commit(s->conn, 1);
	case OP_LAYER_STATE:
		return op_layer_state(s, in);
	case OP_VOLUME:
		return op_volume(s, in);
	case OP_DRAW_VOLUME:
		return op_draw_volume(s, in);
	case OP_VOLUME_LUT:
		return op_volume_lut(s, in);
	case OP_RAW:
	case OPS:
		break;
	}
	return op_raw(s, in);
}

static int by_address(const void *a, const void *b)
{
	uintptr_t x = (uintptr_t) * (const struct vdata *const *)a, y = (uintptr_t) * (const struct vdata *const *)b;
	return x < y ? -1 : x > y;
}

/* Vertices the client's lists hold, pending and committed, each vertex
 * data counted once (the two share it after a commit). */
static uint64_t held_vertices(const struct client *c)
{
	const struct vdata *held[2048];
	size_t n = 0;
	const struct list *l;
	link_for_each(l, &c->lists, link) {
		for (uint32_t i = 0; i < l->pending.count && n < 2048; i++)
			held[n++] = l->pending.items[i].data;
		for (uint32_t i = 0; i < l->committed.count && n < 2048; i++)
			held[n++] = l->committed.items[i].data;
	}
	qsort(held, n, sizeof(*held), by_address);
	uint64_t v = 0;
	for (size_t i = 0; i < n; i++)
		if (i == 0 || held[i] != held[i - 1])
			v += held[i]->count;
	return v;
}

/* The client's accounting against what its objects hold. */
static void check_client(const struct client *c, const struct config *cfg)
{
	uint64_t vertices = 0, bytes = 0;
	uint32_t objects = 0;
	const struct list *l;
	link_for_each(l, &c->lists, link) {
		uint64_t v = 0, p = 0;
		for (uint32_t i = 0; i < l->pending.count; i++) {
			const struct vdata *d = l->pending.items[i].data;
			if (d->prim == SCENE_GRID ? !d->grid || !d->count || d->prims : !d->count || !d->prims)
				fuzz_fail("list %u: an empty draw", l->base.id);
			v += d->count;
			p += d->prims;
		}
		if (v != l->pending.vertices || p != l->pending.prims)
			fuzz_fail("list %u: %llu vertices and %llu primitives counted, %llu and %llu held", l->base.id,
				  (unsigned long long)l->pending.vertices, (unsigned long long)l->pending.prims,
				  (unsigned long long)v, (unsigned long long)p);
		vertices += v;
	}
	for (uint32_t i = 0; i < c->objects.cap; i++) {
		const struct object *o = c->objects.slots[i].value;
		if (!c->objects.slots[i].id)
			continue;
		objects++;
		if (o->id != c->objects.slots[i].id || o->client != c)
			fuzz_fail("object %u: registered as %u", c->objects.slots[i].id, o->id);
		if (o->type == PROTO_IFACE_BUFFER)
			bytes += ((const struct buffer *)o)->size;
		if (o->type == PROTO_IFACE_VOLUME)
			bytes += ((const struct volume_obj *)o)->grid->bytes;
	}
	if (vertices != c->vertices || vertices > cfg->max_vertices)
		fuzz_fail("client: %llu vertices counted, %llu held, quota %llu", (unsigned long long)c->vertices,
			  (unsigned long long)vertices, (unsigned long long)cfg->max_vertices);
	/* max-vertices counts the pending state; with what is committed a
	 * client holds at most twice that (docs/protocol.md). */
	uint64_t held = held_vertices(c);
	if (held > 2 * cfg->max_vertices)
		fuzz_fail("client: %llu vertices held, pending and committed, over twice the quota %llu",
			  (unsigned long long)held, (unsigned long long)cfg->max_vertices);
	if (bytes != c->buffer_bytes || bytes > cfg->max_buffer_bytes)
		fuzz_fail("client: %llu buffer bytes counted, %llu held, quota %llu",
			  (unsigned long long)c->buffer_bytes, (unsigned long long)bytes,
			  (unsigned long long)cfg->max_buffer_bytes);
	if (objects != c->objects.count || objects > cfg->max_objects)
		fuzz_fail("client: %u objects counted, %u held, quota %u", c->objects.count, objects, cfg->max_objects);
}

/* The one client, or NULL once the server dropped it. */
static struct client *the_client(struct lists *s)
{
	if (link_empty(&s->fs.srv.clients))
		return NULL;
	struct client *c = link_entry(s->fs.srv.clients.next, struct client, link);
	return c->dead ? NULL : c;
}

/* Sends what is queued and lets the server handle it. */
static void exchange(struct lists *s)
{
	int r = proto_conn_flush(s->conn);
	if (r < 0 && r != -EAGAIN && r != -EPIPE && r != -ECONNRESET)
		fuzz_fail("flush: %s", strerror(-r));
	fuzz_server_run(&s->fs);
	fuzz_drain(s->sock);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct fuzz_input in = { data, size, 0 };
	struct fuzz_resources before;
	fuzz_resources_take(&before);
	uint8_t v = fuzz_u8(&in);
	struct lists s = { .version = 1 + (v & 15u) % PROTO_VERSION };
	static const char *const policies[][3] = {
		{ "exclusive", "none", NULL },
		{ "exclusive", "admin", NULL },
		{ "exclusive", "any", NULL },
	};
	fuzz_server_start(&s.fs, policies[(v >> 4) % 3]);
	int sock = fuzz_server_connect(&s.fs);
	/* The senders write on a connection of their own over a duplicate;
	 * sock reads (and drops) the events. */
	s.sock = sock;
	s.conn = proto_conn_create(fcntl(sock, F_DUPFD_CLOEXEC, 3), 1u << 20);
	if (!s.conn)
		fuzz_fail("proto_conn_create: %s", strerror(errno));
	proto_req_display_hello(s.conn, 1, s.version);
	exchange(&s);

	struct client *c;
	while (!fuzz_done(&in) && (c = the_client(&s))) {
		check_client(c, &s.fs.srv.cfg);
		int r = send_op(&s, &in);
		if (r < 0 && r != -EMSGSIZE)
			fuzz_fail("sending: %s", strerror(-r));
		exchange(&s);
	}
	if ((c = the_client(&s)))
		check_client(c, &s.fs.srv.cfg);

	proto_conn_destroy(s.conn);
	close(sock);
	fuzz_server_run(&s.fs);
	if (s.fs.srv.client_count != 0)
		fuzz_fail("a closed client was not reaped");
	fuzz_server_stop(&s.fs);
	fuzz_resources_check(&before);
	return 0;
}
