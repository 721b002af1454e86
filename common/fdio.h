/* Writing a whole buffer to a file descriptor. */
#ifndef SPINDLE_FDIO_H
#define SPINDLE_FDIO_H

#include <stddef.h>

/* Writes all len bytes of data to fd, again after EINTR and short writes,
 * at most 1 GiB a call. 0, or -errno (-EPIPE when write() gave 0). */
int fd_write_all(int fd, const void *data, size_t len);

#endif
