/* check_sections.c: runs the element checks over every known section chunk by chunk, each chunk's pending CRC
 * first, so it is read from memory once. */
#include "common/error.h"
#include "layout/binary.h"
#include "layout/wide4.h"
#include "load/load.h"

/* Small enough to stay in L2 between the CRC and the checks. */
#define CHUNK_BYTES (64u * 1024u)

/* The section of `type` (its elements at `data`); `check` may be NULL (materials need none). When the CRC
 * is pending it is computed chunk by chunk ahead of the checks, and a section whose CRC does not match
 * reports that, whatever else the checks found. */
static cbvh_result check_section(const struct cbvh_file *f, const cbvh_section_map *map, uint32_t type,
                                 const void *data, cbvh_range_check check, void *state, cbvh_error *err)
{
    const int slot = cbvh_section_slot(type);
    if (slot < 0) /* callers pass known types only */
        return CBVH_OK;
    const uint32_t index = (uint32_t)map->index[slot];
    const int crc_pending = map->crc_pending[slot];
    const uint32_t size = cbvh_element_size(type, f->sections[index].encoding);
    const uint8_t *bytes = data;
    const uint32_t count = (uint32_t)(f->sections[index].size / size);
    const uint32_t step = crc_pending ? CHUNK_BYTES / size : count;
    uint32_t crc = 0, done = 0;
    cbvh_result r = CBVH_OK;
    for (uint32_t begin = 0; begin < count && r == CBVH_OK; begin = done) {
        done = count - begin < step ? count : begin + step;
        if (crc_pending)
            crc = cbvh_crc32(crc, bytes + (size_t)begin * size, (size_t)(done - begin) * size);
        if (check)
            r = check(f, state, begin, done, err);
    }
    if (crc_pending) {
        crc = cbvh_crc32(crc, bytes + (size_t)done * size, (size_t)(count - done) * size);
        if (crc != f->sections[index].crc32)
            return cbvh_crc_mismatch(f, index, crc, err);
    }
    return r;
}

cbvh_result cbvh_check_sections(struct cbvh_file *f, const cbvh_section_map *map, cbvh_error *err)
{
    cbvh_tree_walk walk = {0};
    cbvh_w4_walk w4_walk = {0};
    const int wide = f->layout == CBVH_LAYOUT_WIDE4;
    cbvh_vertex_bounds bounds;
    cbvh_vertex_bounds_init(&bounds);
    cbvh_unmap_build unmap;
    cbvh_result r = cbvh_unmap_begin(f, &unmap, err);
    if (r == CBVH_OK)
        r = wide ? check_section(f, map, CBVH_SECTION_NODES, f->nodes, cbvh_w4_tree_check, &w4_walk, err)
                 : check_section(f, map, CBVH_SECTION_NODES, f->nodes, cbvh_tree_check, &walk, err);
    if (r == CBVH_OK)
        r = check_section(f, map, CBVH_SECTION_TRIANGLES, f->triangles, cbvh_indices_check, NULL, err);
    if (r == CBVH_OK)
        r = check_section(f, map, CBVH_SECTION_VERTICES, f->vertices, cbvh_vertices_check, &bounds, err);
    if (r == CBVH_OK && f->remap)
        r = check_section(f, map, CBVH_SECTION_REMAP, f->remap, cbvh_remap_check, &unmap, err);
    if (r == CBVH_OK && f->materials)
        r = check_section(f, map, CBVH_SECTION_MATERIALS, f->materials, NULL, NULL, err);
    if (r == CBVH_OK && f->material_names)
        r = check_section(f, map, CBVH_SECTION_MATERIAL_NAMES, f->material_names, NULL, NULL, err);
    if (r == CBVH_OK && f->material_names)
        r = cbvh_material_names_check(
            f, &f->sections[map->index[cbvh_section_slot(CBVH_SECTION_MATERIAL_NAMES)]],
            &f->info.material_name_count, err);
    if (r == CBVH_OK)
        r = wide ? cbvh_w4_tree_finish(f, &w4_walk, err) : cbvh_tree_finish(f, &walk, err);
    if (r == CBVH_OK)
        r = cbvh_vertices_finish(f, &bounds, err);
    if (r == CBVH_OK && f->remap)
        r = cbvh_unmap_finish(f, &unmap, err);
    return r;
}
