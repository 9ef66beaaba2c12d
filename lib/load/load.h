/* load.h: the loader's internal steps, each in its own file, run in order by load.c. */
#ifndef CBVH_LOAD_LOAD_H
#define CBVH_LOAD_LOAD_H

#include <stddef.h>
#include <stdint.h>

#include "common/file.h"

/* Index in f->sections of each known section type (0 = NODES .. 4 = MATERIALS), -1 when absent. */
#define CBVH_KNOWN_SECTIONS 5
typedef struct cbvh_section_map {
    int index[CBVH_KNOWN_SECTIONS];
} cbvh_section_map;

/* CRC32 (zlib's) of `size` bytes, any size: by carry-less multiplication when the CPU has it, else zlib. */
uint32_t cbvh_crc32(const uint8_t *data, uint64_t size);

/* The PCLMULQDQ kernel: the running (uninverted) state after `size` more bytes, size >= 64 and a
 * multiple of 16; callable only when cbvh_crc32_pclmul_available() says so. */
uint32_t cbvh_crc32_pclmul(uint32_t crc, const uint8_t *data, size_t size);
int cbvh_crc32_pclmul_available(void);

/* Checks the 128-byte header of f->bytes (f->size bytes) and fills f->info,
 * f->grid_origin, f->grid_scale and f->original_triangle_count. */
cbvh_result cbvh_validate_header(struct cbvh_file *f, cbvh_error *err);

/* Checks the section table, the layout (bounds, alignment, order, zero
 * padding) and every section's CRC; fills f->sections and `map`. */
cbvh_result cbvh_validate_table(struct cbvh_file *f, cbvh_section_map *map, cbvh_error *err);

/* Inflates one zlib stream of exactly `stored_size` bytes into a new 64-byte
 * aligned buffer of exactly `size` bytes (*out, owned by the caller). */
cbvh_result cbvh_inflate_section(const cbvh_allocator *a, const uint8_t *src, uint64_t stored_size,
                                 uint64_t size, uint32_t section_index, void **out, cbvh_error *err);

/* Checks every node's box, links, depth and leaf ranges (format spec section 5). */
cbvh_result cbvh_validate_tree(const struct cbvh_file *f, cbvh_error *err);

/* Checks every vertex index of the TRIANGLES section against vertex_count. */
cbvh_result cbvh_validate_indices(const struct cbvh_file *f, cbvh_error *err);

/* Checks every decoded vertex is finite and that their bounds equal the header's. */
cbvh_result cbvh_validate_vertices(const struct cbvh_file *f, cbvh_error *err);

/* Checks REMAP values are below original_triangle_count and unique, and
 * builds f->unmap (owned, appended to f->owned). No-op without REMAP. */
cbvh_result cbvh_validate_remap(struct cbvh_file *f, cbvh_error *err);

/* Runs every step on f->bytes / f->size (set by the caller, with f->allocator);
 * on failure the caller frees what f owns, as cbvh_close does. */
cbvh_result cbvh_load(struct cbvh_file *f, cbvh_error *err);

/* Records memory the file owns so that close frees it. */
void cbvh_file_own(struct cbvh_file *f, void *p);

#endif
