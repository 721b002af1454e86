#include "prefault.h"

#include <stdint.h>
#include <sys/mman.h>
#include <unistd.h>

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23 /* linux/mman.h, Linux 5.14 */
#endif

#define PREFAULT_MIN (64u << 10)

void prefault_write(void *p, size_t len)
{
	long page_size = sysconf(_SC_PAGESIZE); /* from the auxiliary vector: no system call */
	if (len < PREFAULT_MIN || page_size <= 0)
		return;
	uintptr_t page = (uintptr_t)page_size, start = ((uintptr_t)p + page - 1) & ~(page - 1),
		  end = ((uintptr_t)p + len) & ~(page - 1);
	if (end > start)
		(void)madvise((void *)start, end - start, MADV_POPULATE_WRITE);
}
