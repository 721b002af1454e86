/* spindle-view: drawing a point cloud of lit voxels with OpenGL ES 3 in the
 * context current on the calling thread (an SDL window's, or an offscreen
 * EGL one): points blended additively, so that dense areas look brighter,
 * and a faint outline of the display cylinder. */
#ifndef SPINDLE_TOOLS_VIEW_GL_H
#define SPINDLE_TOOLS_VIEW_GL_H

#include <stdbool.h>
#include <stdint.h>

#include "view_points.h"

/* The eye: orbiting the point (pan_x, pan_y, 0) of volume space (y up) at
 * yaw (about y, from +z towards +x) and pitch (above the horizon), radians,
 * distance radii away. */
struct view_camera {
	float yaw, pitch, distance;
	float pan_x, pan_y;
};

void view_camera_default(struct view_camera *cam);

struct view_gl;

/* Compiles the shaders: NULL when the context cannot (message on stderr). */
struct view_gl *view_gl_create(void);
void view_gl_destroy(struct view_gl *v);
/* Uploads the points (one vertex buffer, replaced per volume). */
void view_gl_upload(struct view_gl *v, const struct view_points *pts);
/* Draws into the bound framebuffer, width x height pixels. slices: also
 * the outline of one slice plane of image 0 (the 's' key). */
void view_gl_draw(struct view_gl *v, const struct view_camera *cam, int width, int height, bool slices);
/* Reads the bound framebuffer back as RGB rows top to bottom. */
void view_gl_read_rgb(int width, int height, uint8_t *rgb);

#endif
