#include "shapes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void vbuf_add(struct vbuf *b, double x, double y, double z)
{
	if (b->oom)
		return;
	if (b->count == b->cap) {
		uint32_t cap = b->cap ? 2 * b->cap : 1024;
		float *xyz = realloc(b->xyz, (size_t)cap * 3 * sizeof(float));
		if (!xyz) {
			b->oom = true;
			return;
		}
		b->xyz = xyz;
		b->cap = cap;
	}
	float *p = b->xyz + (size_t)b->count * 3;
	p[0] = (float)x;
	p[1] = (float)y;
	p[2] = (float)z;
	b->count++;
}

void vbuf_free(struct vbuf *b)
{
	free(b->xyz);
	memset(b, 0, sizeof(*b));
}

static void add_segment(struct vbuf *b, const double p[3], const double q[3])
{
	vbuf_add(b, p[0], p[1], p[2]);
	vbuf_add(b, q[0], q[1], q[2]);
}

/* Point of the sphere at longitude step i and latitude step j (j = 0: the
 * north pole, j = stacks: the south pole). */
static void sphere_point(double out[3], double r, uint32_t i, uint32_t j, uint32_t slices, uint32_t stacks)
{
	double lat = M_PI / 2 - M_PI * j / stacks, lon = 2 * M_PI * i / slices;
	out[0] = r * cos(lat) * cos(lon);
	out[1] = r * sin(lat);
	out[2] = r * cos(lat) * sin(lon);
}

uint32_t shape_sphere_edges(struct vbuf *b, double r, uint32_t slices, uint32_t stacks)
{
	uint32_t n = 0;
	for (uint32_t i = 0; i < slices; i++) {
		for (uint32_t j = 0; j < stacks; j++) {
			double p[3], q[3];
			sphere_point(p, r, i, j, slices, stacks);
			sphere_point(q, r, i, j + 1, slices, stacks);
			add_segment(b, p, q);
			n++;
			if (j == 0)
				continue;
			sphere_point(q, r, i + 1, j, slices, stacks);
			add_segment(b, p, q);
			n++;
		}
	}
	return n;
}

static void torus_point(double out[3], double R, double r, uint32_t i, uint32_t j, uint32_t major, uint32_t minor)
{
	double a = 2 * M_PI * i / major, t = 2 * M_PI * j / minor;
	double d = R + r * cos(t);
	out[0] = d * cos(a);
	out[1] = r * sin(t);
	out[2] = d * sin(a);
}

uint32_t shape_torus_edges(struct vbuf *b, double R, double r, uint32_t major, uint32_t minor)
{
	uint32_t n = 0;
	for (uint32_t i = 0; i < major; i++) {
		for (uint32_t j = 0; j < minor; j++) {
			double p[3], q[3];
			torus_point(p, R, r, i, j, major, minor);
			torus_point(q, R, r, i + 1, j, major, minor);
			add_segment(b, p, q);
			torus_point(q, R, r, i, j + 1, major, minor);
			add_segment(b, p, q);
			n += 2;
		}
	}
	return n;
}

static void helix_point(double out[3], double r, double height, double turns, double f)
{
	double a = 2 * M_PI * turns * f;
	out[0] = r * cos(a);
	out[1] = height * (f - 0.5);
	out[2] = r * sin(a);
}

uint32_t shape_helix(struct vbuf *b, double r, double height, double turns, uint32_t segments)
{
	for (uint32_t i = 0; i < segments; i++) {
		double p[3], q[3];
		helix_point(p, r, height, turns, (double)i / segments);
		helix_point(q, r, height, turns, (double)(i + 1) / segments);
		add_segment(b, p, q);
	}
	return segments;
}

/* The 12 vertices (0, +-1, +-phi) and their cyclic permutations; the faces
 * are the 20 vertex triples at mutual distance 2 (the edge length). */
static void icosahedron_vertices(double v[12][3])
{
	const double phi = (1 + sqrt(5.0)) / 2;
	int n = 0;
	for (int axis = 0; axis < 3; axis++) {
		for (int s = 0; s < 4; s++) {
			double a = (s & 1) ? -1 : 1, c = (s & 2) ? -phi : phi;
			v[n][axis] = 0;
			v[n][(axis + 1) % 3] = a;
			v[n][(axis + 2) % 3] = c;
			n++;
		}
	}
}

static bool is_edge(const double p[3], const double q[3])
{
	double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
	return fabs(dx * dx + dy * dy + dz * dz - 4.0) < 1e-6;
}

uint32_t shape_icosahedron(struct vbuf *b, double r)
{
	double v[12][3];
	icosahedron_vertices(v);
	double k = r / sqrt(1 + (1 + sqrt(5.0)) * (1 + sqrt(5.0)) / 4);
	uint32_t n = 0;
	for (int i = 0; i < 12; i++)
		for (int j = i + 1; j < 12; j++)
			for (int l = j + 1; l < 12; l++) {
				if (!is_edge(v[i], v[j]) || !is_edge(v[j], v[l]) || !is_edge(v[i], v[l]))
					continue;
				vbuf_add(b, k * v[i][0], k * v[i][1], k * v[i][2]);
				vbuf_add(b, k * v[j][0], k * v[j][1], k * v[j][2]);
				vbuf_add(b, k * v[l][0], k * v[l][1], k * v[l][2]);
				n++;
			}
	return n;
}

void shape_sphere_fit(uint32_t budget, uint32_t *slices, uint32_t *stacks)
{
	uint32_t st = 2;
	while ((uint64_t)2 * (st + 1) * (2 * (st + 1) - 1) <= budget)
		st++;
	*stacks = st;
	*slices = 2 * st;
}

void shape_torus_fit(uint32_t budget, uint32_t *major, uint32_t *minor)
{
	uint32_t n = 2;
	while ((uint64_t)4 * (n + 1) * (n + 1) <= budget)
		n++;
	*minor = n;
	*major = 2 * n;
}

void mat4_pose(float out[16], const double t[3], double ax, double ay, double s)
{
	double cx = cos(ax), sx = sin(ax), cy = cos(ay), sy = sin(ay);
	/* Columns of R = Ry * Rx, times s. */
	double m[16] = {
		cy * s,      0,       -sy * s,     0, sy * sx * s, cx * s, cy * sx * s, 0,
		sy * cx * s, -sx * s, cy * cx * s, 0, t[0],        t[1],   t[2],        1,
	};
	for (int i = 0; i < 16; i++)
		out[i] = (float)m[i];
}
