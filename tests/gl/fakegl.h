/* A fake OpenGL/GLX/EGL library for the spindle-gl tests: every entry
 * point the layer wraps, each doing nothing but counting its calls and
 * keeping its last arguments (up to 4, as doubles), so that a test can
 * tell which calls reached the "real" GL under the layer. */
#ifndef SPINDLE_TEST_FAKEGL_H
#define SPINDLE_TEST_FAKEGL_H

/* Calls of name so far. */
int fakegl_count(const char *name);
/* Argument i (0..3) of the last call of name. */
double fakegl_arg(const char *name, int i);
/* The memory glMapBuffer and glMapBufferRange hand out (1 MiB). */
void *fakegl_map_memory(void);

#endif
