/* struct_size.h: the range of struct_size the public structs that grow accept (cbvh.h). */
#ifndef CBVH_COMMON_STRUCT_SIZE_H
#define CBVH_COMMON_STRUCT_SIZE_H

#include <stddef.h>

/* The offset just past `field` of `type`: a struct_size of at least this covers the field. */
#define CBVH_FIELD_END(type, field) (offsetof(type, field) + sizeof(((type *)0)->field))

/* The smallest struct_size accepted reaches past `first_field`, the one after struct_size: this catches 0,
 * a sizeof taken of a pointer and other small garbage. */
#define CBVH_STRUCT_SIZE_MIN(type, first_field) CBVH_FIELD_END(type, first_field)

/* The largest is the library's own struct: fields past it, from a newer cbvh.h, it could neither honor
 * nor fill. */
static inline int cbvh_struct_size_ok(size_t size, size_t smallest, size_t largest)
{
    return size >= smallest && size <= largest;
}

/* What every *_init function does first: records size in the struct's first field (when s is not NULL and
 * the field fits), and says whether the size is in range. */
static inline int cbvh_struct_size_record(void *s, size_t size, size_t smallest, size_t largest)
{
    if (!s || size < sizeof(size_t))
        return 0;
    *(size_t *)s = size;
    return cbvh_struct_size_ok(size, smallest, largest);
}

#endif
