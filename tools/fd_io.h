/* fd_io.h: writing a whole buffer to a file descriptor, through signals and short writes. */
#ifndef CBVH_TOOLS_FD_IO_H
#define CBVH_TOOLS_FD_IO_H

#include <stddef.h>

/* Writes the `size` bytes at `data` to `fd`, retrying after a signal and after a short write. Returns 0, or
 * -1 with errno set (EIO when the descriptor took no byte without saying why). */
int fd_write_all(int fd, const void *data, size_t size);

#endif
