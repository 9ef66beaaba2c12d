/* alloc.h: allocation through the caller's hooks, with the C library as default. */
#ifndef CBVH_COMMON_ALLOC_H
#define CBVH_COMMON_ALLOC_H

#include <stddef.h>
#include "cbvh.h"

/* Resolves NULL to the default allocator (posix_memalign or _aligned_malloc, in common/os.h). */
cbvh_allocator cbvh_allocator_resolve(const cbvh_allocator *allocator);

/* Allocates `size` bytes aligned to `align` (power of two <= 64); NULL on failure
 * or when size is 0. */
void *cbvh_alloc(const cbvh_allocator *a, size_t size, size_t align);
void cbvh_free(const cbvh_allocator *a, void *ptr);

/* count * elem bytes, or NULL when the product overflows or the allocation fails. */
void *cbvh_alloc_array(const cbvh_allocator *a, size_t count, size_t elem, size_t align);

#endif
