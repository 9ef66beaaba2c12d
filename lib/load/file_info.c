/* file_info.c: what an opened file says about itself: info, sections, triangles and materials by id. */
#include <string.h>

#include "common/endian.h"
#include "common/struct_size.h"
#include "layout/triangle_encodings.h"
#include "load/load.h"

cbvh_result cbvh_file_get_info(const cbvh_file *file, cbvh_file_info *info, size_t struct_size)
{
    const size_t smallest = CBVH_STRUCT_SIZE_MIN(cbvh_file_info, format_version);
    if (!info || !cbvh_struct_size_ok(struct_size, smallest, sizeof *info))
        return CBVH_ERROR_INVALID_ARGUMENT;
    cbvh_file_info whole;
    if (file)
        whole = file->info;
    else
        memset(&whole, 0, sizeof whole);
    whole.struct_size = struct_size;
    memcpy(info, &whole, struct_size);
    return file ? CBVH_OK : CBVH_ERROR_INVALID_ARGUMENT;
}

int cbvh_file_get_section(const cbvh_file *file, uint32_t index, cbvh_section_info *section)
{
    if (!file || !section || index >= file->info.section_count)
        return 0;
    *section = file->sections[index];
    return 1;
}

/* Original id -> cooked index through the unmap table: a lookup when dense, else a binary search of the
 * cooked ids sorted by original id. Returns 0 for an id the cooker dropped (a degenerate triangle) or one
 * out of range. */
static int cooked_index(const struct cbvh_file *f, uint32_t tri, uint32_t *cooked)
{
    if (tri >= f->original_triangle_count)
        return 0;
    if (!f->remap) {
        *cooked = tri;
        return 1;
    }
    if (!f->unmap_sorted) {
        *cooked = f->unmap[tri];
        return *cooked != CBVH_NO_HIT;
    }
    uint32_t lo = 0, hi = f->info.triangle_count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        uint32_t id = cbvh_original_id(f, f->unmap[mid]);
        if (id == tri) {
            *cooked = f->unmap[mid];
            return 1;
        }
        if (id < tri)
            lo = mid + 1;
        else
            hi = mid;
    }
    return 0;
}

int cbvh_file_get_triangle(const cbvh_file *file, uint32_t tri, float v0[3], float v1[3], float v2[3])
{
    uint32_t cooked;
    if (!file || !cooked_index(file, tri, &cooked))
        return 0;
    cbvh_triangle_vertices(file, cooked, v0, v1, v2);
    return 1;
}

uint32_t cbvh_file_get_material(const cbvh_file *file, uint32_t tri)
{
    uint32_t cooked;
    if (!file || !file->materials || !cooked_index(file, tri, &cooked))
        return 0;
    return cbvh_cooked_material(file, cooked);
}

/* Entry `index` of the MATERIAL_NAMES table (validated at open: in range, names NUL-terminated). */
static const char *name_entry(const struct cbvh_file *f, uint32_t index, uint32_t *id)
{
    const uint8_t *e = f->material_names + 4 + 8 * (size_t)index;
    *id = cbvh_read_u32(e);
    return (const char *)f->material_names + 4 + 8 * (size_t)f->info.material_name_count +
           cbvh_read_u32(e + 4);
}

const char *cbvh_file_get_material_name(const cbvh_file *file, uint32_t index, uint32_t *id)
{
    uint32_t unused;
    if (!file || index >= file->info.material_name_count)
        return NULL;
    return name_entry(file, index, id ? id : &unused);
}

const char *cbvh_file_find_material_name(const cbvh_file *file, uint32_t id)
{
    if (!file)
        return NULL;
    uint32_t lo = 0, hi = file->info.material_name_count, entry_id;
    while (lo < hi) { /* the first entry whose id is >= id */
        uint32_t mid = lo + (hi - lo) / 2;
        name_entry(file, mid, &entry_id);
        if (entry_id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == file->info.material_name_count)
        return NULL;
    const char *name = name_entry(file, lo, &entry_id);
    return entry_id == id ? name : NULL;
}
