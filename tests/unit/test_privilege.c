/* daemon/privilege: as root, a child drops to nobody and the kernel must
 * agree (ids, groups, capabilities, no_new_privs), root must not come back
 * and a root-only file must stay closed; an unknown user fails and changes
 * nothing; "root" stays root. Skipped (77) when not run as root. */
#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "privilege.h"

/* The text after "Key:" on its line of /proc/self/status, into out. */
static void status_line(const char *key, char *out, size_t size)
{
	char buf[8192];
	FILE *f = fopen("/proc/self/status", "r");
	CHECK(f);
	size_t len = fread(buf, 1, sizeof(buf) - 1, f);
	fclose(f);
	buf[len] = '\0';
	size_t n = strlen(key);
	for (char *line = strtok(buf, "\n"); line; line = strtok(NULL, "\n")) {
		if (!strncmp(line, key, n) && line[n] == ':') {
			snprintf(out, size, "%s", line + n + 1);
			return;
		}
	}
	CHECK_MSG(0, "no %s in /proc/self/status", key);
}

static uint64_t status_number(const char *key, int base)
{
	char v[256];
	status_line(key, v, sizeof(v));
	return strtoull(v, NULL, base);
}

/* Each of the four ids of a "Uid:" or "Gid:" line is id. */
static void check_ids(const char *key, unsigned id)
{
	char v[256];
	unsigned a, b, c, d;
	status_line(key, v, sizeof(v));
	CHECK_MSG(sscanf(v, "%u %u %u %u", &a, &b, &c, &d) == 4, "%s:%s", key, v);
	CHECK_MSG(a == id && b == id && c == id && d == id, "%s:%s, want %u", key, v, id);
}

/* The supplementary groups are nobody's from /etc/group (initgroups), none
 * of root's (the parent gave itself 0 and ROOT_EXTRA_GID). */
#define ROOT_EXTRA_GID 4242
static void check_groups(const struct passwd *nobody)
{
	gid_t want[64];
	int n_want = 64;
	CHECK(getgrouplist(nobody->pw_name, nobody->pw_gid, want, &n_want) >= 0);
	char v[1024];
	status_line("Groups", v, sizeof(v));
	int seen = 0;
	for (char *tok = strtok(v, " \t"); tok; tok = strtok(NULL, " \t"), seen++) {
		unsigned long g = strtoul(tok, NULL, 10);
		bool wanted = false;
		for (int i = 0; i < n_want; i++)
			wanted |= want[i] == g;
		CHECK_MSG(wanted && g != 0 && g != ROOT_EXTRA_GID, "group %lu kept", g);
	}
	CHECK_EQ(seen, n_want);
}

/* Runs in the child: drop to nobody, then what must no longer work. */
static int dropped(const struct passwd *nobody, const char *secret)
{
	CHECK_EQ(privilege_drop("nobody"), 0);
	check_ids("Uid", nobody->pw_uid);
	check_ids("Gid", nobody->pw_gid);
	check_groups(nobody);
	CHECK_EQ(status_number("CapEff", 16), 0);
	CHECK_EQ(status_number("CapPrm", 16), 0);
	CHECK_EQ(status_number("CapAmb", 16), 0);
	CHECK_EQ(status_number("NoNewPrivs", 10), 1);
	errno = 0;
	CHECK(setuid(0) < 0 && errno == EPERM);
	CHECK(setgid(0) < 0 && errno == EPERM);
	errno = 0;
	int fd = open(secret, O_RDONLY | O_CLOEXEC);
	CHECK_MSG(fd < 0 && errno == EACCES, "open: fd %d, %s", fd, strerror(errno));
	/* Already unprivileged: nothing more to drop. */
	CHECK_EQ(privilege_drop("nobody"), 0);
	CHECK_EQ(getuid(), nobody->pw_uid);
	return check_done();
}

int main(void)
{
	if (geteuid() != 0) {
		printf("not root: skipped\n");
		return 77;
	}
	struct passwd *pw = getpwnam("nobody");
	if (!pw) {
		printf("no user nobody: skipped\n");
		return 77;
	}
	struct passwd nobody = *pw;
	CHECK(nobody.pw_uid != 0 && nobody.pw_gid != 0);

	/* A root-only file in a directory anyone may enter. */
	char dir[] = "/tmp/spindle-privilege-XXXXXX";
	char secret[sizeof(dir) + 16];
	CHECK(mkdtemp(dir));
	CHECK(chmod(dir, 0755) == 0);
	snprintf(secret, sizeof(secret), "%s/secret", dir);
	int fd = open(secret, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
	CHECK(fd >= 0);
	CHECK(write(fd, "root only\n", 10) == 10);
	close(fd);

	/* Supplementary groups of root's that the child must not keep. */
	gid_t root_groups[] = { 0, ROOT_EXTRA_GID };
	CHECK(setgroups(2, root_groups) == 0);
	fflush(stdout);
	pid_t pid = fork();
	CHECK(pid >= 0);
	if (pid == 0) {
		int rc = dropped(&nobody, secret);
		fflush(stdout);
		_exit(rc); /* no atexit handlers: LSan cannot trace a non-dumpable process */
	}
	int status;
	CHECK(waitpid(pid, &status, 0) == pid);
	CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "child status %#x", status);

	/* An unknown user: an error, and still root. */
	int r = privilege_drop("no-such-user-xyz");
	CHECK_MSG(r == -ENOENT, "privilege_drop: %d", r);
	CHECK_EQ(geteuid(), 0);
	/* "root": stays root. */
	CHECK_EQ(privilege_drop("root"), 0);
	CHECK_EQ(geteuid(), 0);
	CHECK_EQ(getuid(), 0);

	CHECK(unlink(secret) == 0);
	CHECK(rmdir(dir) == 0);
	return check_done();
}
