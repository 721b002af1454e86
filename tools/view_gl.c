#include "view_gl.h"

#include <GLES3/gl3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mat4.h"

#define OUTLINE_SEGMENTS 96

static const char vertex_src[] =
	"#version 300 es\n"
	"layout(location = 0) in vec3 pos;\n"
	"layout(location = 1) in vec4 colour;\n"
	"uniform mat4 mvp;\n"
	"uniform float point_size;\n"
	"uniform float gain;\n"
	"out vec4 v_colour;\n"
	"void main() {\n"
	"  gl_Position = mvp * vec4(pos, 1.0);\n"
	"  gl_PointSize = point_size;\n"
	"  v_colour = vec4(colour.rgb * gain, 1.0);\n"
	"}\n";

static const char fragment_src[] =
	"#version 300 es\n"
	"precision mediump float;\n"
	"in vec4 v_colour;\n"
	"uniform float round_points;\n"
	"out vec4 frag;\n"
	"void main() {\n"
	"  vec2 d = gl_PointCoord - vec2(0.5);\n"
	"  if (round_points > 0.5 && dot(d, d) > 0.25) discard;\n"
	"  frag = v_colour;\n"
	"}\n";

struct view_gl {
	GLuint program, vao, vbo, outline_vao, outline_vbo;
	GLint mvp, point_size, gain, round_points;
	GLsizei count, outline_count, slice_first;
	float half_height;
};

void view_camera_default(struct view_camera *cam)
{
	*cam = (struct view_camera){ .yaw = 0.6f, .pitch = 0.35f, .distance = 3.8f };
}

static GLuint shader(GLenum type, const char *src)
{
	GLuint s = glCreateShader(type);
	glShaderSource(s, 1, &src, NULL);
	glCompileShader(s);
	GLint ok = 0;
	glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
	if (!ok) {
		char log[512] = "";
		glGetShaderInfoLog(s, sizeof(log), NULL, log);
		fprintf(stderr, "spindle-view: shader: %s\n", log);
		glDeleteShader(s);
		return 0;
	}
	return s;
}

/* The bound vertex array's layout: struct view_point, position and
 * normalised RGBA, from the bound array buffer. */
static void point_attribs(void)
{
	glEnableVertexAttribArray(0);
	glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(struct view_point), (void *)0);
	glEnableVertexAttribArray(1);
	glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(struct view_point),
			      (void *)offsetof(struct view_point, rgba));
}

/* The cylinder's rims and four posts, and (from slice_first) one slice
 * plane's outline: the vertex layout of the points, dim grey. */
static void make_outline(struct view_gl *v, float h)
{
	struct view_point pts[OUTLINE_SEGMENTS * 4 + 8 + 8];
	int n = 0;
	const uint8_t grey[4] = { 60, 60, 70, 255 }, slice[4] = { 110, 90, 30, 255 };
	for (int rim = 0; rim < 2; rim++) {
		float y = rim ? h : -h;
		for (int i = 0; i < OUTLINE_SEGMENTS; i++) {
			for (int e = 0; e < 2; e++) {
				double a = 2 * M_PI * (i + e) / OUTLINE_SEGMENTS;
				pts[n] = (struct view_point){ (float)cos(a), y, (float)sin(a), { 0 } };
				memcpy(pts[n++].rgba, grey, 4);
			}
		}
	}
	for (int i = 0; i < 4; i++) {
		double a = M_PI / 2 * i;
		for (int e = 0; e < 2; e++) {
			pts[n] = (struct view_point){ (float)cos(a), e ? h : -h, (float)sin(a), { 0 } };
			memcpy(pts[n++].rgba, grey, 4);
		}
	}
	v->slice_first = n;
	const float q[4][2] = { { -1, -1 }, { 1, -1 }, { 1, 1 }, { -1, 1 } };
	for (int i = 0; i < 4; i++) {
		for (int e = 0; e < 2; e++) {
			const float *c = q[(i + e) % 4];
			pts[n] = (struct view_point){ c[0], c[1] * h, 0.0f, { 0 } };
			memcpy(pts[n++].rgba, slice, 4);
		}
	}
	v->outline_count = n;
	glBindVertexArray(v->outline_vao);
	glBindBuffer(GL_ARRAY_BUFFER, v->outline_vbo);
	glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(n * sizeof(pts[0])), pts, GL_STATIC_DRAW);
	point_attribs();
	glBindVertexArray(0);
	v->half_height = h;
}

struct view_gl *view_gl_create(void)
{
	struct view_gl *v = calloc(1, sizeof(*v));
	if (!v)
		return NULL;
	GLuint vs = shader(GL_VERTEX_SHADER, vertex_src), fs = shader(GL_FRAGMENT_SHADER, fragment_src);
	if (!vs || !fs) {
		free(v);
		return NULL;
	}
	v->program = glCreateProgram();
	glAttachShader(v->program, vs);
	glAttachShader(v->program, fs);
	glLinkProgram(v->program);
	glDeleteShader(vs);
	glDeleteShader(fs);
	GLint ok = 0;
	glGetProgramiv(v->program, GL_LINK_STATUS, &ok);
	if (!ok) {
		fprintf(stderr, "spindle-view: the shaders do not link\n");
		glDeleteProgram(v->program);
		free(v);
		return NULL;
	}
	v->mvp = glGetUniformLocation(v->program, "mvp");
	v->point_size = glGetUniformLocation(v->program, "point_size");
	v->gain = glGetUniformLocation(v->program, "gain");
	v->round_points = glGetUniformLocation(v->program, "round_points");
	glGenVertexArrays(1, &v->vao);
	glGenBuffers(1, &v->vbo);
	glGenVertexArrays(1, &v->outline_vao);
	glGenBuffers(1, &v->outline_vbo);
	glBindVertexArray(v->vao);
	glBindBuffer(GL_ARRAY_BUFFER, v->vbo);
	point_attribs();
	glBindVertexArray(0);
	make_outline(v, 1.0f);
	return v;
}

void view_gl_destroy(struct view_gl *v)
{
	if (!v)
		return;
	glDeleteBuffers(1, &v->vbo);
	glDeleteBuffers(1, &v->outline_vbo);
	glDeleteVertexArrays(1, &v->vao);
	glDeleteVertexArrays(1, &v->outline_vao);
	glDeleteProgram(v->program);
	free(v);
}

void view_gl_upload(struct view_gl *v, const struct view_points *pts)
{
	glBindBuffer(GL_ARRAY_BUFFER, v->vbo);
	/* Orphan the old storage: no wait for draws still reading it. */
	glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(pts->count * sizeof(struct view_point)), pts->count ? pts->p : NULL,
		     GL_STREAM_DRAW);
	v->count = (GLsizei)pts->count;
	if (pts->half_height > 0 && pts->half_height != v->half_height)
		make_outline(v, pts->half_height);
}

static void camera_matrix(const struct view_camera *cam, float aspect, float out[16])
{
	/* view = translate(0, 0, -distance) * rotate_x(pitch) * rotate_y(-yaw) * translate(-pan) */
	float cy = cosf(cam->yaw), sy = sinf(cam->yaw), cp = cosf(cam->pitch), sp = sinf(cam->pitch);
	const float ry[16] = { cy, 0, sy, 0, 0, 1, 0, 0, -sy, 0, cy, 0, 0, 0, 0, 1 };
	const float rx[16] = { 1, 0, 0, 0, 0, cp, sp, 0, 0, -sp, cp, 0, 0, 0, 0, 1 };
	const float tp[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -cam->pan_x, -cam->pan_y, 0, 1 };
	const float td[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -cam->distance, 1 };
	float fov = 0.7f, f = 1.0f / tanf(fov / 2), n = 0.05f, fa = 50.0f;
	float ax = aspect >= 1 ? f / aspect : f, ay = aspect >= 1 ? f : f * aspect;
	const float proj[16] = {
		ax, 0, 0, 0, 0, ay, 0, 0, 0, 0, (fa + n) / (n - fa), -1, 0, 0, 2 * fa * n / (n - fa), 0
	};
	float m[16];
	mat4_mul(m, ry, tp);
	mat4_mul(m, rx, m);
	mat4_mul(m, td, m);
	mat4_mul(out, proj, m);
}

void view_gl_draw(struct view_gl *v, const struct view_camera *cam, int width, int height, bool slices)
{
	glViewport(0, 0, width, height);
	glClearColor(0.02f, 0.02f, 0.03f, 1.0f);
	glClear(GL_COLOR_BUFFER_BIT);
	glDisable(GL_DEPTH_TEST);
	glEnable(GL_BLEND);
	glBlendFunc(GL_ONE, GL_ONE);
	glUseProgram(v->program);
	float mvp[16];
	camera_matrix(cam, height > 0 ? (float)width / (float)height : 1.0f, mvp);
	glUniformMatrix4fv(v->mvp, 1, GL_FALSE, mvp);
	glUniform1f(v->point_size, 1.0f);
	glUniform1f(v->gain, 1.0f);
	glUniform1f(v->round_points, 0.0f);
	glBindVertexArray(v->outline_vao);
	glDrawArrays(GL_LINES, 0, slices ? v->outline_count : v->slice_first);
	/* Points about a voxel's size on screen, at least one pixel; fainter
	 * the more there are, so that density shows as brightness. */
	float px = (float)(height < width ? height : width) / (cam->distance * 400.0f);
	float size = px < 1.0f ? 1.0f : px > 6.0f ? 6.0f : px;
	float gain = v->count ? 0.6f * (float)width * (float)height / (float)v->count : 1.0f;
	gain = gain < 0.06f ? 0.06f : gain > 0.9f ? 0.9f : gain;
	glUniform1f(v->point_size, size);
	glUniform1f(v->gain, gain);
	glUniform1f(v->round_points, size >= 3.0f ? 1.0f : 0.0f);
	glBindVertexArray(v->vao);
	if (v->count)
		glDrawArrays(GL_POINTS, 0, v->count);
	glBindVertexArray(0);
}

void view_gl_read_rgb(int width, int height, uint8_t *rgb)
{
	uint8_t *rgba = malloc((size_t)width * height * 4);
	if (!rgba) {
		memset(rgb, 0, (size_t)width * height * 3);
		return;
	}
	glPixelStorei(GL_PACK_ALIGNMENT, 1);
	glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
	for (int y = 0; y < height; y++) {
		const uint8_t *src = rgba + (size_t)(height - 1 - y) * width * 4;
		uint8_t *dst = rgb + (size_t)y * width * 3;
		for (int x = 0; x < width; x++) {
			dst[3 * x] = src[4 * x];
			dst[3 * x + 1] = src[4 * x + 1];
			dst[3 * x + 2] = src[4 * x + 2];
		}
	}
	free(rgba);
}
