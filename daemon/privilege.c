#include "privilege.h"

#include <errno.h>
#include <grp.h>
#include <inttypes.h>
#include <pwd.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <unistd.h>

#include "log.h"

static int no_new_privs(void)
{
	if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) < 0) {
		int r = -errno;
		log_error("privileges: PR_SET_NO_NEW_PRIVS: %s", strerror(-r));
		return r;
	}
	return 0;
}

/* getpwnam() says "not found" with any of these (getpwnam(3)). */
static bool not_found(int err)
{
	return err == 0 || err == ENOENT || err == ESRCH || err == EBADF || err == EPERM;
}

/* The user's ids; -ENOENT when there is no such user. */
static int lookup(const char *user, uid_t *uid, gid_t *gid)
{
	errno = 0;
	struct passwd *pw = getpwnam(user);
	if (!pw) {
		int r = not_found(errno) ? -ENOENT : -errno;
		if (r == -ENOENT)
			log_error("privileges: no user '%s' to run as: create it (systemd-sysusers, which reads "
				  "spindle.conf in sysusers.d, or useradd --system %s), or name another with "
				  "--user NAME or --set user=NAME",
				  user, user);
		else
			log_error("privileges: looking up user '%s': %s", user, strerror(-r));
		return r;
	}
	*uid = pw->pw_uid;
	*gid = pw->pw_gid;
	return 0;
}

/* Groups first, while still root; then the gid, then the uid, all three
 * (real, effective, saved) of each. Leaving root clears the capabilities. */
static int switch_ids(const char *user, uid_t uid, gid_t gid)
{
	if (initgroups(user, gid) < 0) {
		int r = -errno;
		log_error("privileges: initgroups(%s): %s", user, strerror(-r));
		return r;
	}
	if (setresgid(gid, gid, gid) < 0) {
		int r = -errno;
		log_error("privileges: setresgid(%u): %s", (unsigned)gid, strerror(-r));
		return r;
	}
	if (setresuid(uid, uid, uid) < 0) {
		int r = -errno;
		log_error("privileges: setresuid(%u): %s", (unsigned)uid, strerror(-r));
		return r;
	}
	return 0;
}

static int verify_ids(uid_t uid, gid_t gid)
{
	uid_t ru, eu, su;
	gid_t rg, eg, sg;
	if (getresuid(&ru, &eu, &su) < 0 || getresgid(&rg, &eg, &sg) < 0) {
		int r = -errno;
		log_error("privileges: reading back the ids: %s", strerror(-r));
		return r;
	}
	if (ru != uid || eu != uid || su != uid || rg != gid || eg != gid || sg != gid) {
		log_error("privileges: ids are uid %u/%u/%u gid %u/%u/%u, not %u and %u", (unsigned)ru, (unsigned)eu,
			  (unsigned)su, (unsigned)rg, (unsigned)eg, (unsigned)sg, (unsigned)uid, (unsigned)gid);
		return -EPERM;
	}
	if (setuid(0) == 0) {
		log_error("privileges: setuid(0) still succeeds after dropping root");
		return -EPERM;
	}
	return 0;
}

/* The value of a "Key:\tvalue" line of /proc/self/status, in base; false
 * when the line is missing or does not parse. */
static bool status_value(const char *text, const char *key, int base, uint64_t *value)
{
	size_t n = strlen(key);
	const char *line = text;
	while (strncmp(line, key, n) || line[n] != ':') {
		line = strchr(line, '\n');
		if (!line)
			return false;
		line++;
	}
	const char *start = line + n + 1;
	char *end;
	errno = 0;
	*value = strtoull(start, &end, base);
	return !errno && end != start && (*end == '\n' || *end == '\0');
}

static int read_status(char *buf, size_t size)
{
	FILE *f = fopen("/proc/self/status", "re");
	if (!f) {
		int r = -errno;
		log_error("privileges: /proc/self/status: %s", strerror(-r));
		return r;
	}
	size_t len = fread(buf, 1, size - 1, f);
	fclose(f);
	buf[len] = '\0';
	return 0;
}

/* What the kernel says: no capabilities left, no_new_privs set. */
static int verify_status(void)
{
	static const struct {
		const char *key;
		int base;
		uint64_t want;
	} fields[] = { { "CapEff", 16, 0 }, { "CapPrm", 16, 0 }, { "CapAmb", 16, 0 }, { "NoNewPrivs", 10, 1 } };
	char buf[8192];
	int r = read_status(buf, sizeof(buf));
	if (r < 0)
		return r;
	for (size_t i = 0; i < sizeof(fields) / sizeof(fields[0]); i++) {
		uint64_t v;
		if (!status_value(buf, fields[i].key, fields[i].base, &v)) {
			log_error("privileges: no %s in /proc/self/status", fields[i].key);
			return -EPERM;
		}
		if (v != fields[i].want) {
			log_error("privileges: %s is %" PRIx64 " after dropping root, not %" PRIx64, fields[i].key, v,
				  fields[i].want);
			return -EPERM;
		}
	}
	return 0;
}

int privilege_drop(const char *user)
{
	if (geteuid() != 0) {
		log_debug("privileges: already running unprivileged (uid %u)", (unsigned)geteuid());
		return no_new_privs();
	}
	if (!strcmp(user, "root")) {
		log_warn("privileges: user = root: keeps running as root (for tests and development only)");
		return 0;
	}
	uid_t uid = (uid_t)-1; /* set by lookup() */
	gid_t gid = (gid_t)-1;
	int r = lookup(user, &uid, &gid);
	if (r < 0)
		return r;
	if ((r = switch_ids(user, uid, gid)) < 0 || (r = no_new_privs()) < 0 || (r = verify_ids(uid, gid)) < 0 ||
	    (r = verify_status()) < 0)
		return r;
	log_info("privileges: running as user %s (uid %u, gid %u)", user, (unsigned)uid, (unsigned)gid);
	return 0;
}
