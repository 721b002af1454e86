/* spindlectl: status, show a model file or a scan, test patterns,
 * calibration, capture and preview volumes.
 * main() parses the command line and hands over to one function per
 * command; each returns the process exit status. */
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <poll.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <spindle/spindle.h>

#include "ctl.h"
#include "model.h"
#include "patterns.h"
#include "preview.h"
#include "svol.h"

#ifndef SPINDLE_VERSION
#define SPINDLE_VERSION "unknown"
#endif

static const char usage_text[] =
	"usage: spindlectl [--socket PATH] COMMAND [ARGS]\n"
	"\n"
	"commands:\n"
	"  status [--json]                 device geometry and daemon state (--json:\n"
	"                                  one JSON object)\n"
	"  show FILE [--no-fit] [--color RRGGBB]\n"
	"                                  show a model (STL, OBJ, PLY, ...) in its\n"
	"                                  own colours until SIGINT/SIGTERM; prints\n"
	"                                  \"shown SEQ\"\n"
	"  show SCAN [--window C/W | --preset NAME] [--threshold T]\n"
	"       [--sampling nearest|trilinear] [--color RRGGBB]\n"
	"                                  show a scan (FILE.nii, FILE.nii.gz, a DICOM\n"
	"                                  directory) as a volume, superior up;\n"
	"                                  presets ct-bone, ct-soft, ct-lung, mri\n"
	"  show FILE --dims XxYxZ --type uint8|uint16|int16|float32|rgba8\n"
	"       --spacing SX,SY,SZ [--offset N] [--big-endian] [scan options]\n"
	"                                  show a raw file of samples as a scan\n"
	"  capture OUT.svol                save the next volume shown\n"
	"  pattern NAME                    show a test pattern until SIGINT/SIGTERM:\n"
	"                                  axis, rings, grid-cube, colour-bars,\n"
	"                                  walls, slice-index\n"
	"  preview IN.svol OUT.png [--size N]\n"
	"                                  picture of a captured volume (no daemon)\n"
	"  calibrate [KEY VALUE [--save [--config PATH]]]\n"
	"                                  show the calibration, or set one key\n"
	"                                  live (root or the daemon's user):\n"
	"                                  phase-offset, axis-offset-u,\n"
	"                                  axis-offset-v, vertical-scale,\n"
	"                                  vertical-offset; --save\n"
	"                                  also writes it to the config file\n"
	"\n"
	"options:\n"
	"  -s, --socket PATH   daemon socket (default: $SPINDLE_SOCKET, else\n"
	"                      " SPINDLE_DEFAULT_SOCKET ")\n"
	"  -h, --help          this help\n"
	"  -V, --version       version\n";

int ctl_usage_error(const char *fmt, const char *arg)
{
	fprintf(stderr, "spindlectl: ");
	fprintf(stderr, fmt, arg);
	fprintf(stderr, "\nTry 'spindlectl --help'.\n");
	return CTL_USAGE;
}

/* The path libspindle will use, for messages. */
const char *ctl_socket_path(const struct ctl_args *a)
{
	const char *env = getenv("SPINDLE_SOCKET");
	if (a->socket)
		return a->socket;
	return env && *env ? env : SPINDLE_DEFAULT_SOCKET;
}

struct spindle *ctl_connect(const struct ctl_args *a)
{
	struct spindle *sp = spindle_connect(a->socket);
	if (!sp) {
		int e = errno;
		fprintf(stderr, "spindlectl: cannot connect to spindled at %s: %s\n", ctl_socket_path(a),
			e == EPROTO ? "no common protocol version" : strerror(e));
	}
	return sp;
}

void ctl_report_failure(struct spindle *sp, const char *what, int ret)
{
	const char *why = sp ? spindle_get_error(sp) : NULL;
	fprintf(stderr, "spindlectl: %s: %s\n", what, why ? why : strerror(-ret));
}

/* ---- show ---- */

/* Adds one kind of primitive to the list from its own buffer; the buffer
 * may be destroyed right away, the list keeps its copy. */
static int draw_array(struct spindle *sp, struct spindle_list *list, const float *data, size_t vertices,
		      int (*draw)(struct spindle_list *, struct spindle_buffer *, size_t, uint32_t, uint32_t))
{
	if (vertices == 0)
		return 0;
	if (vertices > UINT32_MAX)
		return -E2BIG;
	struct spindle_buffer *buf = spindle_buffer_create(sp, data, vertices * 3 * sizeof(float));
	if (!buf)
		return -errno;
	int ret = draw(list, buf, 0, (uint32_t)vertices, 0);
	spindle_buffer_destroy(buf);
	return ret;
}

/* Like draw_array(), with the model's colours: 16-byte vertices (xyz,
 * RGBA8), protocol version 2. */
static int draw_colored(struct spindle *sp, struct spindle_list *list, enum spindle_mode mode, const float *xyz,
			const uint8_t *rgba, size_t vertices)
{
	if (vertices == 0)
		return 0;
	if (vertices > UINT32_MAX / 16)
		return -E2BIG;
	uint8_t *data = malloc(16 * vertices);
	if (!data)
		return -ENOMEM;
	for (size_t i = 0; i < vertices; i++) {
		memcpy(&data[16 * i], &xyz[3 * i], 12);
		memcpy(&data[16 * i + 12], &rgba[4 * i], 4);
	}
	struct spindle_buffer *buf = spindle_buffer_create(sp, data, 16 * vertices);
	free(data);
	if (!buf)
		return -errno;
	int ret = spindle_list_draw(list, mode, buf, 0, (uint32_t)vertices, 0);
	spindle_buffer_destroy(buf);
	return ret;
}

static int draw_model_colored(struct spindle *sp, struct spindle_list *list, const struct model *m)
{
	int ret = spindle_list_set_vertex_format(list, SPINDLE_XYZ_RGBA8);
	if (ret == 0)
		ret = draw_colored(sp, list, SPINDLE_TRIANGLES, m->triangles, m->triangle_colors,
				   3 * m->triangle_count);
	if (ret == 0)
		ret = draw_colored(sp, list, SPINDLE_LINES, m->lines, m->line_colors, 2 * m->line_count);
	if (ret == 0)
		ret = draw_colored(sp, list, SPINDLE_POINTS, m->points, m->point_colors, m->point_count);
	return ret;
}

static int draw_model_plain(struct spindle *sp, struct spindle_list *list, const struct model *m, const uint8_t rgb[3])
{
	int ret = spindle_list_set_color(list, rgb[0], rgb[1], rgb[2], 255);
	if (ret == 0)
		ret = draw_array(sp, list, m->triangles, 3 * m->triangle_count, spindle_list_triangles);
	if (ret == 0)
		ret = draw_array(sp, list, m->lines, 2 * m->line_count, spindle_list_lines);
	if (ret == 0)
		ret = draw_array(sp, list, m->points, m->point_count, spindle_list_points);
	return ret;
}

/* The model in its own colours, unless --color says otherwise or the
 * daemon is too old for per-vertex colour (then white, with a warning). */
static int build_scene(struct spindle *sp, const struct model *m, const struct ctl_args *a,
		       struct spindle_list **list_out, struct spindle_layer **layer_out)
{
	static const uint8_t white[3] = { 255, 255, 255 };
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	int ret = list && layer ? 0 : -errno;
	bool own_colors = (m->triangle_colors || m->line_colors || m->point_colors) && !a->has_color;

	if (own_colors && spindle_get_version(sp) < 2) {
		fprintf(stderr,
			"spindlectl: %s: the daemon speaks protocol %u, the model's colours need 2: "
			"shown in white\n",
			a->operand[0], spindle_get_version(sp));
		own_colors = false;
	}
	if (ret == 0)
		ret = own_colors ? draw_model_colored(sp, list, m)
				 : draw_model_plain(sp, list, m, a->has_color ? a->color : white);
	if (ret == 0)
		ret = spindle_layer_set_list(layer, list);
	*list_out = list;
	*layer_out = layer;
	return ret;
}

/* SIGINT and SIGTERM as a file descriptor, so one poll() waits for both
 * the daemon and the user. The signals are blocked first. */
static int open_signalfd(void)
{
	sigset_t set;
	sigemptyset(&set);
	sigaddset(&set, SIGINT);
	sigaddset(&set, SIGTERM);
	if (sigprocmask(SIG_BLOCK, &set, NULL) < 0)
		return -errno;
	int fd = signalfd(-1, &set, SFD_CLOEXEC | SFD_NONBLOCK);
	return fd < 0 ? -errno : fd;
}

/* Keeps the connection (and so the model on the display) until a signal.
 * 0 on a signal, 1 when the connection breaks. */
static int hold_until_signal(struct spindle *sp, int sfd)
{
	struct pollfd fds[2] = {
		{ .fd = spindle_get_fd(sp), .events = POLLIN },
		{ .fd = sfd, .events = POLLIN },
	};

	for (;;) {
		if (poll(fds, 2, -1) < 0) {
			if (errno == EINTR)
				continue;
			ctl_report_failure(NULL, "poll", -errno);
			return CTL_FAILED;
		}
		if (fds[1].revents & POLLIN)
			return 0;
		if (fds[0].revents) {
			int ret = spindle_dispatch(sp);
			if (ret < 0 || (fds[0].revents & (POLLHUP | POLLERR))) {
				ctl_report_failure(sp, "connection to spindled lost", ret < 0 ? ret : -EPIPE);
				return CTL_FAILED;
			}
		}
	}
}

static int fit_to_device(struct model *m, const struct spindle_device_info *info)
{
	struct model_fit fit;
	int ret = model_compute_fit(m, info->half_height, CTL_FIT_MARGIN, &fit);
	if (ret == 0)
		model_apply_fit(m, &fit);
	return ret;
}

/* Prints "shown SEQ" and holds until SIGINT/SIGTERM. The signals are caught
 * only from here on: until the model is shown, Ctrl-C simply kills us (the
 * wait for the first frame may be long when the rotor is stopped). They are
 * blocked before the line is printed, so a signal sent on reading it is
 * caught. */
static int announce_and_hold(struct spindle *sp, uint64_t seq)
{
	int sfd = open_signalfd();
	if (sfd < 0) {
		ctl_report_failure(NULL, "signalfd", sfd);
		return CTL_FAILED;
	}
	printf("shown %llu\n", (unsigned long long)seq);
	int status = fflush(stdout) == 0 ? hold_until_signal(sp, sfd) : 1;
	close(sfd);
	return status;
}

int ctl_commit_and_hold(struct spindle *sp, const char *what)
{
	struct spindle_frame frame;
	int ret = spindle_commit_and_wait(sp, &frame);
	if (ret == -EDQUOT || ret == -EACCES || ret == -EBUSY) {
		fprintf(stderr, "spindlectl: show: the daemon refused the %s: %s\n", what,
			ret == -EDQUOT  ? "more primitives than this client may show (max-primitives)"
			: ret == -EBUSY ? "another client's exclusive layer is showing"
					: "not allowed by the daemon's policy");
		return CTL_REFUSED;
	} else if (ret < 0) {
		ctl_report_failure(sp, "show", ret);
		return CTL_FAILED;
	}
	return announce_and_hold(sp, frame.volume_seq);
}

static int show_model(struct spindle *sp, struct model *m, const struct ctl_args *a)
{
	struct spindle_list *list = NULL;
	struct spindle_layer *layer = NULL;
	int status = CTL_FAILED;

	int ret = a->no_fit ? 0 : fit_to_device(m, spindle_get_device_info(sp));
	if (ret < 0) {
		fprintf(stderr, "spindlectl: %s: cannot fit the model into the display: %s\n", a->operand[0],
			strerror(-ret));
		return CTL_INPUT;
	}
	ret = build_scene(sp, m, a, &list, &layer);
	if (ret < 0)
		ctl_report_failure(sp, "show", ret);
	else
		status = ctl_commit_and_hold(sp, "model");
	if (layer)
		spindle_layer_destroy(layer);
	if (list)
		spindle_list_destroy(list);
	return status;
}

static int cmd_show(const struct ctl_args *a)
{
	char err[512];
	int status = CTL_FAILED;
	if (ctl_is_scan(a))
		return cmd_show_scan(a);
	if (ctl_scan_options_given(a))
		return ctl_usage_error("%s: --window, --preset, --threshold and --sampling go with a scan (FILE.nii, "
				       "FILE.nii.gz, a DICOM directory, or a raw file with --dims), not a model",
				       a->operand[0]);
	model_set_progress(stderr); /* a large model takes seconds */
	struct model *m = model_load(a->operand[0], err, sizeof(err));
	if (!m) {
		fprintf(stderr, "spindlectl: %s\n", err);
		return CTL_INPUT;
	}
	int ret = model_order_spatial(m); /* neighbours together: binned and sectioned faster */
	if (ret < 0) {
		fprintf(stderr, "spindlectl: %s: %s\n", a->operand[0], strerror(-ret));
		model_destroy(m);
		return CTL_FAILED;
	}
	struct spindle *sp = ctl_connect(a);
	status = sp ? CTL_FAILED : CTL_CONNECT;
	if (sp) {
		status = show_model(sp, m, a);
		spindle_disconnect(sp);
	}
	model_destroy(m);
	return status;
}

/* ---- pattern ---- */

static int cmd_pattern(const struct ctl_args *a)
{
	struct model *probe = pattern_build(a->operand[0], 1.0f);
	if (!probe && errno == EINVAL) {
		char msg[256];
		snprintf(msg, sizeof(msg), "unknown pattern '%.64s' (one of: %s)", a->operand[0], pattern_names);
		return ctl_usage_error("%s", msg);
	}
	model_destroy(probe);
	struct spindle *sp = ctl_connect(a);
	if (!sp)
		return CTL_CONNECT;
	/* In volume space as it is: made for this display's half height. */
	struct model *m = pattern_build(a->operand[0], spindle_get_device_info(sp)->half_height);
	struct ctl_args as_is = *a;
	as_is.no_fit = true;
	int status = m ? show_model(sp, m, &as_is) : CTL_FAILED;
	if (!m)
		ctl_report_failure(NULL, "pattern", -errno);
	model_destroy(m);
	spindle_disconnect(sp);
	return status;
}

/* ---- capture ---- */

/* Checks the memfd holds one whole .svol file; fills hdr. */
static int check_capture(int fd, size_t size, struct svol_header *hdr)
{
	uint8_t raw[SVOL_HEADER_SIZE];
	if (size < SVOL_HEADER_SIZE || pread(fd, raw, sizeof(raw), 0) != (ssize_t)sizeof(raw))
		return -EINVAL;
	int ret = svol_header_decode(raw, hdr);
	if (ret < 0)
		return ret;
	return svol_file_size(hdr) == size ? 0 : -EINVAL;
}

static int copy_fd(int in, int out, size_t size)
{
	char buf[1 << 16];
	off_t off = 0;
	while ((size_t)off < size) {
		size_t want = size - (size_t)off < sizeof(buf) ? size - (size_t)off : sizeof(buf);
		ssize_t n = pread(in, buf, want, off);
		if (n <= 0)
			return n < 0 ? -errno : -EIO;
		for (ssize_t done = 0; done < n;) {
			ssize_t w = write(out, buf + done, (size_t)(n - done));
			if (w < 0 && errno != EINTR)
				return -errno;
			done += w > 0 ? w : 0;
		}
		off += n;
	}
	return 0;
}

static int save_capture(int fd, size_t size, const char *path)
{
	int out = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
	if (out < 0) {
		fprintf(stderr, "spindlectl: %s: %s\n", path, strerror(errno));
		return CTL_FAILED;
	}
	int ret = copy_fd(fd, out, size);
	if (close(out) < 0 && ret == 0)
		ret = -errno;
	if (ret < 0) {
		fprintf(stderr, "spindlectl: %s: %s\n", path, strerror(-ret));
		unlink(path);
		return CTL_FAILED;
	}
	return 0;
}

static int cmd_capture(const struct ctl_args *a)
{
	struct svol_header hdr;
	size_t size = 0;
	int fd = -1, status = 1;
	struct spindle *sp = ctl_connect(a);
	if (!sp)
		return CTL_CONNECT;
	int ret = spindle_capture(sp, &fd, &size);
	if (ret == -EACCES) {
		fprintf(stderr, "spindlectl: capture refused: only root, the daemon's user and members of its admin "
				"group (spindled's admin-group, default spindle-admin) may capture\n");
		status = CTL_REFUSED;
		goto out_disconnect;
	} else if (ret < 0) {
		ctl_report_failure(sp, "capture", ret);
		goto out_disconnect;
	}
	if (check_capture(fd, size, &hdr) < 0) {
		fprintf(stderr, "spindlectl: capture: the daemon sent no valid .svol file\n");
		goto out_close;
	}
	status = save_capture(fd, size, a->operand[0]);
	if (status == 0)
		printf("captured volume %llu: %ux%u, %u images -> %s\n", (unsigned long long)hdr.seq, hdr.width,
		       hdr.height, hdr.image_count, a->operand[0]);
out_close:
	close(fd);
out_disconnect:
	spindle_disconnect(sp);
	return status;
}

/* ---- preview ---- */

static int cmd_preview(const struct ctl_args *a)
{
	struct preview_options opt;
	FILE *f = fopen(a->operand[0], "rb");
	if (!f) {
		fprintf(stderr, "spindlectl: %s: %s\n", a->operand[0], strerror(errno));
		return CTL_INPUT;
	}
	struct volume *vol = svol_read(f);
	int e = errno;
	fclose(f);
	if (!vol) {
		fprintf(stderr, "spindlectl: %s: %s\n", a->operand[0],
			e == EINVAL ? "not a valid .svol file" : strerror(e));
		return CTL_INPUT;
	}
	preview_default_options(&opt);
	if (a->has_size)
		opt.width = opt.height = a->size;
	opt.progress = stderr; /* a large picture takes seconds */
	opt.progress_name = a->operand[1];
	int ret = preview_volume_to_png(vol, &opt, a->operand[1]);
	volume_destroy(vol);
	if (ret < 0) {
		fprintf(stderr, "spindlectl: %s: %s\n", a->operand[1], strerror(-ret));
		return CTL_FAILED;
	}
	return 0;
}

/* ---- command line ---- */

static int parse_color(const char *s, uint8_t rgb[3])
{
	char *end;
	if (*s == '#')
		s++;
	if (strlen(s) != 6 || strspn(s, "0123456789abcdefABCDEF") != 6)
		return -EINVAL;
	unsigned long v = strtoul(s, &end, 16);
	rgb[0] = (uint8_t)(v >> 16);
	rgb[1] = (uint8_t)(v >> 8);
	rgb[2] = (uint8_t)v;
	return 0;
}

static int parse_size(const char *s, uint32_t *out)
{
	char *end;
	errno = 0;
	unsigned long v = strtoul(s, &end, 10);
	if (errno || end == s || *end || v < 16 || v > 16384)
		return -EINVAL;
	*out = (uint32_t)v;
	return 0;
}

enum { OPT_NO_FIT = 256, OPT_COLOR, OPT_SIZE, OPT_JSON, OPT_SAVE, OPT_CONFIG };

static const struct option long_options[] = {
	{ "socket", required_argument, NULL, 's' },
	{ "help", no_argument, NULL, 'h' },
	{ "version", no_argument, NULL, 'V' },
	{ "no-fit", no_argument, NULL, OPT_NO_FIT },
	{ "color", required_argument, NULL, OPT_COLOR },
	{ "size", required_argument, NULL, OPT_SIZE },
	{ "json", no_argument, NULL, OPT_JSON },
	{ "save", no_argument, NULL, OPT_SAVE },
	{ "config", required_argument, NULL, OPT_CONFIG },
	{ "window", required_argument, NULL, CTL_OPT_WINDOW },
	{ "preset", required_argument, NULL, CTL_OPT_PRESET },
	{ "threshold", required_argument, NULL, CTL_OPT_THRESHOLD },
	{ "sampling", required_argument, NULL, CTL_OPT_SAMPLING },
	{ "dims", required_argument, NULL, CTL_OPT_DIMS },
	{ "type", required_argument, NULL, CTL_OPT_TYPE },
	{ "spacing", required_argument, NULL, CTL_OPT_SPACING },
	{ "offset", required_argument, NULL, CTL_OPT_OFFSET },
	{ "big-endian", no_argument, NULL, CTL_OPT_BIG_ENDIAN },
	{ NULL, 0, NULL, 0 },
};

/* Returns -1 to go on, else the exit status (help, version, bad usage). */
static int parse_option(int c, struct ctl_args *a)
{
	switch (c) {
	case 's':
		a->socket = optarg;
		return -1;
	case 'h':
		fputs(usage_text, stdout);
		return 0;
	case 'V':
		printf("spindlectl %s (protocol %d)\n", SPINDLE_VERSION, SPINDLE_PROTOCOL_VERSION);
		return 0;
	case OPT_NO_FIT:
		a->no_fit = true;
		return -1;
	case OPT_COLOR:
		a->has_color = true;
		return parse_color(optarg, a->color) < 0 ? ctl_usage_error("bad colour '%s' (want RRGGBB)", optarg)
							 : -1;
	case OPT_SIZE:
		a->has_size = true;
		return parse_size(optarg, &a->size) < 0 ? ctl_usage_error("bad size '%s' (want 16..16384)", optarg)
							: -1;
	case OPT_JSON:
		a->json = true;
		return -1;
	case OPT_SAVE:
		a->save = true;
		return -1;
	case OPT_CONFIG:
		a->config = optarg;
		return -1;
	default:
		if (c >= CTL_OPT_WINDOW && c <= CTL_OPT_SCAN_LAST)
			return ctl_scan_option(c, optarg, a);
		/* getopt has said what was wrong */
		fprintf(stderr, "Try 'spindlectl --help'.\n");
		return CTL_USAGE;
	}
}

struct ctl_command {
	const char *name;
	int operands, or_operands; /* how many it takes (or_operands: also that many, when not 0) */
	bool show_opts, preview_opts, status_opts;
	int (*run)(const struct ctl_args *a);
};

static const struct ctl_command commands[] = {
	{ "status", 0, 0, false, false, true, cmd_status },
	{ "show", 1, 0, true, false, false, cmd_show },
	{ "capture", 1, 0, false, false, false, cmd_capture },
	{ "pattern", 1, 0, false, false, false, cmd_pattern },
	{ "preview", 2, 0, false, true, false, cmd_preview },
	{ "calibrate", 0, 2, false, false, false, cmd_calibrate },
};

/* Picks the command and checks its operands and options. */
static const struct ctl_command *check_command(const struct ctl_args *a, int *status)
{
	const struct ctl_command *cmd = NULL;
	for (size_t i = 0; i < sizeof(commands) / sizeof(commands[0]); i++)
		if (strcmp(commands[i].name, a->command) == 0)
			cmd = &commands[i];
	*status = CTL_USAGE;
	if (!cmd)
		ctl_usage_error("unknown command '%s'", a->command);
	else if (a->operand_count != cmd->operands && (!cmd->or_operands || a->operand_count != cmd->or_operands))
		ctl_usage_error("wrong number of arguments for '%s'", cmd->name);
	else if ((a->no_fit || a->has_color) && !cmd->show_opts)
		ctl_usage_error("--no-fit and --color go with 'show', not '%s'", cmd->name);
	else if (ctl_scan_options_given(a) && !cmd->show_opts)
		ctl_usage_error("the scan options (--window, --preset, --threshold, --sampling, --dims, ...) go "
				"with 'show', not '%s'",
				cmd->name);
	else if (a->has_size && !cmd->preview_opts)
		ctl_usage_error("--size goes with 'preview', not '%s'", cmd->name);
	else if (a->json && !cmd->status_opts)
		ctl_usage_error("--json goes with 'status', not '%s'", cmd->name);
	else if ((a->save || a->config) && cmd->run != cmd_calibrate)
		ctl_usage_error("--save and --config go with 'calibrate', not '%s'", cmd->name);
	else
		return cmd;
	return NULL;
}

static bool is_negative_number(const char *s)
{
	char *end;
	if (s[0] != '-' || !s[1])
		return false;
	(void)strtod(s, &end);
	return *end == '\0';
}

/* Whether arg is an option that takes the next argument as its value
 * (-s PATH, --threshold -500; not --threshold=-500): a long option it
 * names or abbreviates, as getopt_long() takes them. */
static bool takes_next(const char *arg)
{
	if (!strcmp(arg, "-s"))
		return true;
	if (strncmp(arg, "--", 2) != 0 || !arg[2] || strchr(arg, '='))
		return false;
	for (const struct option *o = long_options; o->name; o++)
		if (o->has_arg == required_argument && !strncmp(o->name, arg + 2, strlen(arg + 2)))
			return true;
	return false;
}

/* Whether argv[i] is a negative number that is an operand. */
static bool negative_operand(char **argv, int i)
{
	return is_negative_number(argv[i]) && !(i > 1 && takes_next(argv[i - 1]));
}

/* A negative number (calibrate axis-offset-v -5) is an operand, not
 * options: such arguments move behind a "--" at the end, in their order,
 * so that getopt leaves them to the operands; the value of an option
 * (--threshold -500) stays. Returns argv itself when there is none or the
 * user wrote "--", else a new array to free. */
static char **negatives_last(int argc, char **argv, int *out_argc)
{
	*out_argc = argc;
	int moved = 0;
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--"))
			return argv;
		moved += negative_operand(argv, i);
	}
	char **out = moved ? calloc((size_t)argc + 2, sizeof(*out)) : NULL;
	if (!out)
		return argv;
	int n = 0;
	for (int i = 0; i < argc; i++)
		if (i == 0 || !negative_operand(argv, i))
			out[n++] = argv[i];
	out[n++] = "--";
	for (int i = 1; i < argc; i++)
		if (negative_operand(argv, i))
			out[n++] = argv[i];
	*out_argc = n;
	return out;
}

/* Options and operands into a. Returns -1 to go on, else the exit status. */
static int parse_command_line(int argc, char **argv, struct ctl_args *a)
{
	int c, status;
	while ((c = getopt_long(argc, argv, "s:hV", long_options, NULL)) != -1) {
		if ((status = parse_option(c, a)) >= 0)
			return status;
	}
	if (optind >= argc)
		return ctl_usage_error("%s", "no command given");
	a->command = argv[optind++];
	for (; optind < argc; optind++) {
		if (a->operand_count == 2)
			return ctl_usage_error("too many arguments for '%s'", a->command);
		a->operand[a->operand_count++] = argv[optind];
	}
	return -1;
}

int main(int argc, char **argv)
{
	struct ctl_args a = { 0 };
	int status;

	/* A closed stdout or socket must give an error return, not kill us. */
	signal(SIGPIPE, SIG_IGN);

	char **args = negatives_last(argc, argv, &argc);
	status = parse_command_line(argc, args, &a);
	if (args != argv)
		free(args);
	if (status >= 0)
		return status;
	const struct ctl_command *cmd = check_command(&a, &status);
	return cmd ? cmd->run(&a) : status;
}
