/* os.h: the operating-system calls cbvh makes above the allocator (files, threads, clock), implemented once
 * for POSIX (posix.c) and once for Windows (win32.c); the memory calls below it are in os_memory.h. */
#ifndef CBVH_COMMON_OS_H
#define CBVH_COMMON_OS_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

#ifdef _WIN32
typedef void *cbvh_os_thread_id; /* a HANDLE */
#else
#include <pthread.h>
typedef pthread_t cbvh_os_thread_id;
#endif

/* The whole content of a regular file. */
struct cbvh_os_file_bytes {
    const uint8_t *bytes; /* NULL when size is 0 */
    size_t size;
    int mapped; /* 1: a read-only mapping, released by cbvh_os_unmap; 0: a 64-byte aligned buffer from the
                 * allocator, which the caller frees */
};

/* Opens `path` (UTF-8 on Windows) and maps it read-only when `map` is set (falling back to reading when
 * the system cannot map it), or reads it into memory from `a`. Errors name the path and the cause. */
cbvh_result cbvh_os_read_file(const char *path, int map, const cbvh_allocator *a,
                              struct cbvh_os_file_bytes *out, cbvh_error *err);
void cbvh_os_unmap(const uint8_t *bytes, size_t size);

/* Writes `size` bytes to `path` through a temporary file beside it, flushed to disk, then renamed over
 * `path`: readers see the old file or the new one, never a partial one. */
cbvh_result cbvh_os_write_file_replacing(const char *path, const uint8_t *data, size_t size,
                                         const cbvh_allocator *a, cbvh_error *err);

/* A second thread running fn(arg); the struct must live until cbvh_os_thread_join. */
struct cbvh_os_thread {
    void (*fn)(void *arg);
    void *arg;
    cbvh_os_thread_id id;
};
/* 0 on success, -1 when no thread could be started. */
int cbvh_os_thread_start(struct cbvh_os_thread *t, void (*fn)(void *arg), void *arg);
void cbvh_os_thread_join(struct cbvh_os_thread *t);

/* Seconds on a monotonic clock, for timing phases. */
double cbvh_os_seconds(void);

#endif
