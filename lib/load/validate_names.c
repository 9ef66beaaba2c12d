/* validate_names.c: checks the MATERIAL_NAMES section (format spec section 4, "MATERIAL_NAMES"). */
#include <string.h>

#include "common/endian.h"
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

cbvh_result cbvh_material_names_check(const struct cbvh_file *f, const cbvh_section_info *s, uint32_t *count,
                                      cbvh_error *err)
{
    const uint8_t *b = f->material_names;
    const uint64_t size = s->size; /* 4 .. CBVH_MAX_MATERIAL_NAME_BYTES (validate_table.c) */
    const uint32_t n = cbvh_read_u32(b);
    const uint64_t names_start = 4 + 8 * (uint64_t)n;
    if (n == 0 || names_start >= size)
        return CORRUPT("MATERIAL_NAMES: %u names do not fit its %llu bytes (each needs 9 at least)", n,
                       (unsigned long long)size);
    uint64_t at = names_start;
    for (uint32_t i = 0; i < n; i++) {
        const uint8_t *e = b + 4 + 8 * (size_t)i;
        const uint32_t id = cbvh_read_u32(e), offset = cbvh_read_u32(e + 4);
        if (names_start + offset != at)
            return CORRUPT(
                "MATERIAL_NAMES: name %u starts at offset %u, expected %llu (names follow each other)", i,
                offset, (unsigned long long)(at - names_start));
        if (at >= size)
            return CORRUPT("MATERIAL_NAMES: name %u starts past the end of the section", i);
        const uint8_t *nul = memchr(b + at, 0, (size_t)(size - at));
        if (!nul)
            return CORRUPT("MATERIAL_NAMES: name %u has no terminating NUL before the end of the section", i);
        if (i > 0) {
            const uint32_t prev_id = cbvh_read_u32(e - 8);
            const char *prev = (const char *)b + names_start + cbvh_read_u32(e - 4);
            if (id < prev_id || (id == prev_id && strcmp(prev, (const char *)b + at) >= 0))
                return CORRUPT(
                    "MATERIAL_NAMES: name %u (id %u) is not after name %u (id %u) in (id, name) order", i, id,
                    i - 1, prev_id);
        }
        at = (uint64_t)(nul - b) + 1;
    }
    if (at != size)
        return CORRUPT("MATERIAL_NAMES: %llu bytes after the last name", (unsigned long long)(size - at));
    *count = n;
    return CBVH_OK;
}
