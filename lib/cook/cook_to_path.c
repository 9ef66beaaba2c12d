/* cook_to_path.c: cooking to a file atomically (the temporary file, flush and rename are in common/os.h). */
#include <string.h>

#include "common/alloc.h"
#include "common/error.h"
#include "common/os.h"
#include "common/struct_size.h"
#include "cook/cook_internal.h"

CBVH_API cbvh_result cbvh_cook_to_path(const cbvh_mesh *mesh, const cbvh_cook_options *options,
                                       const cbvh_allocator *allocator, const char *path,
                                       cbvh_cook_stats *stats, cbvh_error *err)
{
    if (!path || !*path)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "path is NULL or empty");
    void *data = NULL;
    size_t size = 0;
    cbvh_result r = cbvh_cook(mesh, options, allocator, &data, &size, stats, err);
    if (r == CBVH_OK) {
        double t0 = cbvh_os_seconds();
        cbvh_allocator a = cbvh_allocator_resolve(allocator);
        r = cbvh_os_write_file_replacing(path, data, size, &a, err);
        cbvh_free(&a, data);
        if (stats && stats->struct_size >= CBVH_FIELD_END(cbvh_cook_stats, seconds))
            stats->seconds[CBVH_PHASE_WRITE] += cbvh_os_seconds() - t0;
    }
    return r;
}
