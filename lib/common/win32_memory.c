/* win32_memory.c: the memory calls of os_memory.h on Windows (_aligned_malloc), below the allocator. */
#include <malloc.h>

#include "common/os_memory.h"

void *cbvh_os_aligned_alloc(size_t size, size_t align)
{
    return _aligned_malloc(size, align < sizeof(void *) ? sizeof(void *) : align);
}

void cbvh_os_aligned_free(void *ptr)
{
    _aligned_free(ptr);
}

/* Windows backs memory with large pages only when it is allocated so (VirtualAlloc with MEM_LARGE_PAGES,
 * which needs a privilege a game rarely has): no advice to give. */
void cbvh_os_advise_large_pages(void *p, size_t size)
{
    (void)p;
    (void)size;
}
