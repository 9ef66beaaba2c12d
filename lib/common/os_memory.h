/* os_memory.h: the system's aligned memory and large-page advice, which the default allocator (alloc.c)
 * takes, implemented once for POSIX (posix_memory.c) and once for Windows (win32_memory.c). */
#ifndef CBVH_COMMON_OS_MEMORY_H
#define CBVH_COMMON_OS_MEMORY_H

#include <stddef.h>

/* `size` bytes aligned to `align` (a power of two), or NULL; freed by cbvh_os_aligned_free. */
void *cbvh_os_aligned_alloc(size_t size, size_t align);
void cbvh_os_aligned_free(void *ptr);

/* Advises the system to back the whole 2 MiB pages within [p, p + size) with 2 MiB pages (Linux's
 * transparent huge pages, madvise MADV_HUGEPAGE; no effect where the system has no such advice or the
 * pages are already there). For memory not yet written, from the default allocator only. */
void cbvh_os_advise_large_pages(void *p, size_t size);

#endif
