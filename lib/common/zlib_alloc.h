/* zlib_alloc.h: zlib's memory hooks routed through a cbvh allocator, for deflating and inflating alike. */
#ifndef CBVH_COMMON_ZLIB_ALLOC_H
#define CBVH_COMMON_ZLIB_ALLOC_H

#include <zlib.h>

#include "cbvh.h"

/* Makes `zs` allocate through `a` (resolved, never NULL), which must outlive the stream.
 * Call before deflateInit or inflateInit. */
void cbvh_zlib_use_allocator(z_stream *zs, const cbvh_allocator *a);

#endif
