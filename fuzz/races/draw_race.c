/* A regression test, not a fuzz target: a client that writes its memfd
 * while the daemon handles a draw from it. daemon/draw.c read the client's
 * memory more than once (indices: checked, then read again to fetch;
 * vertex colours: read to count the pieces of the subdivision, then again
 * to emit them), so what it checked was not what it used (fixed: it
 * copies, then checks the copy):
 *   indices   draw_indexed while the indices flip between 0 and 0x7fffffff:
 *             an out-of-bounds read (SEGV in fetch())
 *   colours   a triangle of xyz_rgba8 vertices whose colours flip between
 *             equal and far apart: 1 piece counted, 256 written, a heap
 *             buffer overflow (emit_triangle_pieces())
 * A race, so no input file can show it: this program runs an in-process
 * spindled (fuzz/daemon.c) on the main thread and the writer on another,
 * for a number of rounds (default 2000), and exits 0 if nothing happened.
 * The sanitizer build shows what goes wrong best: build-asan/fuzz/
 * fuzz-race-draw indices. Before the fix both crashed within seconds. */
#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "daemon.h"
#include "harness.h"
#include "spindle-protocol.h"

#define INDICES 1024

struct race {
	volatile uint8_t *map; /* the memfd, as the client maps it */
	bool colours;
	atomic_bool stop;
};

static void *writer(void *arg)
{
	struct race *r = arg;
	volatile uint32_t *idx = (volatile uint32_t *)r->map;
	while (!r->stop) {
		if (r->colours) {
			/* Three xyz_rgba8 vertices at 0: colours all black, then
			 * the second white. */
			for (int i = 0; i < 3 * 16; i++)
				r->map[i] = 0;
			for (int i = 0; i < 3; i++)
				r->map[16 * i + 15] = 255;
			for (int c = 12; c < 15; c++)
				r->map[16 + c] = 255;
		} else {
			for (int i = 0; i < INDICES; i++)
				idx[i] = 0;
			for (int i = 0; i < INDICES; i++)
				idx[i] = 0x7fffffff;
		}
	}
	return NULL;
}

/* One connection: 50 draws from the memfd, each followed by clear. */
static void round_of_draws(struct fuzz_server *fs, struct race *r, int memfd)
{
	static const float vertices[9];
	int sock = fuzz_server_connect(fs);
	struct proto_conn *conn = proto_conn_create(fcntl(sock, F_DUPFD_CLOEXEC, 3), 1u << 24);
	if (!conn)
		fuzz_fail("proto_conn_create");
	proto_req_display_hello(conn, 1, 2);
	proto_req_display_create_buffer(conn, 1, 2, INDICES * 4, memfd);
	proto_req_display_create_buffer_inline(conn, 1, 3, vertices, sizeof(vertices));
	proto_req_display_create_list(conn, 1, 4);
	for (int i = 0; i < 50; i++) {
		if (r->colours) {
			proto_req_list_set_vertex_format(conn, 4, PROTO_LIST_VERTEX_FORMAT_XYZ_RGBA8);
			proto_req_list_draw(conn, 4, PROTO_LIST_MODE_TRIANGLES, 2, 0, 3, 0);
		} else {
			struct proto_list_draw_indexed_args d = {
				.mode = PROTO_LIST_MODE_POINTS,
				.vertices = 3,
				.vertex_count = 3,
				.indices = 2,
				.index_count = INDICES,
				.index_type = PROTO_LIST_INDEX_TYPE_U32,
			};
			proto_req_list_draw_indexed(conn, 4, &d);
		}
		proto_req_list_clear(conn, 4);
	}
	proto_conn_flush(conn);
	fuzz_server_run(fs);
	fuzz_drain(sock);
	proto_conn_destroy(conn);
	close(sock);
	fuzz_server_run(fs);
}

int main(int argc, char **argv)
{
	if (argc < 2 || (strcmp(argv[1], "indices") && strcmp(argv[1], "colours"))) {
		fprintf(stderr, "usage: %s indices|colours [ROUNDS]\n", argv[0]);
		return 2;
	}
	struct race r = { .colours = !strcmp(argv[1], "colours") };
	int rounds = argc > 2 ? atoi(argv[2]) : 2000;
	struct fuzz_server fs;
	fuzz_server_start(&fs, NULL);
	int memfd = fuzz_memfd(FUZZ_FD_MEMFD_SEALED, INDICES * 4, NULL, 0);
	if (memfd < 0)
		fuzz_fail("memfd");
	r.map = mmap(NULL, INDICES * 4, PROT_READ | PROT_WRITE, MAP_SHARED, memfd, 0);
	if (r.map == MAP_FAILED)
		fuzz_fail("mmap");
	pthread_t t;
	if (pthread_create(&t, NULL, writer, &r) != 0)
		fuzz_fail("pthread_create");
	for (int i = 0; i < rounds; i++)
		round_of_draws(&fs, &r, memfd);
	r.stop = true;
	pthread_join(t, NULL);
	munmap((void *)r.map, INDICES * 4);
	close(memfd);
	fuzz_server_stop(&fs);
	printf("%s: nothing happened in %d rounds\n", argv[1], rounds);
	return 0;
}
