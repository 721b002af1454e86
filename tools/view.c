/* spindle-view: the volume spindled shows, live, as a 3-D point cloud of its
 * lit voxels in their colours (a watcher, display.watch: protocol 5), in an
 * SDL2 window with OpenGL ES 3; or a turntable of a volume (live or from a
 * capture file) rendered offscreen with EGL into one PNG contact sheet.
 * See spindle-view(1). */
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>
#include <SDL.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <poll.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <spindle/spindle.h>

#include "preview.h"
#include "svol.h"
#include "view_gl.h"
#include "view_points.h"
#include "wvol.h"

/* Exit statuses, as spindlectl's. */
enum { VIEW_OK = 0, VIEW_FAILED = 1, VIEW_USAGE = 2, VIEW_CONNECT = 3, VIEW_REFUSED = 4, VIEW_INPUT = 5 };

/* Points drawn at most: a fixed --max-points, or adapted so that a frame
 * takes about ADAPT_LOW_S to ADAPT_HIGH_S to upload and draw (a software
 * rasterizer draws a few million points a second), starting here. */
#define DEFAULT_MAX_POINTS 1000000
#define ADAPT_MIN_POINTS 200000
#define ADAPT_MAX_POINTS 8000000
#define ADAPT_LOW_S 0.03
#define ADAPT_HIGH_S 0.06

struct view_args {
	const char *socket;
	const char *input;     /* --input FILE.svol */
	const char *turntable; /* --turntable OUT.png */
	const char *snapshot;  /* --snapshot OUT.png */
	uint32_t rate;         /* --rate HZ, 0: the daemon's */
	uint32_t frames;       /* turntable frames */
	uint32_t size;         /* turntable frame size, px */
	uint32_t exit_after;   /* volumes, then exit (0: never) */
	uint32_t width, height;
	size_t max_points;
	bool adapt; /* no --max-points: adapt it to the drawing speed */
	bool stats;
	bool slices;
};

static const char usage_text[] =
	"usage: spindle-view [OPTIONS]\n"
	"  live, in a window:  spindle-view [--socket PATH] [--rate HZ]\n"
	"  turntable PNG:      spindle-view --turntable OUT.png [--frames N] [--size PX]\n"
	"                                   [--input FILE.svol | --socket PATH]\n"
	"\n"
	"options:\n"
	"  -s, --socket PATH       daemon socket (default: $SPINDLE_SOCKET, else\n"
	"                          " SPINDLE_DEFAULT_SOCKET ")\n"
	"  -r, --rate HZ           at most HZ volumes a second (default: the daemon's\n"
	"                          max-watch-rate)\n"
	"  -i, --input FILE.svol   show a captured volume instead of the daemon's\n"
	"  -t, --turntable OUT.png render an orbit of the volume offscreen into one\n"
	"                          PNG contact sheet, without a window\n"
	"  -n, --frames N          turntable frames (default 12)\n"
	"  -z, --size PX           turntable frame size (default 256)\n"
	"  -o, --snapshot OUT.png  window: write the last frame drawn at exit\n"
	"  -x, --exit-after N      window: exit after N volumes were drawn\n"
	"  -g, --geometry WxH      window size (default 800x800)\n"
	"  -m, --max-points N      draw at most N voxels, every k-th (default: adapted\n"
	"                          to the drawing speed, from 1000000)\n"
	"  -S, --slices            outline the plane of image 0 (key s toggles)\n"
	"  -v, --stats             print volumes received and the rate at exit\n"
	"  -h, --help              this help\n"
	"\n"
	"mouse: left drag orbits, right (or middle) drag pans, the wheel zooms;\n"
	"keys: s slice plane, r reset the view, q or Escape quits.\n";

static int usage_error(const char *what)
{
	fprintf(stderr, "spindle-view: %s\n%s", what, usage_text);
	return VIEW_USAGE;
}

static bool parse_u32(const char *s, uint32_t lo, uint32_t hi, uint32_t *out)
{
	char *end;
	errno = 0;
	unsigned long v = strtoul(s, &end, 10);
	if (errno || end == s || *end || v < lo || v > hi)
		return false;
	*out = (uint32_t)v;
	return true;
}

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

/* ---- volumes in ---- */

static struct volume *read_input(const char *path)
{
	FILE *f = fopen(path, "rb");
	if (!f) {
		fprintf(stderr, "spindle-view: %s: %s\n", path, strerror(errno));
		return NULL;
	}
	struct volume *vol = svol_read(f);
	int e = errno;
	fclose(f);
	if (!vol)
		fprintf(stderr, "spindle-view: %s: %s\n", path, e == EINVAL ? "not a valid .svol file" : strerror(e));
	return vol;
}

/* The live side: a connection and its watcher; each volume received is
 * turned into points at once and released, so the daemon may send the
 * next while this one is drawn. */
struct live {
	struct spindle *sp;
	struct spindle_watcher *watcher;
	struct view_points pts;
	size_t max_points;
	bool fresh;  /* pts changed since the last upload */
	bool failed; /* the watcher ended, or a volume was unusable */
	uint64_t received, skipped;
	double first_s, last_s;
	double convert_s; /* decoding and making points, summed */
	double draw_s;    /* uploading and drawing, summed (the window's) */
	uint64_t draws;
	size_t points; /* the last volume's */
};

static void on_volume(void *data, struct spindle_watcher *w, const struct spindle_watch_volume *v)
{
	struct live *l = data;
	if (!v) {
		l->failed = true;
		return;
	}
	double t0 = now_s();
	struct volume *vol = wvol_decode(v->data, v->size);
	spindle_watch_release(w);
	if (!vol) {
		fprintf(stderr, "spindle-view: the daemon sent an unusable volume\n");
		l->failed = true;
		return;
	}
	if (view_points_from_volume(&l->pts, vol, l->max_points) == 0) {
		l->fresh = true;
		l->received++;
		l->skipped += v->skipped;
		l->last_s = now_s();
		if (l->received == 1)
			l->first_s = l->last_s;
		l->convert_s += l->last_s - t0;
		l->points = l->pts.count;
	}
	volume_destroy(vol);
}

static int live_open(struct live *l, const struct view_args *a)
{
	*l = (struct live){ .max_points = a->max_points };
	l->sp = spindle_connect(a->socket);
	if (!l->sp) {
		fprintf(stderr, "spindle-view: cannot connect to spindled: %s\n", strerror(errno));
		return VIEW_CONNECT;
	}
	l->watcher = spindle_watch_create(l->sp, a->rate, on_volume, l);
	if (!l->watcher) {
		fprintf(stderr, "spindle-view: cannot watch: %s\n",
			errno == EPROTONOSUPPORT ? "the daemon is older than protocol 5" : strerror(errno));
		spindle_disconnect(l->sp);
		l->sp = NULL;
		return errno == EPROTONOSUPPORT ? VIEW_CONNECT : VIEW_FAILED;
	}
	return VIEW_OK;
}

/* Reads what the daemon sent, waiting up to timeout_ms. VIEW_OK or the
 * exit status of a failure (reported). */
static int live_pump(struct live *l, int timeout_ms)
{
	struct pollfd pfd = { spindle_get_fd(l->sp), POLLIN, 0 };
	if (poll(&pfd, 1, timeout_ms) > 0 && spindle_dispatch(l->sp) < 0) {
		fprintf(stderr, "spindle-view: %s\n", spindle_get_error(l->sp));
		return VIEW_FAILED;
	}
	if (l->failed) {
		int e = spindle_watch_get_error(l->watcher);
		if (e == -EACCES) {
			fprintf(stderr, "spindle-view: watching refused: only root, the daemon's user and members of "
					"its admin group may watch (as capture)\n");
			return VIEW_REFUSED;
		}
		fprintf(stderr, "spindle-view: the daemon ended the watcher: %s\n",
			e == -EUSERS ? "it has max-watchers watchers" : strerror(e ? -e : EIO));
		return e == -EUSERS ? VIEW_REFUSED : VIEW_FAILED;
	}
	return VIEW_OK;
}

static void live_close(struct live *l, bool stats)
{
	if (stats && l->received) {
		double t = l->last_s - l->first_s;
		printf("volumes %llu, skipped %llu, %.1f volumes/s; last %zu points; per volume %.1f ms decoding, "
		       "%.1f ms uploading and drawing\n",
		       (unsigned long long)l->received, (unsigned long long)l->skipped,
		       t > 0 ? (double)(l->received - 1) / t : 0.0, l->points, l->convert_s * 1e3 / (double)l->received,
		       l->draws ? l->draw_s * 1e3 / (double)l->draws : 0.0);
	}
	spindle_watch_destroy(l->watcher);
	if (l->sp)
		spindle_disconnect(l->sp);
	view_points_free(&l->pts);
}

/* ---- the turntable: offscreen EGL ---- */

static bool has_word(const char *list, const char *word)
{
	size_t n = strlen(word);
	for (const char *p = list; p && (p = strstr(p, word)); p += n)
		if ((p == list || p[-1] == ' ') && (p[n] == ' ' || !p[n]))
			return true;
	return false;
}

struct offscreen {
	EGLDisplay dpy;
	EGLContext ctx;
	EGLSurface surf;
	GLuint fbo, rb;
};

/* The EGL display: surfaceless (Mesa) if it can be, else the default. */
static int offscreen_display(struct offscreen *o)
{
	const char *client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
	PFNEGLGETPLATFORMDISPLAYEXTPROC get =
		(PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
	EGLint major, minor;
	if (get && has_word(client, "EGL_MESA_platform_surfaceless")) {
		o->dpy = get(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
		if (o->dpy != EGL_NO_DISPLAY && !eglInitialize(o->dpy, &major, &minor))
			o->dpy = EGL_NO_DISPLAY;
	}
	if (o->dpy == EGL_NO_DISPLAY) {
		o->dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY);
		if (o->dpy != EGL_NO_DISPLAY && !eglInitialize(o->dpy, &major, &minor))
			o->dpy = EGL_NO_DISPLAY;
	}
	if (o->dpy == EGL_NO_DISPLAY) {
		fprintf(stderr, "spindle-view: no EGL display (error 0x%x)\n", eglGetError());
		return -1;
	}
	return 0;
}

/* An OpenGL ES 3 context on the display, made current: without a surface
 * if it can be, else on a 1x1 pbuffer. */
static int offscreen_context(struct offscreen *o)
{
	bool surfaceless = has_word(eglQueryString(o->dpy, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context");
	const EGLint want[] = { EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT_KHR, EGL_SURFACE_TYPE,
				surfaceless ? 0 : EGL_PBUFFER_BIT, EGL_NONE };
	EGLConfig cfg;
	EGLint n = 0;
	if (!eglBindAPI(EGL_OPENGL_ES_API) || !eglChooseConfig(o->dpy, want, &cfg, 1, &n) || n < 1) {
		fprintf(stderr, "spindle-view: no EGL config for OpenGL ES 3\n");
		return -1;
	}
	const EGLint attrs[] = { EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE };
	o->ctx = eglCreateContext(o->dpy, cfg, EGL_NO_CONTEXT, attrs);
	if (o->ctx == EGL_NO_CONTEXT) {
		fprintf(stderr, "spindle-view: no OpenGL ES 3 context (EGL error 0x%x)\n", eglGetError());
		return -1;
	}
	if (!surfaceless) {
		const EGLint pb[] = { EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE };
		o->surf = eglCreatePbufferSurface(o->dpy, cfg, pb);
	}
	if (!eglMakeCurrent(o->dpy, o->surf, o->surf, o->ctx)) {
		fprintf(stderr, "spindle-view: eglMakeCurrent failed (0x%x)\n", eglGetError());
		return -1;
	}
	return 0;
}

/* The framebuffer drawn into: one size x size RGBA renderbuffer. */
static int offscreen_framebuffer(struct offscreen *o, int size)
{
	glGenFramebuffers(1, &o->fbo);
	glGenRenderbuffers(1, &o->rb);
	glBindRenderbuffer(GL_RENDERBUFFER, o->rb);
	glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, size, size);
	glBindFramebuffer(GL_FRAMEBUFFER, o->fbo);
	glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, o->rb);
	if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
		fprintf(stderr, "spindle-view: the offscreen framebuffer is incomplete\n");
		return -1;
	}
	return 0;
}

static int offscreen_open(struct offscreen *o, int size)
{
	*o = (struct offscreen){ .dpy = EGL_NO_DISPLAY, .ctx = EGL_NO_CONTEXT, .surf = EGL_NO_SURFACE };
	if (offscreen_display(o) < 0 || offscreen_context(o) < 0)
		return -1;
	return offscreen_framebuffer(o, size);
}

static void offscreen_close(struct offscreen *o)
{
	if (o->dpy == EGL_NO_DISPLAY)
		return;
	if (o->ctx != EGL_NO_CONTEXT) {
		glDeleteFramebuffers(1, &o->fbo);
		glDeleteRenderbuffers(1, &o->rb);
		eglMakeCurrent(o->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
		eglDestroyContext(o->dpy, o->ctx);
	}
	if (o->surf != EGL_NO_SURFACE)
		eglDestroySurface(o->dpy, o->surf);
	/* No eglTerminate(), as the daemon's GL renderer: the display is the
	 * process's, and terminating it unloads the driver, whose few blocks
	 * kept for the process's life would then read as leaks. */
	eglReleaseThread();
}

/* The points of the --input file. VIEW_OK or the exit status of a
 * failure. */
static int input_points(const struct view_args *a, struct view_points *pts)
{
	struct volume *vol = read_input(a->input);
	if (!vol)
		return VIEW_INPUT;
	int r = view_points_from_volume(pts, vol, a->max_points);
	volume_destroy(vol);
	return r < 0 ? VIEW_FAILED : VIEW_OK;
}

/* The points of the volume to turn: from the file, or the next volume the
 * daemon shows. */
static int turntable_points(const struct view_args *a, struct view_points *pts)
{
	if (a->input)
		return input_points(a, pts);
	struct live l;
	int status = live_open(&l, a);
	while (status == VIEW_OK && !l.fresh)
		status = live_pump(&l, 1000);
	if (status == VIEW_OK) {
		*pts = l.pts;
		l.pts = (struct view_points){ 0 };
	}
	live_close(&l, false);
	return status;
}

/* Draws the turntable's frames, each into its place on the sheet (cols
 * frames a row, sw pixels wide). */
static void draw_turntable(struct view_gl *gl, const struct view_args *a, uint8_t *sheet, uint8_t *frame, uint32_t cols,
			   uint32_t sw)
{
	int size = (int)a->size;
	struct view_camera cam;
	view_camera_default(&cam);
	for (uint32_t i = 0; i < a->frames; i++) {
		cam.yaw = (float)(2 * M_PI * i / a->frames);
		view_gl_draw(gl, &cam, size, size, a->slices);
		view_gl_read_rgb(size, size, frame);
		uint32_t x0 = (i % cols) * a->size, y0 = (i / cols) * a->size;
		for (int y = 0; y < size; y++)
			memcpy(sheet + ((size_t)(y0 + y) * sw + x0) * 3, frame + (size_t)y * size * 3,
			       (size_t)size * 3);
	}
}

static int run_turntable(const struct view_args *a)
{
	struct view_points pts = { 0 };
	int status = turntable_points(a, &pts);
	if (status != VIEW_OK)
		return status;
	int size = (int)a->size;
	uint32_t cols = (uint32_t)ceil(sqrt((double)a->frames));
	uint32_t rows = (a->frames + cols - 1) / cols;
	uint32_t sw = cols * a->size, sh = rows * a->size;
	uint8_t *sheet = calloc((size_t)sw * sh, 3), *frame = malloc((size_t)size * size * 3);
	struct offscreen o = { .dpy = EGL_NO_DISPLAY }; /* closed as it is when the allocations fail */
	struct view_gl *gl = NULL;
	status = VIEW_FAILED;
	if (!sheet || !frame || offscreen_open(&o, size) < 0 || !(gl = view_gl_create()))
		goto out;
	view_gl_upload(gl, &pts);
	draw_turntable(gl, a, sheet, frame, cols, sw);
	if (glGetError() != GL_NO_ERROR) {
		fprintf(stderr, "spindle-view: GL error while rendering\n");
		goto out;
	}
	int r = preview_write_png(a->turntable, sheet, sw, sh);
	if (r < 0) {
		fprintf(stderr, "spindle-view: %s: %s\n", a->turntable, strerror(-r));
		goto out;
	}
	printf("turntable: %u frames of %ux%u, %zu points of %llu lit voxels -> %s\n", a->frames, a->size, a->size,
	       pts.count, (unsigned long long)pts.lit, a->turntable);
	status = VIEW_OK;
out:
	view_gl_destroy(gl);
	offscreen_close(&o);
	free(sheet);
	free(frame);
	view_points_free(&pts);
	return status;
}

/* ---- the window ---- */

struct window {
	SDL_Window *win;
	SDL_GLContext ctx;
	struct view_gl *gl;
	struct view_camera cam;
	bool slices, dirty, quit;
	bool orbiting, panning;
};

static int window_open(struct window *w, const struct view_args *a)
{
	*w = (struct window){ .slices = a->slices, .dirty = true };
	view_camera_default(&w->cam);
	/* OpenGL ES through EGL on X11 too (Wayland is EGL anyway). */
	SDL_SetHint(SDL_HINT_VIDEO_X11_FORCE_EGL, "1");
	if (SDL_Init(SDL_INIT_VIDEO) < 0) {
		fprintf(stderr, "spindle-view: SDL: %s\n", SDL_GetError());
		return -1;
	}
	/* Held (once more than the window holds it) until exit: see
	 * window_close(). */
	if (SDL_GL_LoadLibrary(NULL) < 0) {
		fprintf(stderr, "spindle-view: SDL: no GL library: %s\n", SDL_GetError());
		return -1;
	}
	SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_ES);
	SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
	SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 0);
	SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
	w->win = SDL_CreateWindow("spindle-view", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, (int)a->width,
				  (int)a->height, SDL_WINDOW_OPENGL | SDL_WINDOW_RESIZABLE);
	if (!w->win || !(w->ctx = SDL_GL_CreateContext(w->win))) {
		fprintf(stderr, "spindle-view: no OpenGL ES 3 window: %s\n", SDL_GetError());
		return -1;
	}
	SDL_GL_SetSwapInterval(1);
	w->gl = view_gl_create();
	return w->gl ? 0 : -1;
}

static void window_close(struct window *w)
{
	view_gl_destroy(w->gl);
	if (w->ctx)
		SDL_GL_DeleteContext(w->ctx);
	if (w->win)
		SDL_DestroyWindow(w->win);
	/* No SDL_GL_UnloadLibrary() or SDL_Quit() before exit: they terminate
	 * the EGL display, and the driver unloads with the blocks it keeps
	 * for the process's life, which would then read as leaks; the
	 * process ends next anyway. */
}

/* A key: q or Escape quits, s toggles the slice plane, r resets the view. */
static void window_key(struct window *w, SDL_Keycode sym)
{
	switch (sym) {
	case SDLK_q:
	case SDLK_ESCAPE:
		w->quit = true;
		break;
	case SDLK_s:
		w->slices = !w->slices;
		w->dirty = true;
		break;
	case SDLK_r:
		view_camera_default(&w->cam);
		w->dirty = true;
		break;
	}
}

/* The mouse moved: a left drag orbits, another pans. */
static void window_motion(struct window *w, const SDL_MouseMotionEvent *m)
{
	if (w->orbiting) {
		w->cam.yaw -= (float)m->xrel * 0.01f;
		w->cam.pitch += (float)m->yrel * 0.01f;
		w->cam.pitch = fmaxf(-1.5f, fminf(1.5f, w->cam.pitch));
		w->dirty = true;
	} else if (w->panning) {
		float k = w->cam.distance * 0.0015f;
		w->cam.pan_x -= (float)m->xrel * k * cosf(w->cam.yaw);
		w->cam.pan_y += (float)m->yrel * k;
		w->dirty = true;
	}
}

static void window_event(struct window *w, const SDL_Event *e)
{
	switch (e->type) {
	case SDL_QUIT:
		w->quit = true;
		break;
	case SDL_WINDOWEVENT:
		w->dirty = true;
		break;
	case SDL_KEYDOWN:
		window_key(w, e->key.keysym.sym);
		break;
	case SDL_MOUSEBUTTONDOWN:
	case SDL_MOUSEBUTTONUP: {
		bool down = e->type == SDL_MOUSEBUTTONDOWN;
		if (e->button.button == SDL_BUTTON_LEFT)
			w->orbiting = down;
		else
			w->panning = down;
		break;
	}
	case SDL_MOUSEMOTION:
		window_motion(w, &e->motion);
		break;
	case SDL_MOUSEWHEEL:
		w->cam.distance *= e->wheel.y > 0 ? 0.9f : 1.1f;
		w->cam.distance = fmaxf(1.2f, fminf(20.0f, w->cam.distance));
		w->dirty = true;
		break;
	}
}

static int write_snapshot(const char *path, int width, int height)
{
	uint8_t *rgb = malloc((size_t)width * height * 3);
	if (!rgb)
		return -ENOMEM;
	view_gl_read_rgb(width, height, rgb);
	int r = preview_write_png(path, rgb, (uint32_t)width, (uint32_t)height);
	free(rgb);
	return r;
}

/* Thins the cloud when a frame took too long, thickens it when there is
 * time (the point budget --max-points set adaptively). */
static void adapt_points(struct live *l, double dt)
{
	if (dt > ADAPT_HIGH_S && l->max_points > ADAPT_MIN_POINTS)
		l->max_points = l->max_points * 7 / 10 > ADAPT_MIN_POINTS ? l->max_points * 7 / 10 : ADAPT_MIN_POINTS;
	else if (dt < ADAPT_LOW_S && l->pts.stride > 1 && l->max_points < ADAPT_MAX_POINTS)
		l->max_points = l->max_points * 5 / 4;
}

/* Draws the window's frame (and its snapshot, on the last). Returns whether
 * it was the last (--exit-after); a failed snapshot sets *status. */
static bool draw_frame(struct window *w, struct live *l, const struct view_args *a, int *status)
{
	double t0 = now_s();
	int width, height;
	SDL_GL_GetDrawableSize(w->win, &width, &height);
	view_gl_draw(w->gl, &w->cam, width, height, w->slices);
	uint64_t drawn = l->received;
	bool last = a->exit_after && drawn >= a->exit_after;
	if (last && a->snapshot) {
		int r = write_snapshot(a->snapshot, width, height);
		if (r < 0) {
			fprintf(stderr, "spindle-view: %s: %s\n", a->snapshot, strerror(-r));
			*status = VIEW_FAILED;
		}
	}
	SDL_GL_SwapWindow(w->win);
	w->dirty = false;
	double dt = now_s() - t0;
	l->draw_s += dt;
	l->draws++;
	if (a->adapt && l->sp && drawn > 1)
		adapt_points(l, dt);
	return last;
}

/* Shows the volumes until the window is closed, --exit-after is reached
 * or something fails. VIEW_OK or the exit status of the failure. */
static int window_loop(struct window *w, struct live *l, const struct view_args *a)
{
	int status = VIEW_OK;
	while (!w->quit && status == VIEW_OK) {
		SDL_Event e;
		while (SDL_PollEvent(&e))
			window_event(w, &e);
		if (l->sp && (status = live_pump(l, w->dirty ? 0 : 8)) != VIEW_OK)
			break;
		if (l->fresh) {
			view_gl_upload(w->gl, &l->pts);
			l->fresh = false;
			w->dirty = true;
		}
		if (!w->dirty) {
			if (!l->sp)
				SDL_WaitEventTimeout(NULL, 50);
			continue;
		}
		if (draw_frame(w, l, a, &status))
			break;
	}
	return status;
}

static int run_window(const struct view_args *a)
{
	struct live l = { 0 };
	struct view_points file_pts = { 0 };
	int status = a->input ? input_points(a, &file_pts) : live_open(&l, a);
	if (status != VIEW_OK)
		return status;
	struct window w;
	if (window_open(&w, a) < 0) {
		window_close(&w);
		live_close(&l, false);
		view_points_free(&file_pts);
		return VIEW_FAILED;
	}
	if (a->input) {
		view_gl_upload(w.gl, &file_pts);
		l.received = 1;
	}
	status = window_loop(&w, &l, a);
	window_close(&w);
	live_close(&l, a->stats && !a->input);
	view_points_free(&file_pts);
	return status;
}

/* One option of the turntable (--frames, --size) into a. Returns -1 to go
 * on, else the exit status (bad usage). */
static int parse_turntable_option(int c, struct view_args *a)
{
	if (c == 'n' && !parse_u32(optarg, 1, 360, &a->frames))
		return usage_error("--frames takes 1 to 360");
	if (c == 'z' && !parse_u32(optarg, 16, 4096, &a->size))
		return usage_error("--size takes 16 to 4096");
	return -1;
}

/* One option of the window or the drawing (--exit-after, --geometry,
 * --max-points) into a. Returns -1 to go on, else the exit status (bad
 * usage). */
static int parse_window_option(int c, struct view_args *a)
{
	uint32_t mp;
	switch (c) {
	case 'x':
		if (!parse_u32(optarg, 1, UINT32_MAX, &a->exit_after))
			return usage_error("--exit-after takes a count of volumes");
		return -1;
	case 'g':
		if (sscanf(optarg, "%ux%u", &a->width, &a->height) != 2 || a->width < 16 || a->height < 16 ||
		    a->width > 8192 || a->height > 8192)
			return usage_error("--geometry takes WxH");
		return -1;
	default: /* 'm' */
		if (!parse_u32(optarg, 1000, UINT32_MAX, &mp))
			return usage_error("--max-points takes 1000 or more");
		a->max_points = mp;
		a->adapt = false;
		return -1;
	}
}

/* One option of the command line into a. Returns -1 to go on, else the
 * exit status (help, bad usage). */
static int parse_option(int c, struct view_args *a)
{
	switch (c) {
	case 's':
		a->socket = optarg;
		return -1;
	case 'r':
		if (!parse_u32(optarg, 1, 1000, &a->rate))
			return usage_error("--rate takes 1 to 1000");
		return -1;
	case 'i':
		a->input = optarg;
		return -1;
	case 't':
		a->turntable = optarg;
		return -1;
	case 'n':
	case 'z':
		return parse_turntable_option(c, a);
	case 'o':
		a->snapshot = optarg;
		return -1;
	case 'x':
	case 'g':
	case 'm':
		return parse_window_option(c, a);
	case 'S':
		a->slices = true;
		return -1;
	case 'v':
		a->stats = true;
		return -1;
	case 'h':
		fputs(usage_text, stdout);
		return VIEW_OK;
	default:
		return usage_error("bad option");
	}
}

/* The command line into *a. Returns -1 to go on, else the exit status. */
static int parse_args(int argc, char **argv, struct view_args *a)
{
	*a = (struct view_args){ .frames = 12,
				 .size = 256,
				 .width = 800,
				 .height = 800,
				 .max_points = DEFAULT_MAX_POINTS,
				 .adapt = true };
	static const struct option opts[] = {
		{ "socket", required_argument, NULL, 's' },   { "rate", required_argument, NULL, 'r' },
		{ "input", required_argument, NULL, 'i' },    { "turntable", required_argument, NULL, 't' },
		{ "frames", required_argument, NULL, 'n' },   { "size", required_argument, NULL, 'z' },
		{ "snapshot", required_argument, NULL, 'o' }, { "exit-after", required_argument, NULL, 'x' },
		{ "geometry", required_argument, NULL, 'g' }, { "max-points", required_argument, NULL, 'm' },
		{ "slices", no_argument, NULL, 'S' },         { "stats", no_argument, NULL, 'v' },
		{ "help", no_argument, NULL, 'h' },           { NULL, 0, NULL, 0 },
	};
	int c;
	while ((c = getopt_long(argc, argv, "s:r:i:t:n:z:o:x:g:m:Svh", opts, NULL)) != -1) {
		int r = parse_option(c, a);
		if (r >= 0)
			return r;
	}
	if (optind < argc)
		return usage_error("unexpected argument");
	if (a->snapshot && !a->exit_after)
		a->exit_after = 1;
	if (a->input && a->socket)
		return usage_error("--input and --socket exclude each other");
	return -1;
}

int main(int argc, char **argv)
{
	struct view_args a;
	int status = parse_args(argc, argv, &a);
	if (status >= 0)
		return status;
	return a.turntable ? run_turntable(&a) : run_window(&a);
}
