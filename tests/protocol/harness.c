#include "harness.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "svol.h"

static void sleep_ms(int ms)
{
	struct timespec ts = { ms / 1000, (ms % 1000) * 1000000L };
	nanosleep(&ts, NULL);
}

void daemon_start(struct daemon *d)
{
	const char *r = getenv("SPINDLE_TEST_RENDERER");
	daemon_start_renderer(d, r && *r ? r : NULL);
	if (!*d->renderer)
		return;
	if (strcmp(d->renderer, "auto") != 0)
		daemon_require_renderer(d, d->renderer);
	const char *fault = getenv("SPINDLE_GL_FAULT");
	d->strict_gl = (!strcmp(d->renderer, "egl") || !strcmp(d->renderer, "osmesa")) && !(fault && *fault);
}

void daemon_require_renderer(struct daemon *d, const char *name)
{
	/* Both lines are logged before the socket is opened. */
	char line[64];
	snprintf(line, sizeof(line), "renderer '%s' unavailable", name);
	if (daemon_log_contains(d, line)) {
		printf("SKIP: spindled cannot run the %s renderer here; its log:\n", name);
		fflush(stdout);
		daemon_print_log(d);
		daemon_stop(d);
		exit(77);
	}
	snprintf(line, sizeof(line), "renderer: %s\n", name);
	if (!daemon_log_contains(d, line)) {
		fprintf(stderr, "spindled does not run the %s renderer; its log:\n", name);
		daemon_print_log(d);
		CHECK(false);
	}
}

static void spawn(struct daemon *d, const char *renderer, const char *config);

void daemon_start_renderer(struct daemon *d, const char *renderer)
{
	spawn(d, renderer, NULL);
}

void daemon_start_config(struct daemon *d, const char *config)
{
	spawn(d, NULL, config);
}

static void spawn(struct daemon *d, const char *renderer, const char *config)
{
	const char *exe = getenv("SPINDLED");
	CHECK(exe != NULL);
	CHECK(!renderer || strlen(renderer) < sizeof(d->renderer));
	snprintf(d->renderer, sizeof(d->renderer), "%s", renderer ? renderer : "");
	d->strict_gl = false;
	snprintf(d->dir, sizeof(d->dir), "/tmp/spindle-test-XXXXXX");
	CHECK(mkdtemp(d->dir) != NULL);
	snprintf(d->socket, sizeof(d->socket), "%s/spindle.sock", d->dir);
	snprintf(d->log, sizeof(d->log), "%s/spindled.log", d->dir);
	char conf[128] = "/dev/null", text[1024];
	const struct calibration *cal = test_calibration();
	if (memcmp(cal, &(struct calibration){ .vertical_scale = 1.0f }, sizeof(*cal))) {
		snprintf(text, sizeof(text),
			 "%s\nphase-offset = %.9g\naxis-offset-u = %d\naxis-offset-v = %d\nvertical-scale = %.9g\n"
			 "vertical-offset = %.9g\n",
			 config ? config : "", (double)cal->phase_deg, cal->axis_u, cal->axis_v,
			 (double)cal->vertical_scale, (double)cal->vertical_offset);
		config = text;
	}
	if (config) {
		snprintf(conf, sizeof(conf), "%s/spindled.conf", d->dir);
		FILE *f = fopen(conf, "w");
		CHECK(f && fputs(config, f) >= 0 && fclose(f) == 0);
	}
	d->pid = fork();
	CHECK(d->pid >= 0);
	if (d->pid == 0) {
		prctl(PR_SET_PDEATHSIG, SIGKILL); /* never outlive a killed test */
		int log = open(d->log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
		if (log >= 0)
			dup2(log, 2);
		unsetenv("LISTEN_FDS");
		unsetenv("LISTEN_PID");
		/* brightness=exact: the suite's expectations are
		 * docs/design.md's per-image rules, the EXACT model. The
		 * default (EVEN) is checked by render-brightness and
		 * tools-brightness. */
		const char *argv[] = {
			exe,
			"--device",
			"sim",
			"--profile",
			"small",
			"--socket",
			d->socket,
			"--config",
			conf,
			"--set",
			"brightness=exact",
			"--verbose",
			renderer ? "--renderer" : NULL,
			renderer,
			NULL
		};
		execv(exe, (char *const *)argv);
		_exit(127);
	}
	for (int i = 0; i < 400; i++) {
		int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
		struct sockaddr_un a = { .sun_family = AF_UNIX };
		strcpy(a.sun_path, d->socket);
		int r = connect(fd, (struct sockaddr *)&a, sizeof(a));
		close(fd);
		if (r == 0)
			return;
		CHECK(daemon_alive(d));
		sleep_ms(10);
	}
	fprintf(stderr, "spindled did not start\n");
	exit(1);
}

bool daemon_alive(struct daemon *d)
{
	int status;
	return waitpid(d->pid, &status, WNOHANG) == 0;
}

void daemon_print_log(struct daemon *d)
{
	FILE *f = fopen(d->log, "r");
	char line[512];
	while (f && fgets(line, sizeof(line), f))
		fprintf(stderr, "  | %s", line);
	if (f)
		fclose(f);
}

void daemon_stop(struct daemon *d)
{
	daemon_stop_keep_log(d);
	daemon_remove_files(d);
}

void daemon_stop_keep_log(struct daemon *d)
{
	int status = 0;
	kill(d->pid, SIGTERM);
	for (int i = 0; i < 500 && waitpid(d->pid, &status, WNOHANG) == 0; i++)
		sleep_ms(10);
	if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
		fprintf(stderr, "spindled did not exit cleanly (status %#x); its log:\n", status);
		daemon_print_log(d);
		kill(d->pid, SIGKILL);
		exit(1);
	}
	struct stat st;
	CHECK(stat(d->socket, &st) < 0); /* removed on exit */
	if (d->strict_gl && daemon_log_contains(d, "falling back to the CPU renderer")) {
		fprintf(stderr, "the %s renderer failed and the CPU renderer took over; spindled's log:\n",
			d->renderer);
		daemon_print_log(d);
		CHECK(false);
	}
}

void daemon_remove_files(struct daemon *d)
{
	unlink(d->log);
	char conf[128];
	snprintf(conf, sizeof(conf), "%s/spindled.conf", d->dir);
	unlink(conf);
	rmdir(d->dir);
}

bool daemon_log_contains(struct daemon *d, const char *text)
{
	FILE *f = fopen(d->log, "r");
	CHECK(f != NULL);
	static char buf[1 << 20];
	size_t n = fread(buf, 1, sizeof(buf) - 1, f);
	fclose(f);
	buf[n] = '\0';
	return strstr(buf, text) != NULL;
}

int daemon_fd_count(struct daemon *d)
{
	char path[64];
	snprintf(path, sizeof(path), "/proc/%d/fd", (int)d->pid);
	DIR *dir = opendir(path);
	CHECK(dir != NULL);
	int n = 0;
	while (readdir(dir))
		n++;
	closedir(dir);
	return n - 2;
}

struct spindle *client_connect(struct daemon *d)
{
	struct spindle *sp = spindle_connect(d->socket);
	if (!sp)
		fprintf(stderr, "connect: %s\n", strerror(errno));
	CHECK(sp != NULL);
	return sp;
}

int raw_connect(struct daemon *d)
{
	int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
	struct sockaddr_un a = { .sun_family = AF_UNIX };
	strcpy(a.sun_path, d->socket);
	CHECK(connect(fd, (struct sockaddr *)&a, sizeof(a)) == 0);
	return fd;
}

int raw_send(int fd, uint32_t object, uint16_t opcode, const void *body, uint32_t body_size)
{
	uint8_t msg[12 + 4096];
	uint32_t size = 12 + body_size;
	uint16_t nfds = 0;
	CHECK(body_size <= 4096);
	memcpy(msg, &object, 4);
	memcpy(msg + 4, &opcode, 2);
	memcpy(msg + 6, &nfds, 2);
	memcpy(msg + 8, &size, 4);
	if (body_size)
		memcpy(msg + 12, body, body_size);
	return send(fd, msg, size, MSG_NOSIGNAL) == (ssize_t)size ? 0 : -errno;
}

bool raw_expect_error_and_close(int fd, uint32_t code)
{
	uint8_t buf[65536];
	size_t have = 0;
	bool got_error = false;
	for (;;) {
		struct pollfd p = { fd, POLLIN, 0 };
		if (poll(&p, 1, 3000) <= 0)
			return false; /* not closed in time */
		ssize_t n = recv(fd, buf + have, sizeof(buf) - have, 0);
		if (n <= 0)
			break;
		have += (size_t)n;
	}
	/* Walk the events: the last one must be display.error. */
	for (size_t off = 0; off + 12 <= have;) {
		uint32_t obj, size, ecode = 0;
		uint16_t op;
		memcpy(&obj, buf + off, 4);
		memcpy(&op, buf + off + 4, 2);
		memcpy(&size, buf + off + 8, 4);
		if (size < 12 || off + size > have)
			break;
		if (obj == 1 && op == 2 && size >= 24) {
			memcpy(&ecode, buf + off + 16, 4);
			got_error = code == 0 || ecode == code;
		}
		off += size;
	}
	return got_error;
}

struct volume *capture_volume(struct spindle *sp)
{
	int fd;
	size_t size;
	int r = spindle_capture(sp, &fd, &size);
	if (r < 0)
		fprintf(stderr, "capture: %s (%s)\n", strerror(-r), spindle_get_error(sp));
	CHECK(r == 0);
	FILE *f = fdopen(fd, "r");
	CHECK(f != NULL);
	struct volume *vol = svol_read(f);
	fclose(f);
	CHECK(vol != NULL);
	return vol;
}

void show_vertices(struct spindle *sp, int mode, const float *xyz, uint32_t count, uint8_t r, uint8_t g, uint8_t b)
{
	struct spindle_buffer *buf = spindle_buffer_create(sp, xyz, (size_t)count * 12);
	struct spindle_list *list = spindle_list_create(sp);
	struct spindle_layer *layer = spindle_layer_create(sp);
	CHECK(buf && list && layer);
	CHECK(spindle_list_set_color(list, r, g, b, 255) == 0);
	if (mode == 0)
		CHECK(spindle_list_points(list, buf, 0, count, 0) == 0);
	else if (mode == 1)
		CHECK(spindle_list_lines(list, buf, 0, count, 0) == 0);
	else
		CHECK(spindle_list_triangles(list, buf, 0, count, 0) == 0);
	CHECK(spindle_layer_set_list(layer, list) == 0);
	struct spindle_frame frame;
	CHECK(spindle_commit_and_wait(sp, &frame) == 0);
	CHECK(frame.volume_seq > 0 && frame.time_ns > 0);
}

const struct calibration *test_calibration(void)
{
	static struct calibration cal;
	static bool parsed;
	if (parsed)
		return &cal;
	calibration_identity(&cal);
	const char *env = getenv("SPINDLE_TEST_CALIBRATION");
	if (env && *env) {
		double v[5];
		char end;
		CHECK_MSG(sscanf(env, "%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &end) == 5,
			  "SPINDLE_TEST_CALIBRATION=%s: want PHASE,U,V,SCALE,OFFSET", env);
		for (unsigned k = 0; k < CALIBRATION_KEYS; k++)
			CHECK(calibration_set(&cal, k, v[k]) == 0);
	}
	parsed = true;
	return &cal;
}

void calibrated_point(double x, double y, double z, double out[3])
{
	const struct calibration *cal = test_calibration();
	double a = cal->phase_deg * M_PI / 180.0;
	out[0] = x * cos(a) + z * sin(a);
	out[1] = y * cal->vertical_scale + cal->vertical_offset;
	out[2] = -x * sin(a) + z * cos(a);
}

struct voxel expected_point(const struct geometry *g, double x, double y, double z)
{
	const struct calibration *cal = test_calibration();
	double p[3];
	calibrated_point(x, y, z, p);
	double phi = atan2(p[2], p[0]);
	uint32_t k = geometry_image_of_azimuth(g, phi);
	if (g->mirrored)
		k %= g->images_per_rev / 2;
	double th = geometry_image_angle(g, k);
	double s = p[0] * cos(th) + p[2] * sin(th);
	return (struct voxel){ k, geometry_column(g, s) + (uint32_t)cal->axis_u,
			       geometry_row(g, p[1]) + (uint32_t)cal->axis_v };
}

bool lit_near(const struct volume *vol, uint32_t k, int u, int v, int c, int radius)
{
	for (int dv = -radius; dv <= radius; dv++)
		for (int du = -radius; du <= radius; du++) {
			int uu = u + du, vv = v + dv;
			if (uu < 0 || vv < 0 || uu >= (int)vol->geom.width || vv >= (int)vol->geom.height)
				continue;
			if (volume_pixel(vol, k, (uint32_t)uu, (uint32_t)vv, c))
				return true;
		}
	return false;
}
