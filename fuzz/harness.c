#include "harness.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

/* ---- the input ---- */

static uint64_t take_le(struct fuzz_input *in, unsigned n)
{
	uint64_t v = 0;
	for (unsigned i = 0; i < n && in->pos < in->size; i++)
		v |= (uint64_t)in->data[in->pos++] << (8 * i);
	return v;
}

uint8_t fuzz_u8(struct fuzz_input *in)
{
	return (uint8_t)take_le(in, 1);
}

uint16_t fuzz_u16(struct fuzz_input *in)
{
	return (uint16_t)take_le(in, 2);
}

uint32_t fuzz_u32(struct fuzz_input *in)
{
	return (uint32_t)take_le(in, 4);
}

uint64_t fuzz_u64(struct fuzz_input *in)
{
	return take_le(in, 8);
}

uint32_t fuzz_num(struct fuzz_input *in)
{
	uint8_t b = fuzz_u8(in);
	return b < 0x80 ? b : b == 0xff ? UINT32_MAX : fuzz_u32(in);
}

uint64_t fuzz_num64(struct fuzz_input *in)
{
	uint8_t b = fuzz_u8(in);
	return b < 0x80 ? b : b == 0xff ? UINT64_MAX : fuzz_u64(in);
}

const uint8_t *fuzz_bytes(struct fuzz_input *in, size_t max, size_t *n)
{
	size_t left = in->size - in->pos;
	*n = left < max ? left : max;
	const uint8_t *p = in->data + in->pos;
	in->pos += *n;
	return p;
}

/* ---- file descriptors ---- */

int fuzz_memfd(enum fuzz_fd_kind kind, uint64_t size, const void *data, size_t len)
{
	int fd = memfd_create("spindle-fuzz", MFD_CLOEXEC | MFD_ALLOW_SEALING);
	if (fd < 0)
		return -errno;
	if (len > size)
		len = (size_t)size;
	if (ftruncate(fd, (off_t)size) < 0 || (len && pwrite(fd, data, len, 0) != (ssize_t)len))
		goto fail;
	int seals = kind == FUZZ_FD_MEMFD_SEALED      ? F_SEAL_SHRINK
		    : kind == FUZZ_FD_MEMFD_ALL_SEALS ? F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_WRITE | F_SEAL_SEAL
						      : 0;
	if (seals && fcntl(fd, F_ADD_SEALS, seals) < 0)
		goto fail;
	return fd;
fail:;
	int e = errno;
	close(fd);
	return -e;
}

int fuzz_fd(unsigned kind, uint64_t size)
{
	int fds[2];
	switch ((enum fuzz_fd_kind)(kind % FUZZ_FD_KINDS)) {
	case FUZZ_FD_MEMFD_SEALED:
	case FUZZ_FD_MEMFD_ALL_SEALS:
	case FUZZ_FD_MEMFD_UNSEALED:
		return fuzz_memfd((enum fuzz_fd_kind)(kind % FUZZ_FD_KINDS), size, NULL, 0);
	case FUZZ_FD_PIPE:
		if (pipe2(fds, O_CLOEXEC) < 0)
			return -errno;
		close(fds[1]);
		return fds[0];
	case FUZZ_FD_SOCKET:
		if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) < 0)
			return -errno;
		close(fds[1]);
		return fds[0];
	case FUZZ_FD_DEV_NULL:
	case FUZZ_FD_KINDS:
		break;
	}
	int fd = open("/dev/null", O_RDWR | O_CLOEXEC);
	return fd < 0 ? -errno : fd;
}

/* In sanitizer builds: symbolizes a frame (what a report or a suppression
 * does), declared weak so that plain builds link without it. */
void __sanitizer_symbolize_pc(void *pc, const char *fmt, char *out, size_t size) __attribute__((weak));

/* Entries of a /proc directory, but . and .. */
static int count_entries(const char *path)
{
	DIR *d = opendir(path);
	if (!d)
		return -1;
	int n = 0;
	struct dirent *e;
	while ((e = readdir(d)))
		n += e->d_name[0] != '.';
	closedir(d);
	return n;
}

void fuzz_resources_take(struct fuzz_resources *r)
{
	/* The sanitizers start their symbolizer, with two pipes, the first
	 * time they symbolize (a suppressed report): start it now, or the
	 * first such report would look like a leak. */
	static bool symbolizer_started;
	if (!symbolizer_started && __sanitizer_symbolize_pc) {
		char buf[64];
		__sanitizer_symbolize_pc(__builtin_return_address(0), "%p %F", buf, sizeof(buf));
	}
	symbolizer_started = true;
	r->fds = count_entries("/proc/self/fd") - 1; /* the directory's own */
	r->threads = count_entries("/proc/self/task");
}

void fuzz_resources_check(const struct fuzz_resources *before)
{
	struct fuzz_resources after;
	fuzz_resources_take(&after);
	/* A joined thread may still be listed for a moment: pthread_join()
	 * returns when the thread's tid is cleared, before the kernel has
	 * removed it from the process. Wait up to 100 ms for that. */
	for (int i = 0; i < 100 && after.threads > before->threads; i++) {
		usleep(1000);
		fuzz_resources_take(&after);
	}
	if (after.fds != before->fds)
		fuzz_fail("%d fds open before the input, %d after", before->fds, after.fds);
	if (after.threads != before->threads)
		fuzz_fail("%d threads before the input, %d after", before->threads, after.threads);
}

bool fuzz_verbose(void)
{
	static int verbose = -1;
	if (verbose < 0)
		verbose = getenv("SPINDLE_FUZZ_VERBOSE") != NULL;
	return verbose;
}

void fuzz_fail(const char *fmt, ...)
{
	va_list ap;
	va_start(ap, fmt);
	fprintf(stderr, "fuzz: ");
	vfprintf(stderr, fmt, ap);
	fprintf(stderr, "\n");
	va_end(ap);
	abort();
}

int fuzz_send(int sock, const void *data, size_t len, const int *fds, unsigned n_fds, void (*pump)(void *), void *arg)
{
	const uint8_t *p = data;
	unsigned stuck = 0;
	while (len > 0 || n_fds > 0) {
		union {
			char buf[CMSG_SPACE(sizeof(int) * 64)];
			struct cmsghdr align;
		} control;
		struct iovec iov = { (void *)p, len };
		struct msghdr mh = { .msg_iov = &iov, .msg_iovlen = 1 };
		if (n_fds) {
			if (n_fds > 64)
				n_fds = 64;
			mh.msg_control = control.buf;
			mh.msg_controllen = CMSG_SPACE(sizeof(int) * n_fds);
			struct cmsghdr *c = CMSG_FIRSTHDR(&mh);
			c->cmsg_level = SOL_SOCKET;
			c->cmsg_type = SCM_RIGHTS;
			c->cmsg_len = CMSG_LEN(sizeof(int) * n_fds);
			memcpy(CMSG_DATA(c), fds, sizeof(int) * n_fds);
		}
		ssize_t n = sendmsg(sock, &mh, MSG_DONTWAIT | MSG_NOSIGNAL);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0 && errno != EAGAIN)
			return -errno;
		if (n < 0) {
			if (++stuck > 1000)
				return -EAGAIN;
			pump(arg);
			continue;
		}
		stuck = 0;
		p += n;
		len -= (size_t)n;
		n_fds = 0;
	}
	return 0;
}

bool fuzz_drain(int sock)
{
	char buf[4096];
	for (;;) {
		union {
			char buf[CMSG_SPACE(sizeof(int) * 32)];
			struct cmsghdr align;
		} control;
		struct iovec iov = { buf, sizeof(buf) };
		struct msghdr mh = { .msg_iov = &iov,
				     .msg_iovlen = 1,
				     .msg_control = control.buf,
				     .msg_controllen = sizeof(control.buf) };
		ssize_t n = recvmsg(sock, &mh, MSG_DONTWAIT | MSG_CMSG_CLOEXEC);
		if (n < 0 && errno == EINTR)
			continue;
		if (n < 0)
			return errno == EAGAIN;
		for (struct cmsghdr *c = CMSG_FIRSTHDR(&mh); c; c = CMSG_NXTHDR(&mh, c)) {
			if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_RIGHTS)
				continue;
			size_t k = (c->cmsg_len - CMSG_LEN(0)) / sizeof(int);
			for (size_t i = 0; i < k; i++) {
				int fd;
				memcpy(&fd, CMSG_DATA(c) + i * sizeof(int), sizeof(int));
				close(fd);
			}
		}
		if (n == 0)
			return false;
	}
}
