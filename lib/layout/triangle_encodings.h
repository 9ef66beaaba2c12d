/* triangle_encodings.h: the TRIANGLES section's index encodings (format spec section 4), one part per
 * encoding: its bytes and size, how the cooker encodes a triangle, how readers decode one, and what makes
 * one valid. The table of encodings (encodings.h), the cooker's numbering (cook/layout.c) and writer
 * (cook/sections.c), the validator (load/validate_mesh.c) and the query kernels (query/leaf.h) take them
 * from here. The hosts are little-endian (configure checks), so decoding reads the bytes as they lie. */
#ifndef CBVH_LAYOUT_TRIANGLE_ENCODINGS_H
#define CBVH_LAYOUT_TRIANGLE_ENCODINGS_H

#include <stdint.h>

#include "common/endian.h"
#include "common/file.h"
#include "common/format.h"

/* U16 (CBVH_TRIS_U16) and U32 (CBVH_TRIS_U32): a triangle is its three indices. Valid when each is below
 * the vertex count. */
#define CBVH_TRIS_U16_SIZE 6u
#define CBVH_TRIS_U32_SIZE 12u

static inline void cbvh_u16_encode(uint8_t *p, const uint32_t t[3])
{
    for (int v = 0; v < 3; v++)
        cbvh_write_u16(p + 2 * v, (uint16_t)t[v]);
}

static inline void cbvh_u32_encode(uint8_t *p, const uint32_t t[3])
{
    for (int v = 0; v < 3; v++)
        cbvh_write_u32(p + 4 * v, t[v]);
}

/* DELTA16 (CBVH_TRIS_DELTA16): a triangle is a u32 base (its first index), then its second and third
 * indices less the base as i16. Valid when all three, computed in 64 bits (so that a negative or wrapped
 * index is caught), are below the vertex count. */
#define CBVH_TRIS_DELTA16_SIZE 8u

/* Whether index v can follow `base` in a DELTA16 triangle. */
static inline int cbvh_delta16_fits(uint32_t base, uint32_t v)
{
    const int64_t d = (int64_t)v - (int64_t)base;
    return d >= INT16_MIN && d <= INT16_MAX;
}

/* Triangle t (whose second and third indices fit) at p. */
static inline void cbvh_delta16_encode(uint8_t *p, const uint32_t t[3])
{
    cbvh_write_u32(p, t[0]);
    cbvh_write_u16(p + 4, (uint16_t)(t[1] - t[0]));
    cbvh_write_u16(p + 6, (uint16_t)(t[2] - t[0]));
}

/* The base and the two deltas of the DELTA16 triangle at p. */
static inline uint32_t cbvh_delta16_base(const uint8_t *p)
{
    return *(const uint32_t *)(const void *)p;
}

static inline const int16_t *cbvh_delta16_deltas(const uint8_t *p)
{
    return (const int16_t *)(const void *)(p + 4);
}

/* Whether the DELTA16 triangle at p is valid for vertex_count vertices. */
static inline int cbvh_delta16_valid(const uint8_t *p, uint32_t vertex_count)
{
    const int64_t vc = vertex_count, base = cbvh_delta16_base(p);
    const int16_t *d = cbvh_delta16_deltas(p);
    const int64_t a = base + d[0], b = base + d[1];
    return base < vc && a >= 0 && a < vc && b >= 0 && b < vc;
}

/* LOCAL8 (CBVH_TRIS_LOCAL8): blocks of CBVH_LOCAL8_BLOCK triangles, each a u32 base vertex index, then
 * CBVH_LOCAL8_TRIANGLE_BYTES offset bytes a triangle (index = base + offset), so that a block's vertices
 * lie within CBVH_LOCAL8_WINDOW indices. The last block may be partly used; its slots past the section's
 * last triangle hold offsets 0, so that its bytes are canonical. Valid when each block's base plus its
 * largest offset, in 64 bits, is below the vertex count and the unused slots are 0. */
#define CBVH_LOCAL8_BLOCK 8u
#define CBVH_LOCAL8_OFFSETS_AT 4u /* the base, then the offsets */
#define CBVH_LOCAL8_TRIANGLE_BYTES 3u
#define CBVH_LOCAL8_BLOCK_SIZE (CBVH_LOCAL8_OFFSETS_AT + CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK)
#define CBVH_LOCAL8_WINDOW 256u

/* The blocks of a section of `triangles` (at most CBVH_MAX_TRIANGLES) triangles. */
static inline uint32_t cbvh_local8_blocks(uint32_t triangles)
{
    return (triangles + CBVH_LOCAL8_BLOCK - 1u) / CBVH_LOCAL8_BLOCK;
}

/* The block holding triangle k. */
static inline const uint8_t *cbvh_local8_block(const void *tris, uint32_t k)
{
    return (const uint8_t *)tris + (size_t)CBVH_LOCAL8_BLOCK_SIZE * (k / CBVH_LOCAL8_BLOCK);
}

/* The offset bytes of the triangle in `slot` (0 .. CBVH_LOCAL8_BLOCK - 1) of a block. */
static inline const uint8_t *cbvh_local8_offsets(const uint8_t *block, uint32_t slot)
{
    return block + CBVH_LOCAL8_OFFSETS_AT + CBVH_LOCAL8_TRIANGLE_BYTES * slot;
}

/* The n (1 .. CBVH_LOCAL8_BLOCK) triangles of t (3 n indices within CBVH_LOCAL8_WINDOW of their smallest,
 * as the cooker numbers them) as one block at p, unused slots 0. */
static inline void cbvh_local8_encode_block(uint8_t *p, const uint32_t *t, uint32_t n)
{
    uint32_t base = UINT32_MAX;
    for (uint32_t j = 0; j < 3 * n; j++)
        base = t[j] < base ? t[j] : base;
    cbvh_write_u32(p, base);
    for (uint32_t j = 0; j < CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK; j++)
        p[CBVH_LOCAL8_OFFSETS_AT + j] = j < 3 * n ? (uint8_t)(t[j] - base) : 0;
}

/* The largest offset of the first `used` triangles of a block: for a full block, a fixed-length loop the
 * compiler vectorizes. */
static inline uint32_t cbvh_local8_largest_offset(const uint8_t *block, uint32_t used)
{
    const uint8_t *o = block + CBVH_LOCAL8_OFFSETS_AT;
    uint8_t largest = 0;
    if (used == CBVH_LOCAL8_BLOCK) {
        for (uint32_t j = 0; j < CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK; j++)
            largest = o[j] > largest ? o[j] : largest;
    } else {
        for (uint32_t j = 0; j < CBVH_LOCAL8_TRIANGLE_BYTES * used; j++)
            largest = o[j] > largest ? o[j] : largest;
    }
    return largest;
}

/* The first offset byte (counted from the block's first offset) past the first `used` triangles of a
 * block that is not 0, or CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK when they all are. */
static inline uint32_t cbvh_local8_first_loose_offset(const uint8_t *block, uint32_t used)
{
    const uint8_t *o = block + CBVH_LOCAL8_OFFSETS_AT;
    uint32_t j = CBVH_LOCAL8_TRIANGLE_BYTES * used;
    while (j < CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK && o[j] == 0)
        j++;
    return j;
}

/* Any encoding, by its number (CBVH_TRIS_*). Inlined with a constant encoding, the branches fold away (the
 * query kernels' leaf loops). */

/* Where triangle k's entry starts: a LOCAL8 triangle's block (its base and offsets are in the block's
 * bytes). For prefetching a leaf before its visit. */
static inline const void *cbvh_indices_entry(const void *tris, int enc, uint32_t k)
{
    const uint8_t *t = (const uint8_t *)tris;
    if (enc == CBVH_TRIS_LOCAL8)
        return cbvh_local8_block(tris, k);
    const uint32_t size = enc == CBVH_TRIS_DELTA16 ? CBVH_TRIS_DELTA16_SIZE
                          : enc == CBVH_TRIS_U16   ? CBVH_TRIS_U16_SIZE
                                                   : CBVH_TRIS_U32_SIZE;
    return t + size * (size_t)k;
}

/* A vertex index next to triangle k's vertices, from its entry alone: a LOCAL8 triangle's block base (its
 * vertices lie within CBVH_LOCAL8_WINDOW past it), else its first vertex. For requesting a leaf's
 * vertices early. */
static inline uint32_t cbvh_vertex_hint(const void *tris, int enc, uint32_t k)
{
    const uint8_t *t = (const uint8_t *)cbvh_indices_entry(tris, enc, k);
    return enc == CBVH_TRIS_U16 ? (uint32_t) * (const uint16_t *)(const void *)t
                                : *(const uint32_t *)(const void *)t;
}

/* Triangle k's three vertex indices. */
static inline void cbvh_indices_decode(const void *tris, int enc, uint32_t k, uint32_t idx[3])
{
    if (enc == CBVH_TRIS_LOCAL8) {
        const uint8_t *b = cbvh_local8_block(tris, k);
        const uint8_t *o = cbvh_local8_offsets(b, k % CBVH_LOCAL8_BLOCK);
        const uint32_t base = *(const uint32_t *)(const void *)b;
        idx[0] = base + o[0];
        idx[1] = base + o[1];
        idx[2] = base + o[2];
    } else if (enc == CBVH_TRIS_DELTA16) {
        const uint8_t *t = (const uint8_t *)tris + CBVH_TRIS_DELTA16_SIZE * (size_t)k;
        const int16_t *d = cbvh_delta16_deltas(t);
        idx[0] = cbvh_delta16_base(t);
        idx[1] = idx[0] + (uint32_t)(int32_t)d[0];
        idx[2] = idx[0] + (uint32_t)(int32_t)d[1];
    } else if (enc == CBVH_TRIS_U16) {
        const uint16_t *t = (const uint16_t *)tris + 3u * (size_t)k;
        idx[0] = t[0];
        idx[1] = t[1];
        idx[2] = t[2];
    } else {
        const uint32_t *t = (const uint32_t *)tris + 3u * (size_t)k;
        idx[0] = t[0];
        idx[1] = t[1];
        idx[2] = t[2];
    }
}

/* Cooked triangle `tri`'s three vertex indices in f. */
static inline void cbvh_triangle_indices(const struct cbvh_file *f, uint32_t tri, uint32_t idx[3])
{
    cbvh_indices_decode(f->triangles, (int)f->triangle_encoding, tri, idx);
}

/* Cooked triangle `tri`'s three vertices in f. */
static inline void cbvh_triangle_vertices(const struct cbvh_file *f, uint32_t tri, float v0[3], float v1[3],
                                          float v2[3])
{
    uint32_t idx[3];
    cbvh_triangle_indices(f, tri, idx);
    cbvh_vertex_position(f, idx[0], v0);
    cbvh_vertex_position(f, idx[1], v1);
    cbvh_vertex_position(f, idx[2], v2);
}

#endif
