/* torus: a shaded mesh, handed to the daemon without copies.
 *
 * Shows the way to give spindled a large model: the vertices (position
 * and colour) and the triangle indices are written straight into memfds,
 * sealed against shrinking and passed as they are
 * (spindle_buffer_create_from_fd()); the daemon maps them and copies and
 * checks what one draw_indexed uses. Then the blocking helpers: commit and
 * wait until shown (with what a refused commit looks like), the status,
 * and, with --exclusive, an exclusive layer at a raised priority.
 *
 *   torus [--rings N] [--exclusive] [--socket PATH]
 *
 * Prints when the torus was first shown, and exits. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include <spindle/spindle.h>

struct vertex {
	float xyz[3];
	uint8_t rgba[4];
};

/* A memfd of size bytes, mapped for writing; sealed when done. */
struct shared {
	int fd;
	void *map;
	size_t size;
};

static int shared_create(struct shared *s, const char *name, size_t size)
{
	s->size = size;
	s->fd = memfd_create(name, MFD_CLOEXEC | MFD_ALLOW_SEALING);
	if (s->fd < 0 || ftruncate(s->fd, (off_t)size) < 0)
		return -errno;
	s->map = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_SHARED, s->fd, 0);
	return s->map == MAP_FAILED ? -errno : 0;
}

/* The daemon requires F_SEAL_SHRINK: then it can map the file safely. */
static int shared_seal(struct shared *s)
{
	munmap(s->map, s->size);
	return fcntl(s->fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL) < 0 ? -errno : 0;
}

/* A torus about the y axis: rings x sides vertices, coloured by height
 * (blue below, red above) and 2 * rings * sides triangles. */
static void torus(struct vertex *v, uint32_t *idx, int rings, int sides)
{
	const double R = 0.6, r = 0.25;
	for (int i = 0; i < rings; i++)
		for (int j = 0; j < sides; j++) {
			double a = 2 * M_PI * i / rings, b = 2 * M_PI * j / sides;
			double y = r * sin(b), q = R + r * cos(b);
			uint8_t up = (uint8_t)(255 * (y + r) / (2 * r));
			v[i * sides + j] = (struct vertex){ { (float)(q * cos(a)), (float)y, (float)(q * sin(a)) },
							    { up, 64, (uint8_t)(255 - up), 255 } };
		}
	for (int i = 0; i < rings; i++)
		for (int j = 0; j < sides; j++) {
			uint32_t a = (uint32_t)(i * sides + j), b = (uint32_t)(((i + 1) % rings) * sides + j);
			uint32_t c = (uint32_t)(i * sides + (j + 1) % sides),
				 d = (uint32_t)(((i + 1) % rings) * sides + (j + 1) % sides);
			uint32_t *t = idx + 6 * (i * sides + j);
			t[0] = a, t[1] = b, t[2] = c;
			t[3] = c, t[4] = b, t[5] = d;
		}
}

/* The torus written into two memfds, vertices and indices, and sealed. */
static int torus_shared(struct shared *vs, struct shared *is, int rings, int sides)
{
	uint32_t nv = (uint32_t)(rings * sides), ni = 6 * nv;
	int r = shared_create(vs, "torus-vertices", nv * sizeof(struct vertex));
	if (r == 0)
		r = shared_create(is, "torus-indices", ni * sizeof(uint32_t));
	if (r < 0)
		return r;
	torus(vs->map, is->map, rings, sides);
	if ((r = shared_seal(vs)) < 0)
		return r;
	return shared_seal(is);
}

/* Commits and waits until shown; a refused exclusive layer is shown beside
 * the others instead. 0 or -errno. */
static int commit_shown(struct spindle *sp, struct spindle_layer *layer, uint32_t ni, struct spindle_frame *f)
{
	int r = spindle_commit_and_wait(sp, f);
	if (r == -EACCES || r == -EBUSY) {
		fprintf(stderr, "torus: exclusive layer refused (%s); showing it beside the others\n",
			r == -EACCES ? "not allowed" : "another client has one");
		spindle_layer_set_exclusive(layer, false);
		r = spindle_commit_and_wait(sp, f);
	}
	if (r == -EDQUOT)
		fprintf(stderr, "torus: %u triangles are over this client's quota: try fewer --rings\n", ni / 3);
	return r;
}

static int show(struct spindle *sp, int rings, bool exclusive)
{
	int sides = rings / 2 > 3 ? rings / 2 : 3;
	uint32_t nv = (uint32_t)(rings * sides), ni = 6 * nv;
	struct shared vs, is;
	int r = torus_shared(&vs, &is, rings, sides);
	if (r < 0)
		return r;
	struct spindle_buffer *vb = spindle_buffer_create_from_fd(sp, vs.fd, vs.size);
	struct spindle_buffer *ib = spindle_buffer_create_from_fd(sp, is.fd, is.size);
	close(vs.fd); /* libspindle keeps a duplicate until it is sent */
	close(is.fd);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	if (!vb || !ib || !list || !layer)
		return -errno;
	spindle_list_set_vertex_format(list, SPINDLE_XYZ_RGBA8);
	spindle_list_draw_indexed(list, SPINDLE_TRIANGLES, vb, 0, nv, 0, ib, 0, ni, SPINDLE_INDEX_U32);
	spindle_layer_set_list(layer, list);
	if (exclusive) {
		spindle_layer_set_priority(layer, 100);
		spindle_layer_set_exclusive(layer, true);
	}
	struct spindle_frame f;
	if ((r = commit_shown(sp, layer, ni, &f)) < 0)
		return r;
	struct spindle_status st;
	if ((r = spindle_get_status(sp, &st)) < 0)
		return r;
	printf("torus: %u triangles shown by volume %llu; %llu volumes shown, %s, %.0f rpm\n", ni / 3,
	       (unsigned long long)f.volume_seq, (unsigned long long)st.volumes_shown,
	       st.locked ? "locked" : "not locked", st.rpm);
	return 0;
}

int main(int argc, char **argv)
{
	const char *socket = NULL;
	int rings = 48;
	bool exclusive = false;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--rings") && i + 1 < argc)
			rings = atoi(argv[++i]);
		else if (!strcmp(argv[i], "--exclusive"))
			exclusive = true;
		else if (!strcmp(argv[i], "--socket") && i + 1 < argc)
			socket = argv[++i];
		else {
			bool help = !strcmp(argv[i], "--help") || !strcmp(argv[i], "-h");
			fprintf(help ? stdout : stderr, "usage: torus [--rings N] [--exclusive] [--socket PATH]\n");
			return help ? 0 : 2;
		}
	}
	if (rings < 3 || rings > 4096) {
		fprintf(stderr, "torus: --rings must be 3 to 4096\n");
		return 2;
	}
	struct spindle *sp = spindle_connect(socket);
	if (!sp) {
		fprintf(stderr, "torus: cannot connect to spindled: %s\n", strerror(errno));
		return 1;
	}
	int r = spindle_get_version(sp) >= 2 ? show(sp, rings, exclusive) : -ENOTSUP;
	if (r < 0)
		fprintf(stderr, "torus: %s\n", spindle_get_error(sp) ? spindle_get_error(sp) : strerror(-r));
	spindle_disconnect(sp);
	return r < 0 ? 1 : 0;
}
