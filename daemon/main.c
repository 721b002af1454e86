/* spindled: option parsing; server.c runs the daemon. */
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "devices.h"
#include "log.h"
#include "server.h"

static void usage(FILE *f)
{
	fprintf(f, "Usage: spindled [OPTION]...\n"
		   "Drive a swept-volume 3-D display and serve its clients.\n\n"
		   "  -c, --config FILE        configuration file (default " CONFIG_DEFAULT_PATH ")\n"
		   "  -d, --device NAME        device backends: sim (default), hw (GPIO sync\n"
		   "                           and USB projector)\n"
		   "      --blank              darken the projector and exit (for\n"
		   "                           ExecStopPost=)\n"
		   "  -p, --profile NAME       device profile: perspecta (default), small\n"
		   "  -r, --renderer NAME      renderer: auto (default: EGL on a hardware GPU,\n"
		   "                           else cpu), cpu, egl, osmesa\n"
		   "  -s, --socket PATH        client socket (default $SPINDLE_SOCKET or\n"
		   "                           /run/spindle/spindle.sock)\n"
		   "      --user NAME          started as root: run as this user once the\n"
		   "                           devices and the socket are open (default\n"
		   "                           spindle; root: stay root, for development)\n");
	fprintf(f, "  -o, --set KEY=VALUE      set any configuration key\n"
		   "  -v, --verbose            debug logging\n"
		   "  -h, --help               this help\n"
		   "      --version            print the version\n");
}

static int set_option(struct config *cfg, const char *key, const char *value)
{
	int r = config_set(cfg, key, value);
	const char *values = config_key_values(key);
	if (r < 0)
		fprintf(stderr, "spindled: %s '%s'%s%s%s\n", r == -ENOENT ? "unknown key" : "bad value for", key,
			values ? " (one of: " : "", values ? values : "", values ? ")" : "");
	return r;
}

/* Applies one option; the config file was read before. */
static int apply(struct config *cfg, int opt, char *arg)
{
	switch (opt) {
	case 'd':
		return set_option(cfg, "device", arg);
	case 'p':
		return set_option(cfg, "profile", arg);
	case 'r':
		return set_option(cfg, "renderer", arg);
	case 's':
		return set_option(cfg, "socket", arg);
	case 'U':
		return set_option(cfg, "user", arg);
	case 'v':
		cfg->verbose = true;
		return 0;
	case 'B':
		cfg->blank_only = true;
		return 0;
	case 'o': {
		char *eq = strchr(arg, '=');
		if (!eq) {
			fprintf(stderr, "spindled: --set takes KEY=VALUE\n");
			return -EINVAL;
		}
		*eq = '\0';
		return set_option(cfg, arg, eq + 1);
	}
	}
	return -EINVAL;
}

/* First pass: where the config file is (into *config_path), help and
 * version. Returns -1 to go on, else the exit status. */
static int first_pass(int argc, char **argv, const char *shortopts, const struct option *options,
		      const char **config_path)
{
	int opt;
	while ((opt = getopt_long(argc, argv, shortopts, options, NULL)) != -1) {
		if (opt == 'c')
			*config_path = optarg;
		else if (opt == 'h')
			return usage(stdout), 0;
		else if (opt == 'V')
			return puts("spindled " SPINDLE_VERSION), 0;
		else if (opt == '?')
			return usage(stderr), 2;
	}
	if (optind < argc) {
		fprintf(stderr, "spindled: unexpected argument '%s'\n", argv[optind]);
		return 2;
	}
	return -1;
}

int main(int argc, char **argv)
{
	static const struct option options[] = {
		{ "config", required_argument, NULL, 'c' },
		{ "device", required_argument, NULL, 'd' },
		{ "profile", required_argument, NULL, 'p' },
		{ "renderer", required_argument, NULL, 'r' },
		{ "socket", required_argument, NULL, 's' },
		{ "user", required_argument, NULL, 'U' }, /* = --set user=NAME */
		{ "set", required_argument, NULL, 'o' },
		{ "verbose", no_argument, NULL, 'v' },
		{ "help", no_argument, NULL, 'h' },
		{ "version", no_argument, NULL, 'V' },
		{ "blank", no_argument, NULL, 'B' },
		{ 0 },
	};
	const char *shortopts = "c:d:p:r:s:o:vh";
	const char *config_path = NULL;
	int opt, status = first_pass(argc, argv, shortopts, options, &config_path);
	if (status >= 0)
		return status;
	struct config cfg;
	config_defaults(&cfg);
	if (config_load(&cfg, config_path ? config_path : CONFIG_DEFAULT_PATH, config_path != NULL) < 0)
		return 2;
	optind = 1;
	while ((opt = getopt_long(argc, argv, shortopts, options, NULL)) != -1) {
		if (opt != 'c' && apply(&cfg, opt, optarg) < 0)
			return 2;
	}
	log_set_level(cfg.verbose ? LOG_LEVEL_DEBUG : LOG_LEVEL_INFO);
	if (cfg.blank_only)
		return devices_blank(&cfg) < 0 ? 1 : 0;
	return server_run(&cfg);
}
