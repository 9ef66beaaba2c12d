/* alloc.c: allocation through the caller's hooks, with the C library as default. */
#include <stdint.h>

#include "common/alloc.h"
#include "common/os.h"

static void *default_alloc(void *user, size_t size, size_t align)
{
    (void)user;
    return cbvh_os_aligned_alloc(size, align);
}

static void default_free(void *user, void *ptr)
{
    (void)user;
    cbvh_os_aligned_free(ptr);
}

cbvh_allocator cbvh_allocator_resolve(const cbvh_allocator *allocator)
{
    if (allocator && allocator->alloc && allocator->free)
        return *allocator;
    cbvh_allocator d = { default_alloc, default_free, NULL };
    return d;
}

void *cbvh_alloc(const cbvh_allocator *a, size_t size, size_t align)
{
    if (size == 0)
        return NULL;
    return a->alloc(a->user, size, align);
}

void cbvh_free(const cbvh_allocator *a, void *ptr)
{
    if (ptr)
        a->free(a->user, ptr);
}

void *cbvh_alloc_array(const cbvh_allocator *a, size_t count, size_t elem, size_t align)
{
    if (elem != 0 && count > SIZE_MAX / elem)
        return NULL;
    return cbvh_alloc(a, count * elem, align);
}
