/* The spindle-gl test program: one case per run (the case name is the
 * argument), run with libspindle-gl.so preloaded over the fake GL library
 * (fakegl.h), reading back what the layer recorded from its trace file
 * ($SPINDLE_GL_TRACE, docs/opengl.md) and, for the cases with a daemon,
 * what the display shows. */
#ifndef SPINDLE_TEST_GLTEST_H
#define SPINDLE_TEST_GLTEST_H

#define GL_GLEXT_PROTOTYPES 1
#define GLX_GLXEXT_PROTOTYPES 1
#include <EGL/egl.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <stdbool.h>

#include "check.h"
#include "fakegl.h"

#define TRACE_MAX 64

/* A frame as the trace shows it: its "call" and "v" lines (when few) and
 * its "frame" line. s and map are column-major. */
struct tvertex {
	int kind; /* 0 points, 1 line vertices, 2 triangle vertices */
	float p[3];
	unsigned rgba;
};

struct tcall {
	unsigned list, segment, rgba;
	float s[16];
};

struct tframe {
	unsigned ctx, calls, n[3];
	char by[16], status[16];
	float map[16];
	int n_v, n_c;
	struct tvertex v[TRACE_MAX];
	struct tcall c[TRACE_MAX];
};

/* Sets up the environment before the first GL call: the trace in a
 * temporary file, the mapping (NULL: fit), a socket (NULL: one where no
 * daemon listens), reconnection every 50 ms, notes off. Clears LD_PRELOAD
 * for the daemons the case starts. */
void gltest_setup(const char *map, const char *socket);
/* Sends stderr to a file, read back by gltest_stderr_count(). */
void gltest_capture_stderr(void);
/* Lines of the captured stderr holding text. */
int gltest_stderr_count(const char *text);
/* Every frame traced so far, in order (free() the result). */
int gltest_frames(struct tframe **out);
/* The last frame traced (checks there is one). */
struct tframe gltest_last_frame(void);
/* Ends a frame with glXSwapBuffers and returns it as traced. */
struct tframe gltest_swap(void);
/* Trace lines starting with prefix. */
int gltest_trace_count(const char *prefix);
/* The whole trace, NUL-terminated (free() it). */
char *gltest_trace(void);
bool gltest_near(float a, float b);
void gltest_sleep_ms(int ms);

/* The cases. */
void case_immediate(void);
void case_colours(void);
void case_lists(void);
void case_matrices(void);
void case_arrays(void);
void case_buffers(void);
void case_mapping(void);
void case_frustum(void);
void case_fixed(void);
void case_frames(void);
void case_expand(void);
void case_offline(void);
void case_contexts(void);
void case_threads(void);
void case_uncovered(void);
void case_procaddress(void);
void case_noswap(void);

#endif
