/* posix_memory.c: the memory calls of os_memory.h on POSIX systems (posix_memalign, madvise), below the
 * allocator. */
#define _GNU_SOURCE /* MADV_HUGEPAGE where the system has it (Linux) */
#include <stdint.h>
#include <stdlib.h>
#include <sys/mman.h>

#include "common/os_memory.h"

void *cbvh_os_aligned_alloc(size_t size, size_t align)
{
    if (align < sizeof(void *))
        align = sizeof(void *);
    void *p = NULL;
    if (posix_memalign(&p, align, size) != 0)
        return NULL;
    return p;
}

void cbvh_os_aligned_free(void *ptr)
{
    free(ptr);
}

void cbvh_os_advise_large_pages(void *p, size_t size)
{
#ifdef MADV_HUGEPAGE
    const uintptr_t page = (uintptr_t)2 << 20;
    const uintptr_t begin = ((uintptr_t)p + page - 1u) & ~(page - 1u),
                    end = ((uintptr_t)p + size) & ~(page - 1u);
    if (begin < end)
        (void)madvise((void *)begin, end - begin, MADV_HUGEPAGE); /* advice: a refusal changes nothing */
#else
    (void)p;
    (void)size;
#endif
}
