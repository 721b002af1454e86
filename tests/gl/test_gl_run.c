/* Frames against spindled on the simulated device (retained lists, pacing,
 * what the display shows), no daemon and a daemon that comes and goes,
 * contexts and threads, what is not covered, the loaders, and programs
 * that never swap. */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "geometry.h"
#include "gltest.h"
#include "harness.h"

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

/* A square of 2 x 2 in the x-y plane, made of a grid of quads. */
static void square_list(GLuint l)
{
	glNewList(l, GL_COMPILE);
	glColor3f(1, 0.8f, 0);
	glBegin(GL_QUADS);
	for (int i = 0; i < 8; i++) {
		for (int j = 0; j < 8; j++) {
			float x = -1 + i * 0.25f, y = -1 + j * 0.25f;
			glVertex3f(x, y, 0), glVertex3f(x + 0.25f, y, 0);
			glVertex3f(x + 0.25f, y + 0.25f, 0), glVertex3f(x, y + 0.25f, 0);
		}
	}
	glEnd();
	glEndList();
}

static void draw_square(GLuint l, float angle)
{
	glLoadIdentity();
	glTranslatef(0, 0, -10);
	glRotatef(angle, 0, 1, 0);
	glCallList(l);
}

/* Frames in the trace with the given status. */
static int frames_with(const char *status)
{
	struct tframe *frames;
	int n = gltest_frames(&frames), k = 0;
	for (int i = 0; i < n; i++)
		k += !strcmp(frames[i].status, status);
	free(frames);
	return k;
}

/* Swaps (drawing the square still) until a frame sent after now shows. */
static void settle(GLuint l)
{
	int shown = gltest_trace_count("shown ");
	for (int i = 0; i < 300 && gltest_trace_count("shown ") < shown + 2; i++) {
		draw_square(l, 0);
		glXSwapBuffers(NULL, 1);
		gltest_sleep_ms(10);
	}
	CHECK(gltest_trace_count("shown ") >= shown + 2);
}

/* The square's corners, mapped as the last frame says (through proj to
 * the stage, when not NULL), are lit. */
static void check_shown(struct daemon *d, const float *proj)
{
	struct tframe f = gltest_last_frame();
	struct spindle *sp = client_connect(d);
	struct volume *vol = capture_volume(sp);
	struct geometry g;
	CHECK(geometry_from_profile("small", &g) == 0);
	int lit = 0;
	for (int i = 0; i < 4; i++) {
		float e[4] = { i & 1 ? 0.9f : -0.9f, i & 2 ? 0.9f : -0.9f, -10, 1 }, p[4];
		for (int r = 0; r < 4 && proj; r++)
			p[r] = proj[r] * e[0] + proj[4 + r] * e[1] + proj[8 + r] * e[2] + proj[12 + r];
		for (int r = 0; r < 3 && proj; r++)
			e[r] = p[r] / p[3];
		for (int r = 0; r < 3; r++)
			p[r] = f.map[r] * e[0] + f.map[4 + r] * e[1] + f.map[8 + r] * e[2] + f.map[12 + r];
		struct voxel v = expected_point(&g, p[0], p[1], p[2]);
		lit += lit_near(vol, v.k, (int)v.u, (int)v.v, 0, 2) && lit_near(vol, v.k, (int)v.u, (int)v.v, 1, 2);
	}
	CHECK_EQ(lit, 4);
	volume_destroy(vol);
	spindle_disconnect(sp);
}

void case_frames(void)
{
	struct daemon d;
	gltest_setup(NULL, "/nonexistent");
	daemon_start(&d);
	setenv("SPINDLE_SOCKET", d.socket, 1);
	square_list(1);
	double worst = 0, end = now_ms() + 1500;
	for (int i = 0; now_ms() < end; i++) {
		draw_square(1, (float)i);
		double t = now_ms();
		glXSwapBuffers(NULL, 1);
		worst = fmax(worst, now_ms() - t);
		gltest_sleep_ms(1);
	}
	settle(1);
	check_shown(&d, NULL);
	/* The list went to the daemon once; frames carry transforms only. */
	CHECK_EQ(gltest_trace_count("upload list 1 segment 0 own 384 inherit 0"), 1);
	CHECK_EQ(gltest_trace_count("sent ctx 1 layers 1 dynamic 0 ok 1"), frames_with("sent"));
	int sent = frames_with("sent"), dropped = frames_with("dropped");
	CHECK_MSG(sent >= 10 && dropped > sent, "%d frames sent, %d dropped", sent, dropped);
	CHECK_MSG(worst < 100, "a swap took %.1f ms", worst);
	/* Immediate geometry, changed or not. */
	for (int i = 0; i < 5; i++) {
		glBegin(GL_LINES);
		glVertex3f(0, 0, -10), glVertex3f(1, 1, -10);
		glEnd();
		glXSwapBuffers(NULL, 1);
		gltest_sleep_ms(40);
	}
	CHECK(gltest_trace_count("sent ctx 1 layers 0 dynamic 2 ok 1") >= 1);
	CHECK_EQ(gltest_trace_count("warn "), 0);
	daemon_stop(&d);
}

/* Calls shown as geometry: through a perspective projection (frustum
 * mode), and past the layers a frame may use. */
void case_expand(void)
{
	struct daemon d;
	setenv("SPINDLE_GL_MAX_LAYERS", "2", 1);
	gltest_setup("frustum", "/nonexistent");
	daemon_start(&d);
	setenv("SPINDLE_SOCKET", d.socket, 1);
	square_list(1);
	glMatrixMode(GL_PROJECTION);
	glFrustum(-1, 1, -1, 1, 5, 15);
	glMatrixMode(GL_MODELVIEW);
	settle(1);
	CHECK(gltest_trace_count("sent ctx 1 layers 0 dynamic 384 ok 1") >= 2);
	/* glFrustum(-1, 1, -1, 1, 5, 15), column-major. */
	const float proj[16] = { 5, 0, 0, 0, 0, 5, 0, 0, 0, 0, -2, -1, 0, 0, -15, 0 };
	check_shown(&d, proj);
	glMatrixMode(GL_PROJECTION);
	glLoadIdentity();
	glOrtho(-2, 2, -2, 2, 5, 15);
	glMatrixMode(GL_MODELVIEW);
	for (int i = 0; i < 100 && gltest_trace_count("sent ctx 1 layers 2 dynamic 384 ok 1") < 2; i++) {
		for (int k = 0; k < 3; k++)
			draw_square(1, (float)k);
		glXSwapBuffers(NULL, 1);
		gltest_sleep_ms(20);
	}
	CHECK(gltest_trace_count("sent ctx 1 layers 2 dynamic 384 ok 1") >= 2);
	CHECK_EQ(gltest_trace_count("upload list 1 "), 1);
	CHECK_EQ(gltest_trace_count("warn "), 0);
	daemon_stop(&d);
}

void case_offline(void)
{
	struct daemon d;
	gltest_setup(NULL, "/nonexistent/sock");
	gltest_capture_stderr();
	square_list(1);
	for (int i = 0; i < 10; i++) {
		draw_square(1, 0);
		glXSwapBuffers(NULL, 1);
		gltest_sleep_ms(10);
	}
	CHECK_EQ(frames_with("offline"), 10);
	CHECK_EQ(gltest_stderr_count("no display at /nonexistent/sock"), 1);
	for (int round = 1; round <= 2; round++) {
		daemon_start(&d); /* it comes: the layer connects */
		setenv("SPINDLE_SOCKET", d.socket, 1);
		settle(1);
		CHECK_EQ(gltest_trace_count("upload list 1 "), round);
		daemon_stop(&d); /* it goes: the program runs on */
		for (int i = 0; i < 10; i++) {
			draw_square(1, 0);
			glXSwapBuffers(NULL, 1);
			gltest_sleep_ms(5);
		}
		CHECK_EQ(gltest_stderr_count("lost the display"), round);
	}
	CHECK_EQ(gltest_stderr_count("spindle-gl:"), 3);
}

void case_contexts(void)
{
	gltest_setup("fixed", NULL);
	GLXContext a = glXCreateContext(NULL, NULL, NULL, True);
	GLXContext b = glXCreateNewContext(NULL, NULL, GLX_RGBA_TYPE, NULL, True);
	GLXContext s = glXCreateContextAttribsARB(NULL, NULL, a, True, NULL);
	CHECK(a && b && s && a != b);
	CHECK(glXMakeCurrent(NULL, 1, a));
	glNewList(1, GL_COMPILE);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	glEndList();
	glTranslatef(1, 0, 0); /* a's modelview only */
	CHECK(glXMakeContextCurrent(NULL, 2, 2, b));
	glCallList(1); /* b has no list 1 */
	struct tframe fb = gltest_swap();
	CHECK_EQ(fb.calls, 0);
	CHECK(glXMakeCurrent(NULL, 3, s));
	glCallList(1); /* s shares a's lists */
	struct tframe fs = gltest_swap();
	CHECK(fs.calls == 1 && fs.c[0].s[12] == 0 && fs.ctx != fb.ctx);
	CHECK(glXMakeCurrent(NULL, 1, a));
	glCallList(1);
	struct tframe fa = gltest_swap();
	CHECK(fa.calls == 1 && fa.c[0].s[12] == 1 && fa.ctx != fs.ctx && fa.ctx != fb.ctx);
	/* Destroyed while current: it goes when released; a's lists live on in s. */
	glXDestroyContext(NULL, a);
	glXDestroyContext(NULL, b);
	CHECK(glXMakeCurrent(NULL, 3, s));
	glCallList(1);
	fs = gltest_swap();
	CHECK_EQ(fs.calls, 1);
	glXDestroyContext(NULL, s);
	CHECK(glXMakeCurrent(NULL, 0, NULL));
	/* EGL contexts; with none current, the default context. */
	EGLContext e = eglCreateContext(NULL, NULL, EGL_NO_CONTEXT, NULL);
	CHECK(eglMakeCurrent(NULL, NULL, NULL, e));
	glCallList(1);
	CHECK(eglSwapBuffers(NULL, NULL));
	CHECK_EQ(gltest_last_frame().calls, 0);
	CHECK(eglDestroyContext(NULL, e));
	CHECK(eglMakeCurrent(NULL, NULL, NULL, EGL_NO_CONTEXT));
	CHECK_EQ(fakegl_count("glXMakeCurrent"), 5);
	CHECK_EQ(fakegl_count("eglSwapBuffers"), 1);
}

#define THREADS 4
#define THREAD_FRAMES 150

static void *thread_main(void *arg)
{
	EGLContext e = eglCreateContext(NULL, NULL, EGL_NO_CONTEXT, NULL);
	eglMakeCurrent(NULL, NULL, NULL, e);
	glNewList(1, GL_COMPILE);
	glBegin(GL_TRIANGLES);
	glVertex3f(0, 0, 0), glVertex3f(1, 0, 0), glVertex3f(0, 1, 0);
	glEnd();
	glEndList();
	for (int i = 0; i < THREAD_FRAMES; i++) {
		glLoadIdentity();
		glRotatef((float)i, 0, 1, 0);
		glCallList(1);
		glBegin(GL_LINES);
		glVertex3f(0, 0, 0), glVertex3f((float)(uintptr_t)arg, 1, 0);
		glEnd();
		eglSwapBuffers(NULL, NULL);
	}
	eglMakeCurrent(NULL, NULL, NULL, EGL_NO_CONTEXT);
	eglDestroyContext(NULL, e);
	return NULL;
}

void case_threads(void)
{
	struct daemon d;
	gltest_setup(NULL, NULL);
	daemon_start(&d);
	setenv("SPINDLE_SOCKET", d.socket, 1);
	pthread_t t[THREADS];
	for (uintptr_t i = 0; i < THREADS; i++)
		CHECK(pthread_create(&t[i], NULL, thread_main, (void *)(i + 1)) == 0);
	for (int i = 0; i < THREADS; i++)
		CHECK(pthread_join(t[i], NULL) == 0);
	struct tframe *frames;
	int n = gltest_frames(&frames);
	unsigned per[16] = { 0 };
	for (int i = 0; i < n; i++)
		if (frames[i].ctx < 16 && frames[i].calls == 1)
			per[frames[i].ctx]++;
	free(frames);
	int contexts = 0;
	for (int i = 0; i < 16; i++)
		contexts += per[i] == THREAD_FRAMES;
	CHECK_EQ(contexts, THREADS);
	CHECK(frames_with("sent") >= THREADS);
	CHECK(gltest_trace_count("upload list 1 segment 0 own 0 inherit 3") >= THREADS);
	CHECK_EQ(gltest_trace_count("warn "), 0);
	daemon_stop(&d);
}

void case_uncovered(void)
{
	gltest_setup("fixed", NULL);
	gltest_capture_stderr();
	for (int i = 0; i < 3; i++) {
		glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, 1, 1, 0, GL_RGBA, GL_UNSIGNED_BYTE, NULL);
		glEnable(GL_TEXTURE_2D);
		glUseProgramObjectARB(2);
		glUseProgramObjectARB(0);
	}
	GLuint names[4];
	glSelectBuffer(4, names);
	glRenderMode(GL_SELECT);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	glRenderMode(GL_RENDER);
	GLfloat fb[16];
	glFeedbackBuffer(16, GL_3D, fb);
	struct tframe f = gltest_swap();
	CHECK_EQ(f.n[0], 0); /* drawn in selection mode: nothing shown */
	CHECK_EQ(gltest_stderr_count("textures: passed to OpenGL, not shown"), 1);
	CHECK_EQ(gltest_stderr_count("shader programs"), 1);
	CHECK_EQ(gltest_stderr_count("feedback and selection"), 1);
	CHECK_EQ(gltest_stderr_count("spindle-gl:"), 4); /* and the one of no daemon */
	CHECK_EQ(fakegl_count("glTexImage2D"), 3);
	CHECK_EQ(fakegl_count("glRenderMode"), 2);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	CHECK_EQ(gltest_swap().n[0], 1);
}

typedef void (*proc)(void);

void case_procaddress(void)
{
	gltest_setup("fixed", NULL);
	/* The layer's own entry points, as the program's symbols resolve. */
	CHECK(glXGetProcAddressARB((const GLubyte *)"glBegin") == (proc)glBegin);
	CHECK(glXGetProcAddress((const GLubyte *)"glVertex3f") == (proc)glVertex3f);
	CHECK(eglGetProcAddress("glCallList") == (proc)glCallList);
	CHECK(glXGetProcAddressARB((const GLubyte *)"glXSwapBuffers") == (proc)glXSwapBuffers);
	CHECK(eglGetProcAddress("eglSwapBuffers") == (proc)eglSwapBuffers);
	/* Others: the real GL's. */
	proc gen = glXGetProcAddressARB((const GLubyte *)"glGenLists");
	CHECK(gen != NULL && gen == (proc)glGenLists);
	CHECK(glXGetProcAddressARB((const GLubyte *)"glNoSuchFunction") == NULL);
	/* Through the pointers, calls are recorded and passed on. */
	void (*begin)(GLenum) = (void (*)(GLenum))glXGetProcAddressARB((const GLubyte *)"glBegin");
	void (*vertex)(GLfloat, GLfloat, GLfloat) =
		(void (*)(GLfloat, GLfloat, GLfloat))glXGetProcAddressARB((const GLubyte *)"glVertex3f");
	void (*end)(void) = (void (*)(void))eglGetProcAddress("glEnd");
	begin(GL_POINTS);
	vertex(1, 2, 3);
	end();
	CHECK_EQ(gltest_swap().n[0], 1);
	CHECK(fakegl_arg("glVertex3f", 2) == 3);
	CHECK_EQ(fakegl_count("glXGetProcAddressARB"), 6);
}

void case_noswap(void)
{
	gltest_setup("fixed", NULL);
	/* A single-buffered program: glFlush and glFinish end frames. */
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	glFlush();
	struct tframe f = gltest_last_frame();
	CHECK(!strcmp(f.by, "flush") && f.n[0] == 1);
	glFinish();
	CHECK(!strcmp(gltest_last_frame().by, "finish"));
	/* Swaps it makes in a way the layer does not see: glClear of the
	 * colour buffer after drawing ends a frame. */
	int frames = gltest_trace_count("frame ");
	glClear(GL_COLOR_BUFFER_BIT);
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0), glVertex3f(1, 0, 0);
	glEnd();
	glClear(GL_DEPTH_BUFFER_BIT);
	CHECK_EQ(gltest_trace_count("frame "), frames);
	glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
	f = gltest_last_frame();
	CHECK(!strcmp(f.by, "clear") && f.n[0] == 2);
	/* Once it swapped, none of them does. */
	gltest_swap();
	frames = gltest_trace_count("frame ");
	glBegin(GL_POINTS);
	glVertex3f(0, 0, 0);
	glEnd();
	glClear(GL_COLOR_BUFFER_BIT);
	glFlush();
	glFinish();
	CHECK_EQ(gltest_trace_count("frame "), frames);
	CHECK_EQ(fakegl_count("glFlush"), 2);
	CHECK_EQ(fakegl_count("glClear"), 4);
	/* A program that exits in the middle of a frame, or of a list. */
	pid_t pid = fork();
	CHECK(pid >= 0);
	if (pid == 0) {
		glNewList(5, GL_COMPILE);
		glBegin(GL_TRIANGLES);
		glVertex3f(0, 0, 0);
		exit(0);
	}
	int status;
	CHECK(waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
	/* Frames never ended pile up no further than the limit. */
	for (int i = 0; i < 100; i++) {
		glBegin(GL_POINTS);
		glVertex3f((float)i, 0, 0);
		glEnd();
	}
	CHECK_EQ(gltest_swap().n[0], 101);
}
