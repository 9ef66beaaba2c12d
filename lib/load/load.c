/* load.c: the loading pipeline: header, table, section placement (in place, copied or inflated), section
 * checks. */
#include <assert.h>
#include <float.h>
#include <math.h>
#include <string.h>

#include "common/alloc.h"
#include "common/endian.h"
#include "common/error.h"
#include "layout/tree.h"
#include "layout/triangle_encodings.h"
#include "load/load.h"

/* Where a known section's decoded bytes are: in place when raw and cbvh_in_place (the offset of a
 * section is past the header: CBVH_SECTION_LEAD bytes before it are the file's), else in an owned
 * 64-byte aligned copy or inflated buffer, CBVH_SECTION_LEAD zero bytes into its allocation. */
static cbvh_result place_section(struct cbvh_file *f, uint32_t index, const void **out, cbvh_error *err)
{
    const cbvh_section_info *s = &f->sections[index];
    const uint8_t *src = f->bytes + s->offset;
    uint8_t *owned = NULL;
    if (s->codec == CBVH_CODEC_ZLIB) {
        void *inflated;
        cbvh_result r = cbvh_inflate_section(&f->allocator, src, s->stored_size, s->size, CBVH_SECTION_LEAD,
                                             index, &inflated, err);
        if (r != CBVH_OK)
            return r;
        owned = inflated;
    } else if (cbvh_in_place(f)) {
        *out = src;
        return CBVH_OK;
    } else {
        owned = cbvh_alloc_walked(&f->allocator, CBVH_SECTION_LEAD + (size_t)s->size, 64);
        if (!owned)
            return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY,
                             "section %u: cannot allocate %llu bytes for an aligned copy", index,
                             (unsigned long long)s->size);
        memcpy(owned + CBVH_SECTION_LEAD, src, (size_t)s->size);
    }
    memset(owned, 0, CBVH_SECTION_LEAD);
    cbvh_file_own(f, owned);
    *out = owned + CBVH_SECTION_LEAD;
    return CBVH_OK;
}

static cbvh_result place_sections(struct cbvh_file *f, const cbvh_section_map *map, cbvh_error *err)
{
    const void *where[CBVH_KNOWN_SECTIONS] = {NULL};
    for (int t = 0; t < CBVH_KNOWN_SECTIONS; t++) {
        if (map->index[t] < 0)
            continue;
        cbvh_result r = place_section(f, (uint32_t)map->index[t], &where[t], err);
        if (r != CBVH_OK)
            return r;
    }
    f->nodes = where[CBVH_SECTION_NODES - 1];
    f->layout = f->sections[map->index[cbvh_section_slot(CBVH_SECTION_NODES)]].encoding == CBVH_NODES_W4
                    ? CBVH_LAYOUT_WIDE4
                    : CBVH_LAYOUT_BINARY;
    f->info.layout = f->layout;
    f->triangles = where[CBVH_SECTION_TRIANGLES - 1];
    f->vertices = where[CBVH_SECTION_VERTICES - 1];
    f->remap = where[CBVH_SECTION_REMAP - 1];
    f->materials = where[CBVH_SECTION_MATERIALS - 1];
    f->material_names = where[cbvh_section_slot(CBVH_SECTION_MATERIAL_NAMES)];
    f->triangle_encoding = f->sections[map->index[CBVH_SECTION_TRIANGLES - 1]].encoding;
    f->vertex_encoding = f->sections[map->index[CBVH_SECTION_VERTICES - 1]].encoding;
    f->vertices_far =
        f->info.triangle_count > 0 &&
        (uint64_t)f->info.vertex_count * cbvh_element_size(CBVH_SECTION_VERTICES, f->vertex_encoding) >
            CBVH_CACHED_VERTEX_BYTES;
    float extent = 0.0f; /* the bounds were checked: min <= max */
    for (int a = 0; a < 3; a++) {
        const float e = f->info.bounds_max[a] - f->info.bounds_min[a];
        extent = e > extent ? e : extent;
    }
    f->bounds_extent = extent;
    /* past FLT_MAX / 64, the margin could take an origin beyond the overflow test's FLT_MAX / 4: no box */
    const int usable = extent <= FLT_MAX / 64.0f;
    const float margin = (float)CBVH_NEAR_ORIGIN_FACTOR * extent;
    for (int a = 0; a < 4; a++) {
        f->origin_near_lo[a] = a == 3 ? 0.0f : usable ? f->info.bounds_min[a] - margin : INFINITY;
        f->origin_near_hi[a] = a == 3 ? 0.0f : usable ? f->info.bounds_max[a] + margin : -INFINITY;
        f->bounds_lo[a] = a == 3 ? 0.0f : f->info.bounds_min[a];
        f->bounds_hi[a] = a == 3 ? 0.0f : f->info.bounds_max[a];
    }
    if (f->remap)
        f->remap_encoding = f->sections[map->index[CBVH_SECTION_REMAP - 1]].encoding;
    if (f->materials)
        f->material_encoding = f->sections[map->index[CBVH_SECTION_MATERIALS - 1]].encoding;
    f->info.has_remap = f->remap != NULL;
    f->info.original_triangle_count = f->original_triangle_count;
    f->info.has_materials = f->materials != NULL;
    f->info.vertex_format = f->vertex_encoding;
    f->info.index_encoding = f->triangle_encoding;
    return CBVH_OK;
}

/* The file's top box (common/file.h), from its validated tree. */
static void set_top_box(struct cbvh_file *f)
{
    uint32_t q[6];
    const int any = cbvh_tree_top_box(f, f->layout, q);
    for (int a = 0; a < 4; a++) {
        /* none: planes at +inf (lows) and -inf (highs), which every ray's slab test misses */
        f->top_lo[a] = a == 3 ? 0.0f
                       : any  ? cbvh_dequantize(q[a], f->grid_origin[a], f->grid_scale[a])
                              : INFINITY;
        f->top_hi[a] = a == 3 ? 0.0f
                       : any  ? cbvh_dequantize(q[3 + a], f->grid_origin[a], f->grid_scale[a])
                              : -INFINITY;
    }
}

/* The file's small_triangle_extent (common/file.h), from its validated triangles. */
static void set_small_triangle_extent(struct cbvh_file *f)
{
    float extent[CBVH_EXTENT_SAMPLES];
    const uint32_t n = f->info.triangle_count, samples = n < CBVH_EXTENT_SAMPLES ? n : CBVH_EXTENT_SAMPLES;
    for (uint32_t i = 0; i < samples; i++) {
        float v[3][3], e = 0.0f;
        cbvh_triangle_vertices(f, (uint32_t)((uint64_t)i * n / samples), v[0], v[1], v[2]);
        for (int a = 0; a < 3; a++) {
            const float lo = fminf(fminf(v[0][a], v[1][a]), v[2][a]),
                        hi = fmaxf(fmaxf(v[0][a], v[1][a]), v[2][a]);
            e = fmaxf(e, hi - lo);
        }
        uint32_t k = i; /* insertion sort: extent[0..i] ascending */
        for (; k > 0 && extent[k - 1] > e; k--)
            extent[k] = extent[k - 1];
        extent[k] = e;
    }
    f->small_triangle_extent = samples ? extent[samples / 4] : 0.0f;
}

cbvh_result cbvh_load(struct cbvh_file *f, cbvh_error *err)
{
    if (!cbvh_host_is_little_endian())
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED,
                         "this reader uses sections in place and runs on little-endian hosts only");
    cbvh_section_map map;
    cbvh_result r = cbvh_validate_header(f, err);
    if (r == CBVH_OK)
        r = cbvh_validate_table(f, &map, err);
    if (r == CBVH_OK)
        r = place_sections(f, &map, err);
    if (r == CBVH_OK)
        r = cbvh_check_sections(f, &map, err);
    if (r == CBVH_OK) {
        set_top_box(f);
        set_small_triangle_extent(f);
    }
    return r;
}
