/* check_sections.c: runs the element checks over every known section chunk by chunk, each chunk's pending CRC first, so it is read from memory once. */
#include "common/error.h"
#include "load/load.h"

/* Small enough to stay in L2 between the CRC and the checks. */
#define CHUNK_BYTES (64u * 1024u)

/* One section: `count` elements of `size` bytes at `data`; `check` may be NULL (materials need none). When
 * the CRC is pending it is computed chunk by chunk ahead of the checks, and a section whose CRC does not
 * match reports that, whatever else the checks found. */
static cbvh_result check_section(const struct cbvh_file *f, uint32_t index, int crc_pending, const void *data,
                                 uint32_t size, cbvh_range_check check, void *state, cbvh_error *err)
{
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
    static const uint8_t tri_size[] = { 6, 12, 8 }, vert_size[] = { 12, 6 }, remap_size[] = { 2, 4 },
                         mat_size[] = { 1, 2, 4 };
    cbvh_tree_walk walk = { 0 };
    cbvh_vertex_bounds bounds;
    cbvh_vertex_bounds_init(&bounds);
    cbvh_unmap_build unmap;
    cbvh_result r = cbvh_unmap_begin(f, &unmap, err);
    const int *at = map->index, *pending = map->crc_pending;
    if (r == CBVH_OK)
        r = check_section(f, (uint32_t)at[0], pending[0], f->nodes, 16, cbvh_tree_check, &walk, err);
    if (r == CBVH_OK)
        r = check_section(f, (uint32_t)at[1], pending[1], f->triangles, tri_size[f->triangle_encoding],
                          cbvh_indices_check, NULL, err);
    if (r == CBVH_OK)
        r = check_section(f, (uint32_t)at[2], pending[2], f->vertices, vert_size[f->vertex_encoding],
                          cbvh_vertices_check, &bounds, err);
    if (r == CBVH_OK && f->remap)
        r = check_section(f, (uint32_t)at[3], pending[3], f->remap, remap_size[f->remap_encoding], cbvh_remap_check,
                          &unmap, err);
    if (r == CBVH_OK && f->materials)
        r = check_section(f, (uint32_t)at[4], pending[4], f->materials, mat_size[f->material_encoding], NULL, NULL,
                          err);
    if (r == CBVH_OK)
        r = cbvh_tree_finish(f, &walk, err);
    if (r == CBVH_OK)
        r = cbvh_vertices_finish(f, &bounds, err);
    if (r == CBVH_OK && f->remap)
        r = cbvh_unmap_finish(f, &unmap, err);
    return r;
}
