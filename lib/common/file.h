/* file.h: the in-memory form of an opened, validated cbvh file, shared by the loader and the queries. */
#ifndef CBVH_COMMON_FILE_H
#define CBVH_COMMON_FILE_H

#include <assert.h>

#include "cbvh.h"
#include "common/format.h"

/* Readable bytes before every known section the loader places (nodes, triangles, vertices, ...): in place
 * they are the file's (the 128-byte header comes first), and a copied or inflated section is allocated
 * with them in front, zeroed. The ray test's vertex loads start 4 bytes before a float vertex
 * (query/leaf.h's leaf_vertex4) so that they never read past the section's end. */
#define CBVH_SECTION_LEAD 64u

/* A mesh whose vertices take up to this many bytes is taken to stay in the caches (half of a common
 * 1 MiB L2; struct cbvh_file's vertices_far says which side a file is on). Requesting vertices ahead
 * hides misses; where there are none it costs only its instructions, so the walks request ahead, and the
 * streams interleave their tails, only past this size (docs/PERFORMANCE.md). */
#define CBVH_CACHED_VERTEX_BYTES (512u * 1024u)

/* The margin of struct cbvh_file's origin_near box in extents of the mesh: a quarter of the distance past
 * which a ray origin is moved (CBVH_FAR_FACTOR, query/raycast.h), so rounding cannot matter. */
#define CBVH_NEAR_ORIGIN_FACTOR 4

/* The triangles struct cbvh_file's small_triangle_extent samples: enough for a steady quartile, few enough
 * to cost a microsecond or two at open. */
#define CBVH_EXTENT_SAMPLES 64u

/* Everything here was validated by the loader: node links, leaf ranges,
 * indices and encodings are in range, so the query kernels do not check. */
struct cbvh_file {
    cbvh_allocator allocator;

    /* The bytes the file was opened from: a read-only mapping (mapped = 1) or the caller's buffer. */
    const uint8_t *bytes;
    size_t size;
    int mapped;

    cbvh_file_info info;
    cbvh_section_info sections[CBVH_MAX_SECTIONS];

    const void *nodes;          /* the NODES section: read through layout/tree.h only */
    uint32_t layout;            /* the node layout (cbvh_layout): which module reads the nodes */
    const void *triangles;      /* info.triangle_count entries in cooked (leaf) order */
    uint32_t triangle_encoding; /* CBVH_TRIS_* */
    const void *vertices;       /* info.vertex_count entries */
    uint32_t vertex_encoding;   /* CBVH_VERTS_* */
    uint32_t vertices_far;      /* 1 when there are triangles and their vertices take more than
                                 * CBVH_CACHED_VERTEX_BYTES: the walks request vertices ahead */
    float bounds_extent;        /* the bounds' largest extent (max over axes of max - min), set at open */
    /* An origin inside this box (lane 3 is 0 in both) is next to the mesh: cbvh_ray_prepare (query/raycast.h)
     * then skips cbvh_ray_place_origin, whose tests it would pass. The bounds widened by
     * CBVH_NEAR_ORIGIN_FACTOR times bounds_extent; an empty box when that extent is too large for the
     * margin to keep the overflow test passing. Set at open. */
    _Alignas(16) float origin_near_lo[4];
    _Alignas(16) float origin_near_hi[4];
    /* info's bounds, lane 3 0 in both: an origin inside them is among the triangles (cbvh_ray_prepare's
     * any_flip, query/ray_setup.h). Set at open. */
    _Alignas(16) float bounds_lo[4];
    _Alignas(16) float bounds_hi[4];
    /* The box holding every box a walk tests first (layout/tree.h's cbvh_tree_top_box) dequantized with the
     * box test's arithmetic, lane 3 0 in both; lo +inf and hi -inf (a box every ray misses) for a tree
     * without one. A ray that misses it hits nothing (cbvh_ray_prepare, query/raycast.h). Set at open. */
    _Alignas(16) float top_lo[4];
    _Alignas(16) float top_hi[4];
    /* The lower quartile of the largest axis extents of up to CBVH_EXTENT_SAMPLES triangles taken evenly by
     * cooked index (0 without triangles): how small the leaves' triangles are, which decides whether a ball's
     * or capsule's own node tests pay (query/overlap.c). Set at open. */
    float small_triangle_extent;
    const void *remap;       /* cooked -> original triangle id; NULL = identity */
    uint32_t remap_encoding; /* CBVH_REMAP_* */
    const uint32_t *unmap;   /* original -> cooked id (owned, built at open when remap is present): dense,
                              * original_triangle_count entries, CBVH_NO_HIT for dropped ids; or, when
                              * unmap_sorted, cooked ids sorted by original id (triangle_count entries) */
    uint32_t unmap_sorted;
    const void *materials;         /* per cooked triangle, or one for all (CBVH_MATS_UNIFORM); NULL = all 0 */
    uint32_t material_encoding;    /* CBVH_MATS_* */
    const uint8_t *material_names; /* the MATERIAL_NAMES section (info.material_name_count names), or NULL */
    const void *quads; /* NULL, or the triangles expanded for the ray test (cbvh_file_expand_triangles,
                        * SIMD builds): struct leaf_quad g (query/leaf.h) holds cooked triangles
                        * 4g..4g+3, the last group padded with the last triangle */

    float grid_origin[3];
    float grid_scale[3];
    uint32_t original_triangle_count; /* original ids are below it (= triangle_count without remap) */

    /* Memory owned by the file (inflated or realigned known sections, unmap), freed at close. */
    void *owned[CBVH_MAX_SECTIONS + 1];
    uint32_t owned_count;
};

/* Records memory the file owns so that close frees it. At most the six known sections, the unmap table, a
 * read() buffer and the expanded triangles: the table cannot fill up. */
static inline void cbvh_file_own(struct cbvh_file *f, void *p)
{
    assert(f->owned_count < sizeof f->owned / sizeof f->owned[0]);
    f->owned[f->owned_count++] = p;
}

/* Where vertex v's three coordinates start: three floats, or three grid coordinates (u16). */
static inline const void *cbvh_vertex_address(const struct cbvh_file *f, uint32_t v)
{
    if (f->vertex_encoding == CBVH_VERTS_F32)
        return (const float *)f->vertices + 3u * (size_t)v;
    return (const uint16_t *)f->vertices + 3u * (size_t)v;
}

/* Vertex index -> position, decoded exactly as the cooker decoded it. */
static inline void cbvh_vertex_position(const struct cbvh_file *f, uint32_t v, float p[3])
{
    if (f->vertex_encoding == CBVH_VERTS_F32) {
        const float *q = (const float *)cbvh_vertex_address(f, v);
        p[0] = q[0];
        p[1] = q[1];
        p[2] = q[2];
    } else {
        const uint16_t *q = (const uint16_t *)cbvh_vertex_address(f, v);
        p[0] = cbvh_dequantize(q[0], f->grid_origin[0], f->grid_scale[0]);
        p[1] = cbvh_dequantize(q[1], f->grid_origin[1], f->grid_scale[1]);
        p[2] = cbvh_dequantize(q[2], f->grid_origin[2], f->grid_scale[2]);
    }
}

/* Cooked triangle index -> its material id (0 without a MATERIALS section). */
static inline uint32_t cbvh_cooked_material(const struct cbvh_file *f, uint32_t cooked)
{
    if (!f->materials)
        return 0;
    switch (f->material_encoding) {
    case CBVH_MATS_U8:
        return ((const uint8_t *)f->materials)[cooked];
    case CBVH_MATS_U16:
        return ((const uint16_t *)f->materials)[cooked];
    case CBVH_MATS_U32:
        return ((const uint32_t *)f->materials)[cooked];
    default:
        return ((const uint32_t *)f->materials)[0]; /* CBVH_MATS_UNIFORM: one id for all */
    }
}

/* Where the REMAP section holds cooked triangle tri's original id (f->remap not NULL). */
static inline const uint8_t *cbvh_remap_entry(const struct cbvh_file *f, uint32_t tri)
{
    const size_t size = f->remap_encoding == CBVH_REMAP_U16   ? 2u
                        : f->remap_encoding == CBVH_REMAP_U24 ? 3u
                                                              : 4u;
    return (const uint8_t *)f->remap + size * tri;
}

/* Cooked triangle index -> original id as queries report it. */
static inline uint32_t cbvh_original_id(const struct cbvh_file *f, uint32_t tri)
{
    if (!f->remap)
        return tri;
    const uint8_t *p = cbvh_remap_entry(f, tri);
    if (f->remap_encoding == CBVH_REMAP_U16)
        return *(const uint16_t *)(const void *)p;
    if (f->remap_encoding == CBVH_REMAP_U24)
        return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16;
    return *(const uint32_t *)(const void *)p;
}

#endif
