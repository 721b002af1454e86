/* Confining the model loader child (model_sandbox.h), and the scan
 * loader's (tools/scan_loader.c): no fds but its own, no privileges,
 * resource limits, and a seccomp filter, a raw BPF program (no
 * libseccomp): the architecture checked, then an allow list. What assimp
 * or a scan reader needs once the files are open: memory (brk, mmap,
 * mremap, munmap, madvise; never executable), reading the input fds (one
 * for a model; for a scan, a DICOM directory's files, a contiguous
 * range), writing the result pipe and stderr, futex, signals to itself
 * (abort), clocks, its ids, exit. Every other call fails with EPERM: open,
 * socket, execve, ptrace, kill of another process, clone... */
#include "model_sandbox.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <linux/audit.h>
#include <linux/capability.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <pwd.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#if defined(__x86_64__)
#define FILTER_ARCH AUDIT_ARCH_X86_64
#elif defined(__aarch64__)
#define FILTER_ARCH AUDIT_ARCH_AARCH64
#elif defined(__i386__)
#define FILTER_ARCH AUDIT_ARCH_I386
#elif defined(__arm__) && defined(__ARMEL__)
#define FILTER_ARCH AUDIT_ARCH_ARM
#elif defined(__riscv) && __riscv_xlen == 64
#define FILTER_ARCH AUDIT_ARCH_RISCV64
#endif

#define NOBODY_ID 65534

void model_confine_prepare(struct model_confine *c)
{
	uid_t r, e, s;
	memset(c, 0, sizeof(*c));
	c->parent = getpid();
	c->cpu_s = MODEL_LOADER_CPU_S;
	c->memory = MODEL_LOADER_MEMORY;
	if (getresuid(&r, &e, &s) < 0 || r == 0 || e == 0 || s == 0) {
		const struct passwd *pw = getpwnam("nobody");
		c->drop_user = true;
		c->uid = pw && pw->pw_uid != 0 ? pw->pw_uid : NOBODY_ID;
		c->gid = pw && pw->pw_gid != 0 ? pw->pw_gid : NOBODY_ID;
	}
}

static int fail(char *why, size_t why_size, const char *what, int err)
{
	snprintf(why, why_size, "%s: %s", what, strerror(err));
	return -err;
}

static void default_signals(void)
{
	sigset_t none;
	for (int sig = 1; sig < NSIG; sig++)
		if (sig != SIGKILL && sig != SIGSTOP)
			signal(sig, SIG_DFL);
	sigemptyset(&none);
	sigprocmask(SIG_SETMASK, &none, NULL);
}

static void close_between(unsigned first, unsigned last)
{
	if (first > last)
		return;
	if (close_range(first, last, 0) == 0)
		return;
	long max = sysconf(_SC_OPEN_MAX);
	for (unsigned fd = first; fd <= last && (long)fd < max; fd++)
		close((int)fd);
}

/* stdin and stdout on /dev/null; the count input fds moved to 3, 4, ...
 * in their order and the result pipe after them (through copies above
 * every fd involved, so that no move overwrites one still to be moved);
 * everything else closed but stderr. */
static int keep_fds(int *in_fds, unsigned count, int *out_fd)
{
	int base = *out_fd, copies[MODEL_CONFINE_MAX_INPUTS + 1];
	for (unsigned n = 0; n < count; n++)
		base = in_fds[n] > base ? in_fds[n] : base;
	base = base > (int)count + 3 ? base + 1 : (int)count + 4;
	for (unsigned n = 0; n <= count; n++) {
		copies[n] = fcntl(n < count ? in_fds[n] : *out_fd, F_DUPFD, base);
		if (copies[n] < 0)
			return -errno;
	}
	int null = open("/dev/null", O_RDWR);
	if (null < 0 || dup2(null, 0) < 0 || dup2(null, 1) < 0)
		return -errno;
	for (unsigned n = 0; n <= count; n++)
		if (dup2(copies[n], 3 + (int)n) < 0)
			return -errno;
	close_between(4 + count, ~0u);
	for (unsigned n = 0; n < count; n++)
		in_fds[n] = 3 + (int)n;
	*out_fd = 3 + (int)count;
	return 0;
}

static int drop_caps(void)
{
	struct __user_cap_header_struct hdr = { .version = _LINUX_CAPABILITY_VERSION_3 };
	struct __user_cap_data_struct data[_LINUX_CAPABILITY_U32S_3];
	memset(data, 0, sizeof(data));
	return syscall(SYS_capset, &hdr, data) < 0 ? -errno : 0;
}

static int drop_user(const struct model_confine *c, char *why, size_t why_size)
{
	uid_t r, e, s;
	if (c->drop_user) {
		if (setgroups(0, NULL) < 0)
			return fail(why, why_size, "cannot drop privileges: setgroups", errno);
		if (setresgid(c->gid, c->gid, c->gid) < 0 || setresuid(c->uid, c->uid, c->uid) < 0)
			return fail(why, why_size, "cannot drop privileges: setresuid", errno);
	}
	int ret = drop_caps();
	if (ret < 0)
		return fail(why, why_size, "cannot drop capabilities", -ret);
	if (c->drop_user && (getresuid(&r, &e, &s) < 0 || r == 0 || e == 0 || s == 0 || setuid(0) == 0))
		return fail(why, why_size, "cannot drop privileges", EPERM);
	return 0;
}

/* What is mapped now: RLIMIT_AS is that plus the budget (a sanitizer's
 * shadow memory is counted, and must stay usable). */
static uint64_t mapped_bytes(void)
{
	unsigned long long pages = 0;
	FILE *f = fopen("/proc/self/statm", "re");
	if (f) {
		if (fscanf(f, "%llu", &pages) != 1)
			pages = 0;
		fclose(f);
	}
	return (uint64_t)pages * (uint64_t)sysconf(_SC_PAGESIZE);
}

static int set_limit(int resource, rlim_t soft, rlim_t hard)
{
	struct rlimit rl = { .rlim_cur = soft, .rlim_max = hard };
	return setrlimit(resource, &rl) < 0 ? -errno : 0;
}

static int set_limits(const struct model_confine *c)
{
	uint64_t as = mapped_bytes() + c->memory;
	int ret = set_limit(RLIMIT_CORE, 0, 0);
	if (ret == 0)
		ret = set_limit(RLIMIT_CPU, c->cpu_s, c->cpu_s + 1);
	if (ret == 0 && as > c->memory)
		ret = set_limit(RLIMIT_AS, as, as);
	return ret;
}

/* ---- the filter ---- */

#define MAX_FILTER 256
#define ARG_LO(i) (offsetof(struct seccomp_data, args[(i)]))

struct filter {
	struct sock_filter code[MAX_FILTER];
	unsigned len;
};

static void emit(struct filter *f, struct sock_filter insn)
{
	if (f->len < MAX_FILTER)
		f->code[f->len] = insn;
	f->len++;
}

#define STMT(code, k) ((struct sock_filter)BPF_STMT((code), (k)))
#define JUMP(code, k, t, f) ((struct sock_filter)BPF_JUMP((code), (k), (t), (f)))
#define LOAD(off) STMT(BPF_LD | BPF_W | BPF_ABS, (off))
#define RET(v) STMT(BPF_RET | BPF_K, (v))
#define JEQ(k, t, f) JUMP(BPF_JMP | BPF_JEQ | BPF_K, (k), (t), (f))
#define JSET(k, t, f) JUMP(BPF_JMP | BPF_JSET | BPF_K, (k), (t), (f))
#define DENY (SECCOMP_RET_ERRNO | (EPERM & SECCOMP_RET_DATA))

static void allow(struct filter *f, long nr)
{
	emit(f, LOAD(offsetof(struct seccomp_data, nr)));
	emit(f, JEQ((uint32_t)nr, 0, 1));
	emit(f, RET(SECCOMP_RET_ALLOW));
}

/* nr only when its argument arg (low 32 bits) is a or b. */
static void allow_arg(struct filter *f, long nr, unsigned arg, uint32_t a, uint32_t b)
{
	emit(f, LOAD(offsetof(struct seccomp_data, nr)));
	emit(f, JEQ((uint32_t)nr, 0, 5));
	emit(f, LOAD(ARG_LO(arg)));
	emit(f, JEQ(a, 2, 0));
	emit(f, JEQ(b, 1, 0));
	emit(f, RET(DENY));
	emit(f, RET(SECCOMP_RET_ALLOW));
}

/* nr only when its argument arg (low 32 bits) lies in lo..hi. */
static void allow_range(struct filter *f, long nr, unsigned arg, uint32_t lo, uint32_t hi)
{
	emit(f, LOAD(offsetof(struct seccomp_data, nr)));
	emit(f, JEQ((uint32_t)nr, 0, 5));
	emit(f, LOAD(ARG_LO(arg)));
	emit(f, JUMP(BPF_JMP | BPF_JGE | BPF_K, lo, 0, 2));
	emit(f, JUMP(BPF_JMP | BPF_JGT | BPF_K, hi, 1, 0));
	emit(f, RET(SECCOMP_RET_ALLOW));
	emit(f, RET(DENY));
}

/* nr only when none of the bits of mask is set in argument arg. */
static void allow_without(struct filter *f, long nr, unsigned arg, uint32_t mask)
{
	emit(f, LOAD(offsetof(struct seccomp_data, nr)));
	emit(f, JEQ((uint32_t)nr, 0, 4));
	emit(f, LOAD(ARG_LO(arg)));
	emit(f, JSET(mask, 0, 1));
	emit(f, RET(DENY));
	emit(f, RET(SECCOMP_RET_ALLOW));
}

static void allow_memory(struct filter *f)
{
	allow(f, SYS_brk);
	allow(f, SYS_munmap);
	allow(f, SYS_mremap);
	allow(f, SYS_madvise);
	allow_without(f, SYS_mmap, 2, PROT_EXEC);
#ifdef SYS_mmap2
	allow_without(f, SYS_mmap2, 2, PROT_EXEC);
#endif
	allow_without(f, SYS_mprotect, 2, PROT_EXEC);
}

/* Reading the inputs (fds first_in to last_in), writing the result pipe
 * and stderr. */
static void allow_io(struct filter *f, uint32_t first_in, uint32_t last_in, uint32_t out)
{
	allow_range(f, SYS_read, 0, first_in, last_in);
	allow_range(f, SYS_pread64, 0, first_in, last_in);
	allow_range(f, SYS_readv, 0, first_in, last_in);
	allow_range(f, SYS_lseek, 0, first_in, last_in);
#ifdef SYS__llseek
	allow_range(f, SYS__llseek, 0, first_in, last_in);
#endif
#ifdef SYS_fstat
	allow_range(f, SYS_fstat, 0, first_in, last_in);
#endif
	allow_arg(f, SYS_write, 0, out, STDERR_FILENO);
	allow_arg(f, SYS_writev, 0, out, STDERR_FILENO);
	allow(f, SYS_close);
}

static void allow_process(struct filter *f, uint32_t self)
{
	static const long calls[] = {
		SYS_exit,
		SYS_exit_group,
		SYS_rt_sigreturn,
		SYS_rt_sigprocmask,
		SYS_rt_sigaction,
		SYS_sigaltstack,
		SYS_futex,
		SYS_getpid,
		SYS_gettid,
		SYS_sched_yield,
		SYS_restart_syscall,
		SYS_clock_gettime,
		SYS_gettimeofday,
		SYS_getrandom,
		SYS_getuid,
		SYS_geteuid,
		SYS_getgid,
		SYS_getegid,
		SYS_getgroups,
#ifdef SYS_clock_gettime64
		SYS_clock_gettime64,
#endif
	};
	for (size_t i = 0; i < sizeof(calls) / sizeof(calls[0]); i++)
		allow(f, calls[i]);
	/* abort() and raise(): to itself only */
	allow_arg(f, SYS_kill, 0, self, self);
	allow_arg(f, SYS_tgkill, 0, self, self);
	allow_arg(f, SYS_tkill, 0, self, self);
}

static int install_filter(int first_in, int last_in, int out, char *why, size_t why_size)
{
#ifndef FILTER_ARCH
	return fail(why, why_size, "no seccomp filter for this architecture", ENOSYS);
#else
	struct filter f = { .len = 0 };
	emit(&f, LOAD(offsetof(struct seccomp_data, arch)));
	emit(&f, JEQ(FILTER_ARCH, 1, 0));
	emit(&f, RET(SECCOMP_RET_KILL_PROCESS));
#ifdef __x86_64__
	/* x32 calls: the same numbers with a high bit */
	emit(&f, LOAD(offsetof(struct seccomp_data, nr)));
	emit(&f, JUMP(BPF_JMP | BPF_JGE | BPF_K, __X32_SYSCALL_BIT, 0, 1));
	emit(&f, RET(DENY));
#endif
	allow_memory(&f);
	allow_io(&f, (uint32_t)first_in, (uint32_t)last_in, (uint32_t)out);
	allow_process(&f, (uint32_t)getpid());
	emit(&f, RET(DENY));
	if (f.len > MAX_FILTER)
		return fail(why, why_size, "seccomp filter too long", E2BIG);
	struct sock_fprog prog = { .len = (unsigned short)f.len, .filter = f.code };
	if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog) < 0)
		return fail(why, why_size, "cannot install the seccomp filter", errno);
	return 0;
#endif
}

int model_confine_child_fds(const struct model_confine *c, int *in_fds, unsigned count, int *out_fd, char *why,
			    size_t why_size)
{
	default_signals();
	if (count < 1 || count > MODEL_CONFINE_MAX_INPUTS)
		return fail(why, why_size, "cannot set up the loader's fds", EINVAL);
	int ret = keep_fds(in_fds, count, out_fd);
	if (ret < 0)
		return fail(why, why_size, "cannot set up the loader's fds", -ret);
	ret = drop_user(c, why, why_size);
	if (ret < 0)
		return ret;
	ret = set_limits(c);
	if (ret < 0)
		return fail(why, why_size, "cannot set resource limits", -ret);
	if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) < 0 || prctl(PR_SET_DUMPABLE, 0, 0, 0, 0) < 0 ||
	    prctl(PR_SET_PDEATHSIG, SIGKILL, 0, 0, 0) < 0)
		return fail(why, why_size, "prctl", errno);
	if (getppid() != c->parent)
		return fail(why, why_size, "the parent is gone", ESRCH);
	return install_filter(in_fds[0], in_fds[count - 1], *out_fd, why, why_size);
}

int model_confine_child(const struct model_confine *c, int *in_fd, int *out_fd, char *why, size_t why_size)
{
	return model_confine_child_fds(c, in_fd, 1, out_fd, why, why_size);
}
