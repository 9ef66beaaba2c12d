/* leaf_expand.c: cbvh_file_expand_triangles: the cooked triangles copied four by four as the ray test reads
 * them. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "common/alloc.h"
#include "common/error.h"
#include "load/load.h"
#include "query/leaf.h"

cbvh_result cbvh_file_expand_triangles(cbvh_file *file, cbvh_error *err)
{
    if (!file)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "cbvh_file_expand_triangles: file is NULL");
    cbvh_error_clear(err);
#ifdef CBVH_HAVE_SIMD
    struct cbvh_file *f = file;
    const uint32_t n = f->info.triangle_count;
    if (f->quads || n == 0)
        return CBVH_OK;
    const size_t groups = ((size_t)n + 3u) / 4u;
    struct leaf_quad *q =
        groups <= SIZE_MAX / sizeof *q ? cbvh_alloc_walked(&f->allocator, groups * sizeof *q, 64) : NULL;
    if (!q)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY,
                         "cannot allocate %llu bytes for the expanded triangles",
                         (unsigned long long)(groups * sizeof *q));
    /* the gather of the ray test itself, so the floats are the ones it reads without the copy */
    for (uint32_t g = 0; g < groups; g++) {
        const uint32_t k = 4u * g, last = n - 1u - k;
        const uint32_t lane[4] = {0u, last < 1u ? last : 1u, last < 2u ? last : 2u, last < 3u ? last : 3u};
        leaf_gather4(f->triangles, (int)f->triangle_encoding, f->vertices, (int)f->vertex_encoding,
                     f->grid_origin, f->grid_scale, k, lane, &q[g]);
    }
    cbvh_file_own(f, q);
    f->quads = q;
    f->info.expanded_bytes = groups * sizeof *q;
#endif
    return CBVH_OK;
}
