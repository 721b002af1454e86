/* Making memory present before it is filled. */
#ifndef SPINDLE_PREFAULT_H
#define SPINDLE_PREFAULT_H

#include <stddef.h>

/* Makes the pages wholly inside [p, p + len) present and writable in one
 * call (MADV_POPULATE_WRITE, Linux 5.14) rather than by a fault a page,
 * for memory about to be filled whole: a fault costs a trap each, and
 * under some hypervisors (a guest whose page tables the host shadows)
 * about 10 us. It takes the pages the writes would take. Where the
 * call fails (a kernel without it, a system call filter, no memory),
 * the writes fault the pages in as before. Ranges under 64 KiB are left
 * to the faults. */
void prefault_write(void *p, size_t len);

#endif
