/* The shapes spindle-bench-brightness shows (brightness_shapes.h). */
#include "brightness_shapes.h"

#include <math.h>

/* Longest edge of a triangle of the disk and the sphere, and the grid of
 * the wall, in pixels; tube facets are at most TUBE_FACET_PX wide. */
#define MESH_STEP_PX 4.0
#define TUBE_FACET_PX 0.5
/* Edges of the wall and tubes lie this far inside a row's boundary, so
 * that they light whole rows and no more. */
#define ROW_INSET_PX 0.05

/* Point i of a horizontal ring of m points, radius r, at height y. The same
 * i always gives the same point, so that stitched rings share vertices. */
static void ring_vertex(struct vbuf *b, double r, double y, unsigned m, unsigned i)
{
	double a = 2.0 * M_PI * (i % m) / m;
	vbuf_add(b, r * cos(a), y, r * sin(a));
}

/* Triangles between two rings of ma and mb points (a ring of one point is
 * a pole or the centre), walking both by angle. */
static void stitch(struct vbuf *b, double ra, double ya, unsigned ma, double rb, double yb, unsigned mb)
{
	unsigned i = 0, j = 0;
	while (i < ma || j < mb) {
		bool advance_a = j == mb || (i < ma && (uint64_t)(i + 1) * mb < (uint64_t)(j + 1) * ma);
		if (advance_a ? ma > 1 : mb > 1) {
			ring_vertex(b, ra, ya, ma, i);
			ring_vertex(b, rb, yb, mb, j);
			if (advance_a)
				ring_vertex(b, ra, ya, ma, i + 1);
			else
				ring_vertex(b, rb, yb, mb, j + 1);
		}
		if (advance_a)
			i++;
		else
			j++;
	}
}

static unsigned ring_points(double r_px)
{
	unsigned m = (unsigned)ceil(2.0 * M_PI * r_px / MESH_STEP_PX);
	return r_px > 0.0 ? (m < 8 ? 8 : m) : 1;
}

double light_shape_row_y(const struct light_device *d, double v)
{
	return d->half_height - v * d->row;
}

/* Horizontal disk of radius 1 at the middle of row H/2: rings MESH_STEP_PX
 * apart, each with points MESH_STEP_PX apart. */
void light_shape_disk(struct vbuf *m, const struct light_device *d)
{
	double rim = d->w / 2.0;
	unsigned rings = (unsigned)ceil(rim / MESH_STEP_PX);
	for (unsigned i = 0; i < rings; i++) {
		double a = i * MESH_STEP_PX, b = i + 1 == rings ? rim : (i + 1) * MESH_STEP_PX;
		stitch(m, a * d->px, d->y_mid, ring_points(a), b * d->px, d->y_mid, ring_points(b));
	}
}

/* Vertical rectangle through the axis at azimuth theta, s from -1 to 1,
 * rows v0 .. v1 - 1: a grid of cells at most MESH_STEP_PX square. */
void light_shape_wall(struct vbuf *m, const struct light_device *d, double theta)
{
	unsigned ns = 2 * (unsigned)ceil(d->w / 2.0 / MESH_STEP_PX); /* even: s = 0 is a grid line */
	unsigned nv = (unsigned)ceil((d->v1 - d->v0) / MESH_STEP_PX);
	double c = cos(theta), sn = sin(theta);
	for (unsigned i = 0; i < ns; i++)
		for (unsigned j = 0; j < nv; j++) {
			double s0 = -1.0 + 2.0 * i / ns, s1 = -1.0 + 2.0 * (i + 1) / ns;
			double y0 = d->y_top + (d->y_bottom - d->y_top) * j / nv;
			double y1 = d->y_top + (d->y_bottom - d->y_top) * (j + 1) / nv;
			static const int quad[6][2] = { { 0, 0 }, { 1, 0 }, { 1, 1 }, { 0, 0 }, { 1, 1 }, { 0, 1 } };
			for (int k = 0; k < 6; k++) {
				double s = quad[k][0] ? s1 : s0, y = quad[k][1] ? y1 : y0;
				vbuf_add(m, s * c, y, s * sn);
			}
		}
}

/* Vertical cylinder of radius r_px pixels over rows v0 .. v1 - 1, facets at
 * most TUBE_FACET_PX wide, each two triangles the tube's height. */
void light_shape_tube(struct vbuf *m, const struct light_device *d, double r_px)
{
	unsigned f = (unsigned)ceil(2.0 * M_PI * r_px / TUBE_FACET_PX);
	if (f < 16)
		f = 16;
	double r = r_px * d->px;
	for (unsigned i = 0; i < f; i++) {
		ring_vertex(m, r, d->y_top, f, i);
		ring_vertex(m, r, d->y_bottom, f, i);
		ring_vertex(m, r, d->y_bottom, f, i + 1);
		ring_vertex(m, r, d->y_top, f, i);
		ring_vertex(m, r, d->y_bottom, f, i + 1);
		ring_vertex(m, r, d->y_top, f, i + 1);
	}
}

/* Sphere of radius r_px pixels centred on the axis: rings of latitude
 * MESH_STEP_PX apart along the surface, stitched. */
void light_shape_sphere(struct vbuf *m, const struct light_device *d, double r_px)
{
	unsigned lat = (unsigned)ceil(M_PI * r_px / MESH_STEP_PX);
	if (lat < 8)
		lat = 8;
	double r = r_px * d->px;
	for (unsigned i = 0; i < lat; i++) {
		double t0 = M_PI * i / lat, t1 = M_PI * (i + 1) / lat;
		double ra = i == 0 ? 0.0 : r * sin(t0), rb = i + 1 == lat ? 0.0 : r * sin(t1);
		stitch(m, ra, r * cos(t0), ring_points(ra / d->px), rb, r * cos(t1), ring_points(rb / d->px));
	}
}

/* Horizontal circle of radius r_px at the middle of row H/2 as a closed
 * line strip, segments about a pixel long. */
void light_shape_ring(struct vbuf *m, const struct light_device *d, double r_px)
{
	unsigned n = (unsigned)ceil(2.0 * M_PI * r_px);
	if (n < 32)
		n = 32;
	for (unsigned i = 0; i <= n; i++)
		ring_vertex(m, r_px * d->px, d->y_mid, n, i);
}

void light_shape_device(struct light_device *d, const struct spindle_device_info *info)
{
	*d = (struct light_device){
		.w = info->width,
		.h = info->height,
		.n = info->images_per_rev,
		.mirrored = info->mirrored,
		.half_height = info->half_height,
	};
	d->r0 = d->n / (2.0 * M_PI);
	d->px = 2.0 / d->w;
	d->row = 2.0 * d->half_height / d->h;
	d->y_mid = light_shape_row_y(d, d->h / 2 + 0.5);
	d->v0 = d->h / 4;
	d->v1 = d->h - d->h / 4;
	d->y_top = light_shape_row_y(d, d->v0 + ROW_INSET_PX);
	d->y_bottom = light_shape_row_y(d, d->v1 - ROW_INSET_PX);
}
