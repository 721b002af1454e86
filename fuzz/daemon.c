#include "daemon.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <systemd/sd-event.h>
#include <unistd.h>

#include "config.h"
#include "harness.h"
#include "log.h"

/* Low quotas keep every input cheap: at most a few thousand vertices to
 * copy, check and render on the small profile. */
static const char *const base_config[] = {
	"device",
	"sim",
	"profile",
	"small",
	"renderer",
	"cpu",
	"render-threads",
	"1",
	"projector-buffers",
	"2",
	"max-clients",
	"4",
	"max-objects",
	"64",
	"max-buffer-bytes",
	"1048576",
	"max-vertices",
	"4096",
	"max-primitives",
	"2048",
	"max-scene-primitives",
	"3072",
	NULL,
};

static void configure(struct config *cfg, const char *const *pairs)
{
	for (; pairs && pairs[0]; pairs += 2) {
		int r = config_set(cfg, pairs[0], pairs[1]);
		/* A key main does not know yet is skipped, not fatal. */
		if (r < 0 && r != -ENOENT)
			fuzz_fail("config %s = %s: %s", pairs[0], pairs[1], strerror(-r));
	}
}

/* The configuration, made once: config_set's string compares would
 * otherwise show up in every input's coverage. */
static const struct config *base(void)
{
	static struct config cfg;
	static bool made;
	if (made)
		return &cfg;
	made = true;
	if (!fuzz_verbose())
		log_set_level(LOG_LEVEL_ERROR);
	config_defaults(&cfg);
	/* Never bound (listen = false), but unique all the same. */
	snprintf(cfg.socket_path, sizeof(cfg.socket_path), "/tmp/spindle-fuzz-%d.sock", (int)getpid());
	configure(&cfg, base_config);
	return &cfg;
}

void fuzz_server_start(struct fuzz_server *fs, const char *const *extra)
{
	struct config cfg = *base();
	configure(&cfg, extra);
	/* server_init blocks SIGINT and SIGTERM for its signal sources; put
	 * the mask back after, so that libFuzzer's own handlers still work. */
	sigset_t old;
	sigprocmask(SIG_SETMASK, NULL, &old);
	int r = server_init(&fs->srv, &cfg, false);
	if (r < 0)
		fuzz_fail("server_init: %s", strerror(-r));
	sigprocmask(SIG_SETMASK, &old, NULL);
	fs->up = true;
}

int fuzz_server_connect(struct fuzz_server *fs)
{
	int sv[2];
	if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) < 0)
		fuzz_fail("socketpair: %s", strerror(errno));
	if (fcntl(sv[1], F_SETFL, O_NONBLOCK) < 0)
		fuzz_fail("fcntl: %s", strerror(errno));
	int r = server_add_client(&fs->srv, sv[1]);
	if (r < 0)
		fuzz_fail("server_add_client: %s", strerror(-r));
	return sv[0];
}

void fuzz_server_run(struct fuzz_server *fs)
{
	/* A bound, in case something stays ready forever: that is a bug the
	 * fuzzer should see as a hang, not spin on. */
	for (int i = 0; i < 100000; i++) {
		int r = sd_event_run(fs->srv.event, 0);
		if (r < 0)
			fuzz_fail("sd_event_run: %s", strerror(-r));
		if (r == 0)
			return;
	}
	fuzz_fail("the event loop never goes idle");
}

void fuzz_server_stop(struct fuzz_server *fs)
{
	if (!fs->up)
		return;
	server_finish(&fs->srv);
	fs->up = false;
}
