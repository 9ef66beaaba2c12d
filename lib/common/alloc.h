/* alloc.h: allocation through the caller's hooks, with the C library as default. */
#ifndef CBVH_COMMON_ALLOC_H
#define CBVH_COMMON_ALLOC_H

#include <stddef.h>
#include "cbvh.h"

/* Resolves NULL to the default allocator (posix_memalign or _aligned_malloc, in common/os_memory.h). */
cbvh_allocator cbvh_allocator_resolve(const cbvh_allocator *allocator);

/* Allocates `size` bytes for the query kernels to walk at random (a file read into memory, its expanded
 * triangles), as cbvh_alloc; from the default allocator, a block of at least 2 MiB is advised to the
 * system's 2 MiB pages (cbvh_os_advise_large_pages) before it is written: on a large mesh, a walk's
 * scattered node and vertex loads miss the translation cache less. A caller's allocator is left alone. */
void *cbvh_alloc_walked(const cbvh_allocator *a, size_t size, size_t align);

/* Allocates `size` bytes aligned to `align` (power of two <= 64); NULL on failure
 * or when size is 0. */
void *cbvh_alloc(const cbvh_allocator *a, size_t size, size_t align);
void cbvh_free(const cbvh_allocator *a, void *ptr);

/* count * elem bytes, or NULL when the product overflows or the allocation fails. */
void *cbvh_alloc_array(const cbvh_allocator *a, size_t count, size_t elem, size_t align);

/* A meter between a caller and its allocator: it counts the bytes held through it and the most held
 * at once. Each block carries a 64-byte header (its size), so a block from the meter's allocator goes
 * back to it, never to `inner`. Not thread-safe: allocate from one thread at a time. */
typedef struct cbvh_meter {
    cbvh_allocator inner;
    size_t held, peak;
} cbvh_meter;

/* Hooks that allocate from m->inner and count in m. */
cbvh_allocator cbvh_meter_allocator(cbvh_meter *m);

/* Counts `size` bytes held elsewhere (add != 0) or given back (add == 0). */
void cbvh_meter_count(cbvh_meter *m, size_t size, int add);

#endif
