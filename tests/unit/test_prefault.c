/* prefault_write() (prefault.h): the pages wholly inside the range are
 * present afterwards (mincore()), the partial pages at its ends and the
 * pages outside it are not, what a page held is kept, ranges under 64 KiB
 * are left alone, and a shared memfd mapping (as the scan loader fills)
 * is made present too. Skipped (77) on a kernel without
 * MADV_POPULATE_WRITE. */
#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "check.h"
#include "prefault.h"

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23
#endif

static size_t page;

/* Whether each of the n pages at p is resident, into in[]. */
static void resident(void *p, size_t n, unsigned char *in)
{
	CHECK(mincore(p, n * page, in) == 0);
}

static void test_anonymous(void)
{
	size_t n = 1024; /* pages */
	unsigned char in[1024];
	uint8_t *p = mmap(NULL, n * page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
	CHECK(p != MAP_FAILED);
	memset(p + 5 * page, 0xAB, page); /* a page already written */
	resident(p, n, in);
	CHECK(!(in[0] & 1) && (in[5] & 1) && !(in[6] & 1));
	/* From 100 bytes into page 0 to 100 bytes into page 801. */
	prefault_write(p + 100, 801 * page);
	resident(p, n, in);
	CHECK(!(in[0] & 1));
	for (size_t i = 1; i < 801; i++)
		CHECK_MSG(in[i] & 1, "page %zu", i);
	for (size_t i = 801; i < n; i++)
		CHECK_MSG(!(in[i] & 1), "page %zu", i);
	for (size_t i = 0; i < page; i++)
		CHECK(p[5 * page + i] == 0xAB);
	CHECK(p[700 * page] == 0);
	/* Under 64 KiB: left to the faults. */
	prefault_write(p + 900 * page, 15 * page);
	resident(p, n, in);
	for (size_t i = 900; i < 915; i++)
		CHECK(!(in[i] & 1));
	/* Empty and tiny ranges are harmless. */
	prefault_write(p, 0);
	prefault_write(p + 1, 1);
	munmap(p, n * page);
}

static void test_memfd(void)
{
	size_t n = 256;
	unsigned char in[256];
	int fd = memfd_create("prefault-test", MFD_CLOEXEC);
	CHECK(fd >= 0 && ftruncate(fd, (off_t)(n * page)) == 0);
	uint8_t *p = mmap(NULL, n * page, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
	CHECK(p != MAP_FAILED);
	prefault_write(p, n * page);
	resident(p, n, in);
	for (size_t i = 0; i < n; i++)
		CHECK_MSG(in[i] & 1, "page %zu", i);
	munmap(p, n * page);
	close(fd);
}

int main(void)
{
	page = (size_t)sysconf(_SC_PAGESIZE);
	void *probe = mmap(NULL, page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
	CHECK(probe != MAP_FAILED);
	if (madvise(probe, page, MADV_POPULATE_WRITE) != 0) {
		printf("MADV_POPULATE_WRITE: %s: skipped\n", strerror(errno));
		return 77;
	}
	munmap(probe, page);
	test_anonymous();
	test_memfd();
	return check_done();
}
