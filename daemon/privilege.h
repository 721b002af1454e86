/* Giving up root: a daemon started as root runs as the configured user
 * (config key user) once its devices and its socket are open. */
#ifndef SPINDLE_PRIVILEGE_H
#define SPINDLE_PRIVILEGE_H

/* Started as root: becomes user (its uid, its gid and the supplementary
 * groups /etc/group gives it, which is where the device group comes from)
 * with no capabilities and no_new_privs, then checks that root cannot come
 * back; "root" keeps root, with a warning. Not root: sets no_new_privs only.
 * 0 or a negative errno, each failing step logged; on failure the caller must
 * exit, as the process may be half switched. */
int privilege_drop(const char *user);

#endif
