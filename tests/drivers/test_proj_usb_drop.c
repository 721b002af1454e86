/* The USB projector re-plugged after the privilege drop.
 *
 * spindled opens its devices as root and then becomes its user
 * (privilege_drop(): no capabilities, no_new_privs); the projector may be
 * unplugged and plugged again after that, and the udev rule gives its node
 * to a group the daemon's user is in (root:G 0660). The test plays that in
 * a process of its own, this program run again with AFTER_DROP_ARG: it
 * cannot come back to root, and a mere fork of this process could not
 * safely use GLib (umockdev's), whose threads a fork leaves behind.
 *
 * The parent stays root and plays udev: each time the device is plugged,
 * the child (playing the kernel as well as running the driver) asks it
 * over a socket to apply the rule to the node; the child waits for the
 * answer before it returns from the plug, so the node has its owner, group
 * and mode before the driver can try it, as udev applies a rule before
 * libudev's listeners hear of the device. The child's user is nobody, its
 * group nobody's own (the group a real rule names is a supplementary one,
 * which privilege_drop() sets through initgroups() as it does the primary:
 * unit-privilege checks them). */

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "privilege.h"
#include "proj_usb_rig.h"
#include "volume_util.h"

struct rule_request {
	char path[PATH_MAX];
	uint32_t gid, mode; /* the owner is root */
};

/* The child's end: usb_emul's node rule. */
struct udev_link {
	int fd;
	gid_t gid;
	mode_t mode;
};

static int ask_udev(void *data, const char *path)
{
	const struct udev_link *u = data;
	struct rule_request q = { .gid = u->gid, .mode = u->mode };
	snprintf(q.path, sizeof(q.path), "%s", path);
	if (send(u->fd, &q, sizeof(q), MSG_NOSIGNAL) != (ssize_t)sizeof(q))
		return -EIO;
	int r;
	if (recv(u->fd, &r, sizeof(r), 0) != (ssize_t)sizeof(r))
		return -EIO;
	return r;
}

/* The parent's end, until the child closes its own (it is done). */
static int serve_udev(int fd)
{
	struct rule_request q;
	ssize_t n;
	int served = 0;
	while ((n = recv(fd, &q, sizeof(q), 0)) == (ssize_t)sizeof(q)) {
		q.path[sizeof(q.path) - 1] = '\0';
		int r = 0;
		if (lchown(q.path, 0, q.gid) < 0 || chmod(q.path, q.mode) < 0)
			r = -errno;
		CHECK(send(fd, &r, sizeof(r), MSG_NOSIGNAL) == (ssize_t)sizeof(r));
		served++;
	}
	CHECK_EQ(n, 0);
	return served;
}

/* The environment for the child: this one, with no testbed and without
 * LeakSanitizer, which cannot stop the world of a process that gave up
 * root (no longer dumpable, it may not ptrace its own threads); so does
 * tests/conformance/test_service.py for spindled. */
static char **child_env(char **opt_out)
{
	extern char **environ;
	size_t n = 0;
	while (environ[n])
		n++;
	char **env = calloc(n + 2, sizeof(*env));
	CHECK(env);
	const char *asan = getenv("ASAN_OPTIONS");
	char *opt = malloc(strlen("ASAN_OPTIONS=") + (asan ? strlen(asan) : 0) + strlen(":detect_leaks=0") + 1);
	CHECK(opt);
	sprintf(opt, "ASAN_OPTIONS=%s%sdetect_leaks=0", asan ? asan : "", asan && *asan ? ":" : "");
	size_t k = 0;
	for (size_t i = 0; i < n; i++) {
		if (strncmp(environ[i], "ASAN_OPTIONS=", 13) && strncmp(environ[i], "UMOCKDEV_DIR=", 13))
			env[k++] = environ[i];
	}
	env[k] = opt;
	*opt_out = opt;
	return env;
}

/* A number of /proc/self/status, the value of "Key:" in base. */
static unsigned long long status_number(const char *key, int base)
{
	char line[512];
	size_t n = strlen(key);
	FILE *f = fopen("/proc/self/status", "re");
	CHECK(f);
	unsigned long long v = 0;
	bool found = false;
	while (!found && fgets(line, sizeof(line), f)) {
		if (!strncmp(line, key, n) && line[n] == ':') {
			v = strtoull(line + n + 1, NULL, base);
			found = true;
		}
	}
	fclose(f);
	CHECK_MSG(found, "no %s in /proc/self/status", key);
	return v;
}

/* The node as the rule left it: root's, group gid, mode; and whether this
 * process may open it. */
static bool check_node(struct usb_emul *e, gid_t gid, mode_t mode)
{
	struct stat st;
	const char *node = usb_emul_node_path(e);
	CHECK_MSG(stat(node, &st) == 0, "%s: %s", node, strerror(errno));
	CHECK_EQ(st.st_uid, 0);
	CHECK_EQ(st.st_gid, gid);
	CHECK_EQ(st.st_mode & 07777, mode);
	return access(node, R_OK | W_OK) == 0;
}

/* This process becomes nobody (uid, gid) as spindled becomes its user:
 * no capabilities, no_new_privs, no way back; the node open to it through
 * the group. */
static void drop_root(struct rig *r, uid_t uid, gid_t gid)
{
	CHECK_EQ(privilege_drop("nobody"), 0);
	CHECK_EQ(getuid(), uid);
	CHECK_EQ(geteuid(), uid);
	CHECK_EQ(getgid(), gid);
	CHECK_EQ(status_number("CapEff", 16), 0);
	CHECK_EQ(status_number("NoNewPrivs", 10), 1);
	CHECK(setuid(0) < 0);
	CHECK(check_node(r->emul, gid, 0660)); /* through the group: not the owner */
	printf("after the drop: uid %u gid %u, CapEff 0, no_new_privs; node root:%u 0660\n", (unsigned)getuid(),
	       (unsigned)getgid(), (unsigned)gid);
}

/* Out mid-upload and in again: a new node, which udev gives the group;
 * the unprivileged driver finds it and shows. */
static void replug_after_drop(struct rig *r, struct volume *large, gid_t gid)
{
	struct proj_usb_debug dbg;
	proj_usb_get_debug(r->p, &dbg);
	uint64_t events = dbg.usb.hotplug_arrivals;
	unplug_mid_upload(r, large);
	int64_t ms = replug(r, &big);
	CHECK(check_node(r->emul, gid, 0660));
	large->seq = 71;
	upload_and_show(r, 1, large);
	proj_usb_get_debug(r->p, &dbg);
	if (dbg.usb.hotplug) /* the uevent reached the unprivileged driver (it or a rescan opened the device) */
		CHECK(dbg.usb.hotplug_arrivals > events);
	printf("hot-plug after the drop: libusb events %s; re-plug found in %lld ms; arrivals seen %llu, "
	       "removals %llu, found by rescan %llu\n",
	       dbg.usb.hotplug ? "on" : "off", (long long)ms, (unsigned long long)dbg.usb.hotplug_arrivals,
	       (unsigned long long)dbg.usb.hotplug_removals, (unsigned long long)dbg.usb.rescan_opens);
}

/* The control's first half: out again, and in with a node only root may
 * open (udev's rule so), which the hot-plug event and two rescans
 * announce and the driver cannot open: absent, nothing of it left open.
 * Returns the opens refused. */
static int refused_root_only(struct rig *r, struct volume *large, struct udev_link *udev)
{
	unplug_mid_upload(r, large);
	CHECK_EQ(usb_emul_wait_closed(r->emul, 2000), 0); /* the driver holds nothing of it */
	int arrived = r->ev.arrived;
	*udev = (struct udev_link){ .fd = udev->fd, .gid = 0, .mode = 0600 };
	CHECK_EQ(usb_emul_plug(r->emul, &big, 3, 0), 0);
	/* libusb's hot-plug thread reads the new device's sysfs files: let it
	 * (the driver tries nothing until run_for() below), then count the
	 * fds, the device model's included. */
	struct timespec settle = { .tv_nsec = 100000000 };
	nanosleep(&settle, NULL);
	int fds = count_fds();
	CHECK(!check_node(r->emul, 0, 0600));
	CHECK_EQ(errno, EACCES);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(r->p, &dbg);
	uint64_t events = dbg.usb.hotplug_arrivals;
	run_for(r->p, 1200); /* the hot-plug event and two rescans */
	CHECK_EQ(r->ev.arrived, arrived);
	proj_usb_get_debug(r->p, &dbg);
	if (dbg.usb.hotplug)
		CHECK(dbg.usb.hotplug_arrivals > events); /* announced, and still refused */
	/* Each refused open left a socket of the preload library's (see
	 * usb_emul_close_stray_sockets()), none of the driver's. */
	int refused = usb_emul_close_stray_sockets(r->emul);
	CHECK(refused >= 1);
	CHECK_EQ(usb_emul_wait_closed(r->emul, 2000), 0);
	CHECK_EQ(count_fds(), fds);
	struct projector_stats st;
	r->p->impl->get_stats(r->p, &st);
	CHECK(!st.present);
	struct projector_info info;
	CHECK_EQ(r->p->impl->get_info(r->p, &info), -ENODEV);
	CHECK_EQ(r->p->impl->upload(r->p, 2, large, NULL, NULL), -ENODEV);
	return refused;
}

/* The control's second half: once udev gives the node the group, a
 * rescan opens it and the driver shows. */
static void granted(struct rig *r, struct volume *large, struct udev_link *udev, gid_t gid, int refused)
{
	int arrived = r->ev.arrived;
	udev->gid = gid;
	udev->mode = 0660;
	CHECK_EQ(usb_emul_apply_node_rule(r->emul), 0);
	CHECK(check_node(r->emul, gid, 0660));
	int64_t ms = wait_for(r->p, &r->ev.arrived, arrived, 2000);
	large->seq = 72;
	upload_and_show(r, 2, large);
	struct proj_usb_debug dbg;
	proj_usb_get_debug(r->p, &dbg);
	printf("root-only node after the drop: absent through 1200 ms of hot-plug and rescans (%d opens refused); "
	       "given the group, found in %lld ms (found by rescan %llu)\n",
	       refused, (long long)ms, (unsigned long long)dbg.usb.rescan_opens);
	struct projector_stats st;
	r->p->impl->get_stats(r->p, &st);
	CHECK_EQ(st.arrivals, 3); /* at the start, after the drop, given the group */
	CHECK_EQ(r->ev.arrived, 2);
	CHECK_EQ(r->ev.gone, 2);
}

/* The child, as root at first: the driver open and showing, then the drop,
 * then the device out and in again, twice. Its CHECKs exit it with 1. */
int after_drop(int udev_fd)
{
	setvbuf(stdout, NULL, _IOLBF, 0); /* in order with the driver's log */
	const struct passwd *pw = getpwnam("nobody");
	CHECK(pw);
	const uid_t uid = pw->pw_uid;
	const gid_t gid = pw->pw_gid;
	CHECK(uid != 0 && gid != 0);
	struct volume *large = volume_create(&big);
	CHECK(large);
	random_volume(large, 8, 1);
	struct udev_link udev = { .fd = udev_fd, .gid = gid, .mode = 0660 };
	/* As root, as spindled at its start: the projector found (its node
	 * given the group by udev at boot) and showing. */
	struct rig r;
	rig_init(&r, &big, &big, 0);
	usb_emul_set_node_rule(r.emul, ask_udev, &udev);
	CHECK_EQ(usb_emul_apply_node_rule(r.emul), 0);
	large->seq = 70;
	upload_and_show(&r, 2, large); /* unplug_mid_upload() uploads to 0 */
	/* This process goes on playing the kernel for the testbed (see
	 * usb_emul_chown_testbed()); only the node is left to udev. */
	CHECK_EQ(usb_emul_chown_testbed(r.emul, uid, gid), 0);
	drop_root(&r, uid, gid);
	replug_after_drop(&r, large, gid);
	granted(&r, large, &udev, gid, refused_root_only(&r, large, &udev));
	rig_finish(&r);
	volume_destroy(large);
	close(udev_fd);
	printf("after the drop: ");
	return check_done();
}

void test_hotplug_after_drop(const char *self)
{
	if (geteuid() != 0 || !getpwnam("nobody")) {
		printf("hot-plug after the privilege drop: skipped (needs root and a user nobody)\n");
		return;
	}
	int sv[2];
	CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) == 0);
	char fd_arg[16];
	snprintf(fd_arg, sizeof(fd_arg), "%d", sv[1]);
	char *argv[] = { (char *)self, AFTER_DROP_ARG, fd_arg, NULL };
	char *asan_opt;
	char **env = child_env(&asan_opt);
	fflush(NULL);
	pid_t pid = fork();
	CHECK(pid >= 0);
	if (pid == 0) {
		/* Only async-signal-safe calls between fork and exec. */
		if (fcntl(sv[1], F_SETFD, 0) == 0)
			execve(self, argv, env);
		_exit(127);
	}
	close(sv[1]);
	free(asan_opt);
	free(env);
	int served = serve_udev(sv[0]);
	close(sv[0]);
	int status;
	CHECK_EQ(waitpid(pid, &status, 0), pid);
	CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "the child that dropped root: status 0x%x", status);
	CHECK_EQ(served, 4); /* at the start, at each of the two plugs after the drop, and the fix */
}
