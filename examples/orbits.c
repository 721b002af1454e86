/* orbits: a small planetary system, animated once per revolution.
 *
 * Shows how a libspindle client is built around its own event loop:
 * poll() on spindle_get_fd(), spindle_dispatch() for events, one frame
 * callback per commit to pace the animation to the volumes actually shown,
 * and the state listener for the rotor's lock and the projector. The
 * drawing uses protocol version 2: orbits as line strips with a colour per
 * vertex, planets as large points, moons placed with nested transforms
 * (push, multiply_transform, pop) inside one retained display list.
 *
 *   orbits [--seconds S] [--socket PATH]
 *
 * Exits 0 after S seconds (default: run until interrupted). */
#include <errno.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <spindle/spindle.h>

#define ORBIT_SEGMENTS 96

struct vertex {
	float xyz[3];
	uint8_t rgba[4];
};

struct app {
	struct spindle *sp;
	struct spindle_list *list;
	struct spindle_layer *layer;
	struct spindle_buffer *orbit, *body;
	bool frame_pending;
	uint64_t frames;
	double t; /* animation time, seconds */
};

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
	stop = 1;
}

static double now_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec / 1e9;
}

/* A unit circle in the xz plane, shading from blue to white. */
static struct spindle_buffer *make_orbit(struct spindle *sp)
{
	struct vertex v[ORBIT_SEGMENTS + 1];
	for (int i = 0; i <= ORBIT_SEGMENTS; i++) {
		double a = 2 * M_PI * i / ORBIT_SEGMENTS;
		uint8_t w = (uint8_t)(64 + 191 * i / ORBIT_SEGMENTS);
		v[i] = (struct vertex){ { (float)cos(a), 0, (float)sin(a) }, { w, w, 255, 255 } };
	}
	return spindle_buffer_create(sp, v, sizeof(v));
}

/* Column-major matrices. */
static void rotate_y_scale(float m[16], double angle, double scale)
{
	float c = (float)(cos(angle) * scale), s = (float)(sin(angle) * scale), k = (float)scale;
	const float r[16] = { c, 0, -s, 0, 0, k, 0, 0, s, 0, c, 0, 0, 0, 0, 1 };
	memcpy(m, r, sizeof(r));
}

static void translate(float m[16], float x, float y, float z)
{
	const float t[16] = { 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, x, y, z, 1 };
	memcpy(m, t, sizeof(t));
}

/* One planet on an orbit of radius r at angle a, with n moons. */
static void draw_planet(struct app *app, double r, double a, double tilt, int moons, uint8_t size)
{
	struct spindle_list *l = app->list;
	float m[16];
	spindle_list_push(l);
	translate(m, 0, (float)tilt, 0);
	spindle_list_multiply_transform(l, m);
	rotate_y_scale(m, 0, r);
	spindle_list_push(l);
	spindle_list_multiply_transform(l, m);
	spindle_list_set_vertex_format(l, SPINDLE_XYZ_RGBA8);
	spindle_list_draw(l, SPINDLE_LINE_STRIP, app->orbit, 0, ORBIT_SEGMENTS + 1, 0);
	spindle_list_pop(l);
	/* The planet's own frame: moons orbit it. */
	rotate_y_scale(m, a, 1);
	spindle_list_multiply_transform(l, m);
	translate(m, (float)r, 0, 0);
	spindle_list_multiply_transform(l, m);
	spindle_list_set_color(l, 255, 200, 80, 255);
	spindle_list_set_point_size(l, size);
	spindle_list_points(l, app->body, 0, 1, 0);
	for (int i = 0; i < moons; i++) {
		spindle_list_push(l);
		rotate_y_scale(m, 3 * a + 2 * M_PI * i / moons, 0.12);
		spindle_list_multiply_transform(l, m);
		spindle_list_set_color(l, 160, 255, 160, 255);
		spindle_list_set_point_size(l, 2);
		translate(m, 1, 0, 0);
		spindle_list_multiply_transform(l, m);
		spindle_list_points(l, app->body, 0, 1, 0);
		spindle_list_pop(l);
	}
	spindle_list_pop(l);
}

static void on_frame(void *data, const struct spindle_frame *frame)
{
	struct app *app = data;
	app->frame_pending = false;
	app->frames++;
}

/* Rebuilds the list for time t and commits, asking for a frame. */
static int draw_scene(struct app *app)
{
	double t = app->t;
	spindle_list_clear(app->list);
	spindle_list_set_color(app->list, 255, 255, 100, 255);
	spindle_list_set_point_size(app->list, 5);
	spindle_list_points(app->list, app->body, 0, 1, 0); /* the sun */
	draw_planet(app, 0.35, t * 1.3, 0.05, 1, 3);
	draw_planet(app, 0.6, t * 0.8 + 1, -0.1, 2, 4);
	draw_planet(app, 0.85, t * 0.5 + 2, 0.15, 0, 3);
	int r = spindle_request_frame(app->sp, on_frame, app);
	if (r == 0)
		r = spindle_commit(app->sp);
	app->frame_pending = r == 0;
	return r;
}

static void on_state(void *data, const struct spindle_state *st)
{
	printf("display: %s, %s, projector %s, %.0f rpm\n", st->locked ? "locked" : "not locked",
	       st->blanked ? "dark" : "lit", st->projector_present ? "present" : "absent", st->rpm);
	fflush(stdout);
}

static void on_refused(void *data, enum spindle_refusal code, uint32_t object, const char *message)
{
	fprintf(stderr, "orbits: commit refused: %s\n", message);
}

static const struct spindle_listener listener = { .state = on_state, .refused = on_refused };

static int setup(struct app *app, const char *socket)
{
	app->sp = spindle_connect(socket);
	if (!app->sp) {
		fprintf(stderr, "orbits: cannot connect to spindled: %s\n", strerror(errno));
		return -1;
	}
	if (spindle_get_version(app->sp) < 2) {
		fprintf(stderr, "orbits: spindled speaks protocol version 1; version 2 is needed\n");
		return -1;
	}
	spindle_set_listener(app->sp, &listener, app);
	static const float origin[3] = { 0, 0, 0 };
	app->body = spindle_buffer_create(app->sp, origin, sizeof(origin));
	app->orbit = make_orbit(app->sp);
	app->list = spindle_list_create(app->sp);
	app->layer = spindle_layer_create(app->sp);
	if (!app->body || !app->orbit || !app->list || !app->layer)
		return -1;
	return spindle_layer_set_list(app->layer, app->list);
}

/* Waits for events; a new scene goes out when the last one was shown. */
static int run(struct app *app, double seconds)
{
	double start = now_s();
	int r = draw_scene(app);
	while (r >= 0 && !stop && (seconds <= 0 || now_s() - start < seconds)) {
		struct pollfd pfd = { spindle_get_fd(app->sp), POLLIN, 0 };
		if (spindle_flush(app->sp) == -EAGAIN)
			pfd.events |= POLLOUT;
		if (poll(&pfd, 1, 100) < 0 && errno != EINTR)
			return -errno;
		r = spindle_dispatch(app->sp);
		if (r >= 0 && !app->frame_pending) {
			app->t = now_s() - start;
			r = draw_scene(app);
		}
	}
	if (r < 0)
		fprintf(stderr, "orbits: %s\n", spindle_get_error(app->sp) ? spindle_get_error(app->sp) : strerror(-r));
	printf("orbits: %llu frames shown in %.1f s\n", (unsigned long long)app->frames, now_s() - start);
	return r < 0 ? r : 0;
}

int main(int argc, char **argv)
{
	const char *socket = NULL;
	double seconds = 0;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--seconds") && i + 1 < argc)
			seconds = atof(argv[++i]);
		else if (!strcmp(argv[i], "--socket") && i + 1 < argc)
			socket = argv[++i];
		else {
			bool help = !strcmp(argv[i], "--help") || !strcmp(argv[i], "-h");
			fprintf(help ? stdout : stderr, "usage: orbits [--seconds S] [--socket PATH]\n");
			return help ? 0 : 2;
		}
	}
	signal(SIGINT, on_signal);
	signal(SIGTERM, on_signal);
	struct app app = { 0 };
	int r = setup(&app, socket);
	if (r == 0)
		r = run(&app, seconds);
	spindle_disconnect(app.sp);
	return r < 0 ? 1 : 0;
}
