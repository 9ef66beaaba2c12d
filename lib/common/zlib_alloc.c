/* zlib_alloc.c: zlib's memory hooks routed through a cbvh allocator, for deflating and inflating alike. */
#include <stdint.h>

#include "common/alloc.h"
#include "common/zlib_alloc.h"

static voidpf zlib_alloc(voidpf opaque, uInt items, uInt size)
{
    return cbvh_alloc_array((const cbvh_allocator *)opaque, items, size, 16);
}

static void zlib_free(voidpf opaque, voidpf address)
{
    cbvh_free((const cbvh_allocator *)opaque, address);
}

void cbvh_zlib_use_allocator(z_stream *zs, const cbvh_allocator *a)
{
    zs->zalloc = zlib_alloc;
    zs->zfree = zlib_free;
    zs->opaque = (voidpf)(uintptr_t)a;
}
