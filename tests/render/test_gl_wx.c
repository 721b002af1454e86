/* A GL renderer on a software rasterizer (llvmpipe compiles its shaders to
 * machine code at run time) in a process that may not map memory both
 * writable and executable (systemd's MemoryDenyWriteExecute=, here the
 * kernel's PR_SET_MDWE): render_gl_create() must refuse, so that the daemon
 * takes the CPU renderer, instead of llvmpipe crashing at the first render.
 * Skipped (77) where the kernel has no PR_SET_MDWE or EGL is on a GPU. */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/prctl.h>

#include "check.h"
#include "rtest.h"

#ifndef PR_SET_MDWE
#define PR_SET_MDWE 65
#define PR_MDWE_REFUSE_EXEC_GAIN (1UL << 0)
#endif

int main(void)
{
	struct geometry g = rtest_small();
	/* Where EGL runs on a GPU there is no JIT to refuse. */
	struct render_gl_options probe = { .backend = "egl", .hardware_only = true };
	struct renderer *hw = render_gl_create(&g, &probe);
	if (hw) {
		render_destroy(hw);
		printf("SKIP: EGL runs on a GPU here\n");
		return 77;
	}
	if (prctl(PR_SET_MDWE, PR_MDWE_REFUSE_EXEC_GAIN, 0, 0, 0) < 0) {
		printf("SKIP: no PR_SET_MDWE (%s)\n", strerror(errno));
		return 77;
	}
	const char *const backends[] = { "egl", "osmesa" };
	for (int i = 0; i < 2; i++) {
		struct render_gl_options opts = { .backend = backends[i], .threads = 1 };
		errno = 0;
		struct renderer *r = render_gl_create(&g, &opts);
		if (r) { /* the bug: llvmpipe would crash in this render */
			struct volume *vol = volume_create(&g);
			struct scene s = { 0 };
			render_volume(r, &s, vol);
			volume_destroy(vol);
			render_destroy(r);
		}
		CHECK_MSG(!r, "%s on a software rasterizer was created under W^X", backends[i]);
		CHECK_MSG(errno == ENOTSUP || errno == ENODEV || errno == ENOENT, "%s: errno %d (%s)", backends[i],
			  errno, strerror(errno));
	}
	/* The CPU renderer needs no executable memory. */
	struct renderer *cpu = render_create("cpu", &g, 1);
	CHECK(cpu);
	render_destroy(cpu);
	return check_done();
}
