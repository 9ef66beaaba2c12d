/* load.h: the loader's internal steps, each in its own file, run in order by load.c. */
#ifndef CBVH_LOAD_LOAD_H
#define CBVH_LOAD_LOAD_H

#include <stddef.h>
#include <stdint.h>

#include "common/compiler.h"
#include "common/file.h"
#include "common/crc32.h"
#include "layout/encodings.h"

/* Index in f->sections of each known section type (0 = NODES .. 4 = MATERIALS), -1 when absent;
 * crc_pending: a raw section used in place whose CRC is checked chunk by chunk with its content. */
typedef struct cbvh_section_map {
    int index[CBVH_KNOWN_SECTIONS];
    int crc_pending[CBVH_KNOWN_SECTIONS];
} cbvh_section_map;

/* Raw sections are used in place when the file's bytes are 4-byte aligned (sections sit at multiples of
 * 64, and nothing in a section needs more than 4); otherwise they are copied. */
static inline int cbvh_in_place(const struct cbvh_file *f)
{
    return (uintptr_t)f->bytes % 4 == 0;
}

/* Checks the 128-byte header of f->bytes (f->size bytes) and fills f->info,
 * f->grid_origin, f->grid_scale and f->original_triangle_count. */
cbvh_result cbvh_validate_header(struct cbvh_file *f, cbvh_error *err);

/* Checks the section table, the layout (bounds, alignment, order, zero
 * padding) and the CRC of every section but those left crc_pending; fills f->sections and `map`. */
cbvh_result cbvh_validate_table(struct cbvh_file *f, cbvh_section_map *map, cbvh_error *err);

/* The error for section `index` whose stored bytes have CRC `computed`. */
cbvh_result cbvh_crc_mismatch(const struct cbvh_file *f, uint32_t index, uint32_t computed, cbvh_error *err);

/* Inflates one zlib stream of exactly `stored_size` bytes into a new 64-byte aligned buffer (*out, owned
 * by the caller) of `lead` bytes, left for the caller, and then exactly `size` bytes. */
cbvh_result cbvh_inflate_section(const cbvh_allocator *a, const uint8_t *src, uint64_t stored_size,
                                 uint64_t size, size_t lead, uint32_t section_index, void **out,
                                 cbvh_error *err);

/* Element checks. Each runs over consecutive ranges [begin, end) of its section's elements, in order
 * (cbvh_check_sections feeds them chunk by chunk, each chunk checked while in cache), then finishes. */
typedef cbvh_result (*cbvh_range_check)(const struct cbvh_file *f, void *state, uint32_t begin, uint32_t end,
                                        cbvh_error *err);

/* Nodes: boxes, links, depth and leaf ranges (format spec section 5). Start from a zeroed walk. */
typedef struct cbvh_tree_walk {
    uint32_t begin[CBVH_MAX_DEPTH], end[CBVH_MAX_DEPTH], depth[CBVH_MAX_DEPTH]; /* pending second children */
    uint32_t top, next_triangle, max_depth, current_depth, after_leaf, bad_box;
} cbvh_tree_walk;
cbvh_result cbvh_tree_check(const struct cbvh_file *f, void *walk, uint32_t begin, uint32_t end,
                            cbvh_error *err);
cbvh_result cbvh_tree_finish(const struct cbvh_file *f, const cbvh_tree_walk *walk, cbvh_error *err);

/* Wide4 nodes: slots, links, levels and leaf ranges (format spec section 5.2). Start from a zeroed walk. */
typedef struct cbvh_w4_walk {
    uint32_t next_child, next_triangle, level_end, depth;
} cbvh_w4_walk;
cbvh_result cbvh_w4_tree_check(const struct cbvh_file *f, void *walk, uint32_t begin, uint32_t end,
                               cbvh_error *err);
cbvh_result cbvh_w4_tree_finish(const struct cbvh_file *f, const cbvh_w4_walk *walk, cbvh_error *err);

/* Triangles: every vertex index below vertex_count (no state). */
cbvh_result cbvh_indices_check(const struct cbvh_file *f, void *unused, uint32_t begin, uint32_t end,
                               cbvh_error *err);

/* Vertices: finite, and their bounds equal to the header's. */
typedef struct cbvh_vertex_bounds {
    float lo[3], hi[3];      /* float vertices */
    uint32_t qlo[3], qhi[3]; /* grid vertices */
} cbvh_vertex_bounds;
void cbvh_vertex_bounds_init(cbvh_vertex_bounds *b);
cbvh_result cbvh_vertices_check(const struct cbvh_file *f, void *bounds, uint32_t begin, uint32_t end,
                                cbvh_error *err);
cbvh_result cbvh_vertices_finish(const struct cbvh_file *f, const cbvh_vertex_bounds *b, cbvh_error *err);

/* Remap: values below original_triangle_count and unique, while building f->unmap. begin allocates the
 * table (owned by f at once); the range check fills a dense table; finish builds a sorted one. */
typedef struct cbvh_unmap_build {
    uint32_t *unmap;
    int dense;
} cbvh_unmap_build;
cbvh_result cbvh_unmap_begin(struct cbvh_file *f, cbvh_unmap_build *b, cbvh_error *err);
cbvh_result cbvh_remap_check(const struct cbvh_file *f, void *build, uint32_t begin, uint32_t end,
                             cbvh_error *err);
cbvh_result cbvh_unmap_finish(const struct cbvh_file *f, const cbvh_unmap_build *b, cbvh_error *err);

/* MATERIAL_NAMES (section `s`, at f->material_names): a count, then entries of (id, offset) in increasing
 * (id, name) order, each offset where its NUL-terminated name starts, the names tiling the rest; stores the
 * count in *count. */
cbvh_result cbvh_material_names_check(const struct cbvh_file *f, const cbvh_section_info *s, uint32_t *count,
                                      cbvh_error *err);

/* Runs the element checks over every known section, with the pending CRCs, chunk by chunk. */
cbvh_result cbvh_check_sections(struct cbvh_file *f, const cbvh_section_map *map, cbvh_error *err);

/* Runs every step on f->bytes / f->size (set by the caller, with f->allocator);
 * on failure the caller frees what f owns, as cbvh_close does. */
cbvh_result cbvh_load(struct cbvh_file *f, cbvh_error *err);

#endif
