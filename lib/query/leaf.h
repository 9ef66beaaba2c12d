/* leaf.h: testing one ray against the triangles of a leaf, for closest-hit and any-hit walks. */
#ifndef CBVH_QUERY_LEAF_H
#define CBVH_QUERY_LEAF_H

#include <float.h>

#include "common/file.h"
#include "query/lanes.h"
#include "query/ray_setup.h"
#include "query/ray_triangle.h"

/* The lowest set bit of a non-empty 4-bit mask, as a slot or lane number: 1, 2, 4, 8 -> 0, 1, 2, 3 (the
 * walks' child slots and the leaves' filtered lanes). */
static inline uint32_t cbvh_lowest_lane(uint32_t mask4)
{
    const uint32_t low = mask4 & (0u - mask4);
    return (low >> 1) - (low >> 3);
}

/* The best hit so far, in cooked triangle order. */
struct cbvh_best_hit {
    uint32_t tri; /* cooked index, UINT32_MAX while there is none */
    float t, u, v;
};

/* The tie rule every ray path shares: a hit replaces the best one when it is
 * nearer, or exactly as near with a lower cooked index. It makes the result
 * independent of the order in which nodes are visited (sorted, stackless,
 * distance, streams), provided no path culls a box holding a hit at t <= tmax. */
static inline int cbvh_hit_better(float t, uint32_t tri, float best_t, uint32_t best_tri)
{
    return t < best_t || (t == best_t && tri < best_tri);
}

/* The culling and hit filter of a query with options (raycast.c fills it in). check says what becomes of
 * cooked triangle k, which the ray hits at t (the kernels' t) with barycentrics u, v: a
 * cbvh_filter_result. It is called through the pointer, so the kernels, which tools and tests also
 * compile, name no library function. */
struct cbvh_hit_gate {
    int (*check)(const struct cbvh_hit_gate *gate, const struct cbvh_file *f, uint32_t k, float t, float u,
                 float v);
    cbvh_cull cull;
    cbvh_hit_filter_fn filter;
    void *user;
    double t_base; /* the kernels' t plus this is t on the caller's ray */
    float dir[3];  /* the ray direction in the mesh's frame */
    int placed;    /* a query transform: records are rotated into the world by `rotation` */
    double rotation[3][3];
};

/* Triangle k, hit at t in the ray's current range: any hit: 1 (the walk stops) unless the gate rejects it;
 * closest hit: it becomes the best when nearer than the best so far (cbvh_hit_better) and the gate, when
 * there is one, does not reject it; returns 1 when the gate says to stop there. The gate is asked only
 * about hits that would count, so a plain query pays one NULL test per hit. */
CBVH_KERNEL int leaf_take(const struct cbvh_file *restrict f, const struct cbvh_hit_gate *gate, uint32_t k, float t,
                          float u, float v, const int any, float *restrict best_t, struct cbvh_best_hit *restrict best)
{
    if (!any && !cbvh_hit_better(t, k, *best_t, best->tri))
        return 0;
    const int verdict = gate ? gate->check(gate, f, k, t, u, v) : CBVH_FILTER_ACCEPT;
    if (verdict == CBVH_FILTER_REJECT)
        return 0;
    if (any)
        return 1;
    /* the answer reports k's original id: on a large mesh its REMAP entry is likely a cache miss, which
     * the rest of the walk can hide */
    if (f->remap)
        CBVH_PREFETCH(cbvh_remap_entry(f, k));
    *best_t = t;
    best->tri = k;
    best->t = t;
    best->u = u;
    best->v = v;
    return verdict == CBVH_FILTER_STOP;
}

/* Triangle k's vertex indices and positions (p[v]: vertex v) for encodings that are compile-time
 * constants in the specialised leaf loops below (the switch then folds away), or run-time values in the
 * generic one. An array of rows, not three output pointers: the walks inline this, and an array of
 * pointers to the caller's locals was built in every walk's prologue. */
CBVH_KERNEL void leaf_triangle(const void *restrict tris, const int tri_enc, const void *restrict verts,
                               const int vert_enc, const float *restrict grid_origin,
                               const float *restrict grid_scale, uint32_t k, float p[3][3])
{
    uint32_t idx[3];
    cbvh_indices_decode(tris, tri_enc, k, idx);
    for (int v = 0; v < 3; v++) {
        if (vert_enc == CBVH_VERTS_F32) {
            const float *q = (const float *)verts + 3u * (size_t)idx[v];
            p[v][0] = q[0];
            p[v][1] = q[1];
            p[v][2] = q[2];
        } else {
            const uint16_t *q = (const uint16_t *)verts + 3u * (size_t)idx[v];
            for (int x = 0; x < 3; x++)
                p[v][x] = cbvh_dequantize(q[x], grid_origin[x], grid_scale[x]);
        }
    }
}

#ifdef CBVH_HAVE_SIMD
/* Vertex i as (any, x, y, z): for floats one 16-byte load ending with the vertex's 12 bytes, so starting 4
 * bytes before them, which every placed section has readable (CBVH_SECTION_LEAD) and never past them; or
 * dequantized. */
CBVH_KERNEL __m128 leaf_vertex4(const void *restrict verts, const int vert_enc, const float *restrict grid_origin,
                                const float *restrict grid_scale, uint32_t i)
{
    if (vert_enc == CBVH_VERTS_F32)
        return _mm_loadu_ps((const float *)(const void *)((const uint8_t *)verts + 12u * (size_t)i - 4u));
    const uint16_t *q = (const uint16_t *)verts + 3u * (size_t)i;
    return _mm_setr_ps(0.0f, cbvh_dequantize(q[0], grid_origin[0], grid_scale[0]),
                       cbvh_dequantize(q[1], grid_origin[1], grid_scale[1]),
                       cbvh_dequantize(q[2], grid_origin[2], grid_scale[2]));
}

/* Four triangles gathered for the SIMD filter, a lane per triangle: c[v][a][j] is axis a of vertex v of
 * lane j's triangle. Floats rather than vectors, so that the exact test of a lane the filter keeps reads
 * its vertices back as they are (leaf_lane_test) instead of decoding the triangle again. */
struct leaf_quad {
    _Alignas(16) float c[3][3][4];
};

/* The vertices idx[v][j] (vertex v of lane j's triangle) into q. */
CBVH_KERNEL void leaf_gather4_vertices(const void *restrict verts, const int vert_enc,
                                       const float *restrict grid_origin, const float *restrict grid_scale,
                                       const uint32_t idx[3][4], struct leaf_quad *restrict q)
{
    CBVH_UNROLL(3)
    for (uint32_t v = 0; v < 3; v++) {
        __m128 r0 = leaf_vertex4(verts, vert_enc, grid_origin, grid_scale, idx[v][0]);
        __m128 r1 = leaf_vertex4(verts, vert_enc, grid_origin, grid_scale, idx[v][1]);
        __m128 r2 = leaf_vertex4(verts, vert_enc, grid_origin, grid_scale, idx[v][2]);
        __m128 r3 = leaf_vertex4(verts, vert_enc, grid_origin, grid_scale, idx[v][3]);
        _MM_TRANSPOSE4_PS(r0, r1, r2, r3); /* r0: the lanes before x (leaf_vertex4) */
        _mm_store_ps(q->c[v][0], r1);
        _mm_store_ps(q->c[v][1], r2);
        _mm_store_ps(q->c[v][2], r3);
    }
}

/* Triangles k + lane[j] (j = 0..3) into q, lane j for triangle k + lane[j]. */
CBVH_KERNEL void leaf_gather4(const void *restrict tris, const int tri_enc, const void *restrict verts,
                              const int vert_enc, const float *restrict grid_origin,
                              const float *restrict grid_scale, uint32_t k, const uint32_t lane[4],
                              struct leaf_quad *restrict q)
{
    uint32_t idx[3][4];
    CBVH_UNROLL(4)
    for (uint32_t j = 0; j < 4; j++) {
        uint32_t t[3];
        cbvh_indices_decode(tris, tri_enc, k + lane[j], t);
        idx[0][j] = t[0];
        idx[1][j] = t[1];
        idx[2][j] = t[2];
    }
    leaf_gather4_vertices(verts, vert_enc, grid_origin, grid_scale, idx, q);
}

#if defined(__AVX2__)
/* The LOCAL8 indices of a group of four (format.h: blocks of 8 triangles, a u32 base and 3 offset bytes a
 * triangle) by byte shuffles rather than a block address, a base and three byte loads a lane. The group
 * of n (1..4) triangles from k starts at slot r = k % 8 of its block, and its lanes past slot 7 are the
 * next block's first slots. Two 16-byte loads hold every offset it needs: `lo`, bytes 3 m to 3 m + 15 of
 * the block (m = min(r, 4): slots r to min(r + 3, 7), and never past the block's 28 bytes), and `hi`,
 * the next block's bytes 0 to 15 (slots 0 to 3) when the group reaches it, else the block's own (then
 * unused, and never past the section). Table entry [r][n - 1] gives, for each vertex v, the shuffle
 * moving lane j's offset byte from `lo` (lo[v]) or `hi` (hi[v]) into byte 0 of lane j (0x80: zero), and
 * `second`, all ones in the lanes from the next block, which take its base. Lanes past n repeat lane 0
 * (leaf_group), as the shuffles say. */
#define L8_LANE(n, j) ((j) < (n) ? (j) : 0)
#define L8_SLOT(r, n, j) ((r) + L8_LANE(n, j))
#define L8_SECOND(r, n, j) (L8_SLOT(r, n, j) >= 8)
#define L8_LO_BYTE(r, n, v, j)                                                                               \
    (L8_SECOND(r, n, j) ? 0x80 : 4 + 3 * (L8_SLOT(r, n, j) - ((r) < 4 ? (r) : 4)) + (v))
#define L8_HI_BYTE(r, n, v, j) (L8_SECOND(r, n, j) ? 4 + 3 * (L8_SLOT(r, n, j) - 8) + (v) : 0x80)
#define L8_LO(r, n, v)                                                                                       \
    {                                                                                                        \
        L8_LO_BYTE(r, n, v, 0), 0x80, 0x80, 0x80, L8_LO_BYTE(r, n, v, 1), 0x80, 0x80, 0x80,                  \
            L8_LO_BYTE(r, n, v, 2), 0x80, 0x80, 0x80, L8_LO_BYTE(r, n, v, 3), 0x80, 0x80, 0x80               \
    }
#define L8_HI(r, n, v)                                                                                       \
    {                                                                                                        \
        L8_HI_BYTE(r, n, v, 0), 0x80, 0x80, 0x80, L8_HI_BYTE(r, n, v, 1), 0x80, 0x80, 0x80,                  \
            L8_HI_BYTE(r, n, v, 2), 0x80, 0x80, 0x80, L8_HI_BYTE(r, n, v, 3), 0x80, 0x80, 0x80               \
    }
#define L8_MASK(r, n, j) (L8_SECOND(r, n, j) ? 0xFF : 0)
#define L8_SECOND_LANES(r, n)                                                                                \
    {                                                                                                        \
        L8_MASK(r, n, 0), L8_MASK(r, n, 0), L8_MASK(r, n, 0), L8_MASK(r, n, 0), L8_MASK(r, n, 1),            \
            L8_MASK(r, n, 1), L8_MASK(r, n, 1), L8_MASK(r, n, 1), L8_MASK(r, n, 2), L8_MASK(r, n, 2),        \
            L8_MASK(r, n, 2), L8_MASK(r, n, 2), L8_MASK(r, n, 3), L8_MASK(r, n, 3), L8_MASK(r, n, 3),        \
            L8_MASK(r, n, 3)                                                                                 \
    }
#define L8_ENTRY(r, n)                                                                                       \
    {                                                                                                        \
        {L8_LO(r, n, 0), L8_LO(r, n, 1), L8_LO(r, n, 2)}, {L8_HI(r, n, 0), L8_HI(r, n, 1), L8_HI(r, n, 2)},  \
            L8_SECOND_LANES(r, n)                                                                            \
    }
#define L8_ROW(r)                                                                                            \
    {                                                                                                        \
        L8_ENTRY(r, 1), L8_ENTRY(r, 2), L8_ENTRY(r, 3), L8_ENTRY(r, 4)                                       \
    }
struct leaf_local8_shuffle {
    _Alignas(16) uint8_t lo[3][16];
    _Alignas(16) uint8_t hi[3][16];
    _Alignas(16) uint8_t second[16];
};
static const struct leaf_local8_shuffle leaf_local8_shuffles[CBVH_LOCAL8_BLOCK][4] = {
    L8_ROW(0), L8_ROW(1), L8_ROW(2), L8_ROW(3), L8_ROW(4), L8_ROW(5), L8_ROW(6), L8_ROW(7)};
#undef L8_ROW
#undef L8_ENTRY
#undef L8_SECOND_LANES
#undef L8_MASK
#undef L8_HI
#undef L8_LO
#undef L8_HI_BYTE
#undef L8_LO_BYTE
#undef L8_SECOND
#undef L8_SLOT
#undef L8_LANE

/* idx[v][j]: vertex v of triangle k + j (j < n), of triangle k past n, from LOCAL8 triangles (above). */
CBVH_KERNEL void leaf_local8_indices4(const void *restrict tris, uint32_t k, uint32_t n, uint32_t idx[3][4])
{
    const uint32_t r = k % CBVH_LOCAL8_BLOCK, m = r < 4u ? r : 4u;
    const uint8_t *block = (const uint8_t *)tris + (size_t)CBVH_LOCAL8_BLOCK_SIZE * (k / CBVH_LOCAL8_BLOCK);
    const uint8_t *next = block + CBVH_LOCAL8_BLOCK_SIZE * (size_t)(r + n > CBVH_LOCAL8_BLOCK);
    const struct leaf_local8_shuffle *sh = &leaf_local8_shuffles[r][n - 1u];
    const __m128i lo = _mm_loadu_si128((const __m128i *)(const void *)(block + 3u * m));
    const __m128i hi = _mm_loadu_si128((const __m128i *)(const void *)next);
    const __m128i base = _mm_blendv_epi8(_mm_set1_epi32(*(const int32_t *)(const void *)block),
                                         _mm_set1_epi32(*(const int32_t *)(const void *)next),
                                         _mm_load_si128((const __m128i *)(const void *)sh->second));
    CBVH_UNROLL(3)
    for (uint32_t v = 0; v < 3; v++) {
        const __m128i lo_bytes =
            _mm_shuffle_epi8(lo, _mm_load_si128((const __m128i *)(const void *)sh->lo[v]));
        const __m128i hi_bytes =
            _mm_shuffle_epi8(hi, _mm_load_si128((const __m128i *)(const void *)sh->hi[v]));
        _mm_storeu_si128((__m128i *)(void *)idx[v], _mm_add_epi32(base, _mm_or_si128(lo_bytes, hi_bytes)));
    }
}
#endif

/* Triangles k + lane[j] of a group of n (1..4) from triangle k: lanes past the group's end repeat its first
 * triangle (leaf_gather4), and `kept` masks them out of the answers. */
CBVH_KERNEL void leaf_group(uint32_t n, uint32_t lane[4], uint32_t *kept)
{
    for (uint32_t j = 0; j < 4; j++) /* j, or 0 past the end: masks, not branches on n */
        lane[j] = j & (0u - (uint32_t)(j < n));
    *kept = (1u << n) - 1u;
}

/* The groups of four in which a leaf's cooked triangles [first, end) are tested: group k (from
 * leaf_groups_begin, stepping by 4 while k < end) holds triangles k + j in its lanes j of *mask. A file with
 * expanded triangles (cbvh_file_expand_triangles) has them stored four by four from triangle 0, read in
 * place: k is a multiple of 4 and the lanes outside the leaf are masked. Otherwise the groups start at
 * `first` and are gathered into `scratch`. */

static inline uint32_t leaf_groups_begin(const struct leaf_quad *quads, uint32_t first)
{
    return quads ? first & ~3u : first;
}

/* Group k of a leaf [first, end) (see above): quads is the file's expanded triangles or NULL; the other
 * arguments are leaf_gather4's, read once per leaf by the caller. */
CBVH_KERNEL const struct leaf_quad *
leaf_group_load(const struct leaf_quad *restrict quads, const void *restrict tris, const int tri_enc,
                const void *restrict verts, const int vert_enc, const float *restrict grid_origin,
                const float *restrict grid_scale, uint32_t first, uint32_t end, uint32_t k,
                struct leaf_quad *restrict scratch, uint32_t *mask)
{
    const uint32_t past = end - k < 4u ? end - k : 4u; /* the lanes before the leaf's end */
    if (quads) {
        const uint32_t before = first > k ? first - k : 0u; /* the lanes before its start */
        *mask = ((1u << past) - 1u) & ~((1u << before) - 1u);
        return quads + k / 4u;
    }
    uint32_t lane[4];
    leaf_group(past, lane, mask);
#if defined(__AVX2__)
    if (tri_enc == CBVH_TRIS_LOCAL8) {
        uint32_t idx[3][4];
        leaf_local8_indices4(tris, k, past, idx);
        leaf_gather4_vertices(verts, vert_enc, grid_origin, grid_scale, idx, scratch);
        return scratch;
    }
#endif
    leaf_gather4(tris, tri_enc, verts, vert_enc, grid_origin, grid_scale, k, lane, scratch);
    return scratch;
}

/* A group of CBVH_LANES triangles for the ray filter: lanes 4 h .. 4 h + 3 in quad[h], triangles k + j
 * (leaf_group_lanes) for the lanes j of mask. */
#define CBVH_LEAF_QUADS (CBVH_LANES / 4u)
struct leaf_group {
    const struct leaf_quad *quad[CBVH_LEAF_QUADS];
    uint32_t mask;
};

/* At most this many groups a leaf: read in place, the first starts up to 3 triangles before the leaf. */
#define CBVH_LEAF_GROUPS ((CBVH_MAX_LEAF_SIZE + 3u + CBVH_LANES - 1u) / CBVH_LANES)

/* Group k of a leaf [first, end) in CBVH_LANES lanes, k stepping by CBVH_LANES from leaf_groups_begin:
 * leaf_group_load on each quad of it (scratch: one quad each), the quads past the leaf's end not read
 * (the first stands in for them, its lanes masked). */
CBVH_KERNEL void leaf_group_lanes(const struct leaf_quad *restrict quads, const void *restrict tris,
                                  const int tri_enc, const void *restrict verts, const int vert_enc,
                                  const float *restrict grid_origin, const float *restrict grid_scale,
                                  uint32_t first, uint32_t end, uint32_t k,
                                  struct leaf_quad scratch[CBVH_LEAF_QUADS], struct leaf_group *restrict g)
{
    uint32_t mask;
    g->quad[0] = leaf_group_load(quads, tris, tri_enc, verts, vert_enc, grid_origin, grid_scale, first, end,
                                 k, &scratch[0], &mask);
    g->mask = mask;
    for (uint32_t h = 1; h < CBVH_LEAF_QUADS; h++) {
        g->quad[h] = g->quad[0];
        if (end - k > 4u * h) {
            g->quad[h] = leaf_group_load(quads, tris, tri_enc, verts, vert_enc, grid_origin, grid_scale,
                                         first, end, k + 4u * h, &scratch[h], &mask);
            g->mask |= mask << 4u * h;
        }
    }
}

/* Of the lanes of a group, those whose hit t, were the exact test (cbvh_ray_triangle_decide) to
 * accept them, would be outside [tmin, tmax] for sure: the bits of `candidates` (lanes whose float edge
 * functions u, v, w are finite, of one sign, with sum det) that it can rule out. px, py, pz: the sheared
 * vertices (the ray along +z, pz the kz coordinate relative to the origin) as leaf_reject_lanes has them.
 *
 * The exact test's t is the double plane t clamped into the span of the vertices' projections on the
 * ray and into the line's interval in the triangle's bounding box, then rounded to float. Here t is
 * Woop's interpolation (u z0 + v z1 + w z2) / det / dir[kz] in float. With R the largest |sheared x or
 * y| of the lane's vertices, Zspan and Zabs the span and the largest |z|, first order in the float
 * rounding unit 2^-24: the sheared coordinates are off by at most 2^-23 (R + 2 Zabs), each edge function
 * by at most E = 2^-20 R (R + Zabs). A lane whose |u|, |v|, |w| all exceed 4 E therefore has exact edge
 * functions of the same signs: the line crosses the triangle's plane strictly inside the triangle, at a
 * t* inside both clamping intervals, so the exact test's t is t* up to its double rounding. The float
 * barycentrics u / det... are then off by at most 6 E / |det| together, which moves the interpolated z by
 * half that times Zspan; the rounding of the z values, of the interpolation and of the division by
 * dir[kz] add 9 2^-24 Zabs. The margin is four times that bound, in t (times 1/|dir[kz]|), plus FLT_MIN
 * (a t just below 0 that rounds to -0). A lane nearer an edge, or with a non-finite estimate, is left to
 * the exact test. Returns the ruled-out bits; *within receives those of `candidates` whose t the exact
 * test would find inside [tmin, tmax] for sure (the same bound: t* is then more than 3/4 of the margin
 * inside the range, and so is its rounding to float), the lanes it would accept. */
CBVH_KERNEL uint32_t leaf_outside_lanes(const struct cbvh_ray_shear *restrict s, const cbvh_lanes px[3],
                                        const cbvh_lanes py[3], const cbvh_lanes pz[3], cbvh_lanes u,
                                        cbvh_lanes v, cbvh_lanes w, cbvh_lanes det, uint32_t candidates,
                                        float tmin, float tmax, uint32_t *restrict within)
{
    const cbvh_lanes sign = lanes_set1(-0.0f), sz = lanes_set1(s->sz);
    const cbvh_lanes z = lanes_add(lanes_add(lanes_mul(u, pz[0]), lanes_mul(v, pz[1])), lanes_mul(w, pz[2]));
    const cbvh_lanes t = lanes_mul(lanes_div(z, det), sz);
    cbvh_lanes r = lanes_zero();
    CBVH_UNROLL(3)
    for (int k = 0; k < 3; k++)
        r = lanes_max(r, lanes_max(lanes_andnot(sign, px[k]), lanes_andnot(sign, py[k])));
    const cbvh_lanes zmin = lanes_min(lanes_min(pz[0], pz[1]), pz[2]);
    const cbvh_lanes zmax = lanes_max(lanes_max(pz[0], pz[1]), pz[2]);
    const cbvh_lanes zabs = lanes_max(zmax, lanes_sub(lanes_zero(), zmin));
    const cbvh_lanes edge_error = lanes_mul(r, lanes_add(r, zabs)); /* E / 2^-20 */
    const cbvh_lanes smallest =
        lanes_min(lanes_min(lanes_andnot(sign, u), lanes_andnot(sign, v)), lanes_andnot(sign, w));
    const cbvh_lanes inside = lanes_gt(smallest, lanes_mul(lanes_set1(0x1p-18f), edge_error));
    const cbvh_lanes spread =
        lanes_div(lanes_mul(lanes_sub(zmax, zmin), edge_error), lanes_andnot(sign, det));
    const cbvh_lanes margin =
        lanes_add(lanes_mul(lanes_andnot(sign, sz), lanes_add(lanes_mul(lanes_set1(0x1p-16f), spread),
                                                              lanes_mul(lanes_set1(0x1p-18f), zabs))),
                  lanes_set1(FLT_MIN));
    const cbvh_lanes low = lanes_sub(t, margin), high = lanes_add(t, margin);
    const cbvh_lanes lo = lanes_set1(tmin), hi = lanes_set1(tmax);
    const cbvh_lanes below = lanes_lt(high, lo), above = lanes_gt(low, hi);
    const cbvh_lanes in_range = lanes_and(lanes_ge(low, lo), lanes_le(high, hi));
    *within = (uint32_t)lanes_bits(lanes_and(inside, in_range)) & candidates;
    return (uint32_t)lanes_bits(lanes_and(inside, lanes_or(below, above))) & candidates;
}

/* The first test of cbvh_ray_triangle (ray_triangle.h) on the CBVH_LANES triangles of g at once, lane for
 * lane the same float operations in the same order (the build contracts no multiply-add): the vertices
 * relative to the origin, sheared, then the three edge functions, left in edge[e][j] (function e of lane j).
 * Returns the bits of the lanes that test rejects for sure (finite edge functions of both signs) and, when
 * `ranged`, of those it keeps whose t would be outside [tmin, tmax] for sure (leaf_outside_lanes); the
 * exact test of every other lane (leaf_lane_test) then decides it exactly as the scalar test would alone,
 * so answers are the same with or without this filter. *within: when ranged, the lanes the exact test
 * would accept for sure (leaf_outside_lanes), else 0; an occlusion query without a hit filter needs no
 * more of them. Callers range the leaves whose box holds the ray's start (its entry is tmin), where the
 * line crosses triangles behind the start or, from a surface, the start's own (elsewhere it costs more
 * than it saves: Wuson incoherent rays -4%, shadow rays from the surface +5%), and every leaf of an
 * occlusion query, where a lane it accepts saves the exact test and ends the walk. */
CBVH_KERNEL uint32_t leaf_reject_lanes(const struct cbvh_ray_shear *restrict s,
                                       const struct leaf_group *restrict g, const int ranged, float tmin,
                                       float tmax, float edge[3][CBVH_LANES], uint32_t *restrict within)
{
    const uint32_t kx = s->kx, ky = s->ky, kz = s->kz;
    const cbvh_lanes sx = lanes_set1(s->sx), sy = lanes_set1(s->sy);
    const cbvh_lanes ox = lanes_set1(s->org[kx]), oy = lanes_set1(s->org[ky]), oz = lanes_set1(s->org[kz]);
    const struct leaf_quad *restrict lo = g->quad[0], *restrict hi = g->quad[CBVH_LEAF_QUADS - 1u];
    cbvh_lanes px[3], py[3], pz[3];
    (void)hi;
    CBVH_UNROLL(3)
    for (int v = 0; v < 3; v++) {
        pz[v] = lanes_sub(lanes_load_halves(lo->c[v][kz], hi->c[v][kz]), oz);
        px[v] = lanes_sub(lanes_sub(lanes_load_halves(lo->c[v][kx], hi->c[v][kx]), ox), lanes_mul(sx, pz[v]));
        py[v] = lanes_sub(lanes_sub(lanes_load_halves(lo->c[v][ky], hi->c[v][ky]), oy), lanes_mul(sy, pz[v]));
    }
    /* u = cx*by - cy*bx, v = ax*cy - ay*cx, w = bx*ay - by*ax (a, b, c = vertices 0, 1, 2) */
    const cbvh_lanes u = lanes_sub(lanes_mul(px[2], py[1]), lanes_mul(py[2], px[1]));
    const cbvh_lanes v = lanes_sub(lanes_mul(px[0], py[2]), lanes_mul(py[0], px[2]));
    const cbvh_lanes w = lanes_sub(lanes_mul(px[1], py[0]), lanes_mul(py[1], px[0]));
    lanes_store(edge[0], u);
    lanes_store(edge[1], v);
    lanes_store(edge[2], w);
    const cbvh_lanes zero = lanes_zero();
    const cbvh_lanes sum = lanes_add(lanes_add(u, v), w);
    const cbvh_lanes abs_sum = lanes_andnot(lanes_set1(-0.0f), sum);
    const cbvh_lanes finite =
        lanes_le(abs_sum, lanes_set1(FLT_MAX)); /* false for NaN, as fabsf(..) <= FLT_MAX */
    const cbvh_lanes negative = lanes_or(lanes_or(lanes_lt(u, zero), lanes_lt(v, zero)), lanes_lt(w, zero));
    const cbvh_lanes positive = lanes_or(lanes_or(lanes_gt(u, zero), lanes_gt(v, zero)), lanes_gt(w, zero));
    const uint32_t mixed = (uint32_t)lanes_bits(lanes_and(finite, lanes_and(negative, positive)));
    *within = 0;
    if (!ranged)
        return mixed;
    const uint32_t candidates = (uint32_t)lanes_bits(finite) & ~mixed;
    return candidates
               ? mixed | leaf_outside_lanes(s, px, py, pz, u, v, w, sum, candidates, tmin, tmax, within)
               : mixed;
}

/* The exact test of lane j of g, which leaf_reject_lanes kept: cbvh_ray_triangle_decide (ray_triangle.h)
 * on the lane's vertices and edge functions as the filter left them, the floats the scalar test computes.
 * Arguments and result as for cbvh_ray_triangle. */
CBVH_KERNEL int leaf_lane_test(const struct cbvh_ray_shear *restrict s, const struct leaf_group *restrict g,
                               const float edge[3][CBVH_LANES], uint32_t j, float tmin, float tmax,
                               const int want_uv, float *t, float *u, float *v)
{
    const struct leaf_quad *restrict q = g->quad[j / 4u];
    const uint32_t i = j % 4u;
    const cbvh_v3 vert[3] = {v3(q->c[0][0][i], q->c[0][1][i], q->c[0][2][i]),
                             v3(q->c[1][0][i], q->c[1][1][i], q->c[1][2][i]),
                             v3(q->c[2][0][i], q->c[2][1][i], q->c[2][2][i])};
    return cbvh_ray_triangle_decide(s, vert, edge[0][j], edge[1][j], edge[2][j], tmin, tmax, want_uv, t, u,
                                    v);
}
#endif

/* Tests the leaf's triangles [first, first+count) against the ray. Any-hit:
 * returns 1 at the first hit. Closest-hit: updates best and *tmax (the
 * closest hit so far; hits at t == *tmax still compete by index), returns 0,
 * or 1 when a query's filter stopped the walk (the ray's gate, leaf_take).
 * *tested receives the number of triangles tested. The file's arrays and
 * grid are read into locals once per leaf. */
CBVH_KERNEL int leaf_loop(const struct cbvh_file *restrict f, uint32_t first, uint32_t count,
                          const struct cbvh_ray_shear *restrict s, const struct cbvh_hit_gate *gate,
                          float tmin, float *restrict tmax, struct cbvh_best_hit *restrict best,
                          const int any, const int scalar, const int near, const int tri_enc,
                          const int vert_enc)
{
    const void *restrict tris = f->triangles;
    const void *restrict verts = f->vertices;
    const float origin[3] = {f->grid_origin[0], f->grid_origin[1], f->grid_origin[2]};
    const float scale[3] = {f->grid_scale[0], f->grid_scale[1], f->grid_scale[2]};
    float best_t = *tmax;
    float t, u = 0.0f, v = 0.0f, p[3][3];
    /* an occlusion query without a filter never looks at the barycentrics, nor at t once it is in range */
    const int want_uv = !any || gate, occlusion = any && !gate;
#ifdef CBVH_HAVE_SIMD
    /* CBVH_LANES triangles at a time through the SIMD filter; the scalar test on the lanes it keeps, in
     * order. */
    if (!scalar && count > 1) {
        const struct leaf_quad *restrict quads = (const struct leaf_quad *)f->quads;
        const uint32_t end = first + count;
        for (uint32_t k = leaf_groups_begin(quads, first); k < end; k += CBVH_LANES) {
            struct leaf_quad scratch[CBVH_LEAF_QUADS];
            struct leaf_group g;
            leaf_group_lanes(quads, tris, tri_enc, verts, vert_enc, origin, scale, first, end, k, scratch,
                             &g);
            float edge[3][CBVH_LANES];
            uint32_t within;
            const uint32_t rejected =
                leaf_reject_lanes(s, &g, near || occlusion, tmin, best_t, edge, &within);
            if (occlusion && (within & g.mask))
                return 1;
            /* the lanes the filter keeps, lowest first */
            for (uint32_t kept = ~rejected & g.mask; kept; kept &= kept - 1u) {
                const uint32_t j = lanes_lowest(kept);
                if (leaf_lane_test(s, &g, edge, j, tmin, best_t, want_uv, &t, &u, &v) &&
                    leaf_take(f, gate, k + j, t, u, v, any, &best_t, best))
                    return 1;
            }
        }
        *tmax = best_t;
        return 0;
    }
#else
    (void)scalar;
    (void)occlusion;
#endif
    for (uint32_t k = first; k < first + count; k++) {
        leaf_triangle(tris, tri_enc, verts, vert_enc, origin, scale, k, p);
        if (cbvh_ray_triangle(s, p[0], p[1], p[2], tmin, best_t, want_uv, &t, &u, &v) &&
            leaf_take(f, gate, k, t, u, v, any, &best_t, best))
            return 1;
    }
    *tmax = best_t;
    return 0;
}

/* The leaf step of every single-ray walk: the leaf's cooked triangles
 * [first, first + count). Any-hit: returns 1 when the leaf occludes the ray.
 * Closest-hit: updates best and *tmax, returns 0 (1: a filter stopped the walk). The encodings the cooker
 * writes for lossless files (LOCAL8 or U16 indices, float vertices) get
 * loops of their own (one switch per leaf, not per triangle); the others go
 * through the generic one, which keeps every walk instance small. */
CBVH_KERNEL int cbvh_leaf_visit(const struct cbvh_file *restrict f, uint32_t first, uint32_t count,
                                const struct cbvh_ray_ctx *ray, const int any, const int scalar,
                                const int near, float *restrict tmax, struct cbvh_best_hit *restrict best)
{
    const struct cbvh_ray_shear *s = &ray->shear;
    const float tmin = ray->tmin;
    switch (f->triangle_encoding << 1 | f->vertex_encoding) {
    case CBVH_TRIS_LOCAL8 << 1 | CBVH_VERTS_F32:
        return leaf_loop(f, first, count, s, ray->gate, tmin, tmax, best, any, scalar, near, CBVH_TRIS_LOCAL8,
                         CBVH_VERTS_F32);
    case CBVH_TRIS_U16 << 1 | CBVH_VERTS_F32:
        return leaf_loop(f, first, count, s, ray->gate, tmin, tmax, best, any, scalar, near, CBVH_TRIS_U16,
                         CBVH_VERTS_F32);
    default:
        return leaf_loop(f, first, count, s, ray->gate, tmin, tmax, best, any, scalar, near,
                         (int)f->triangle_encoding, (int)f->vertex_encoding);
    }
}

/* Adds a walk's counters to the caller's stats. */
static inline void cbvh_stats_add(cbvh_query_stats *stats, uint64_t visited, uint64_t tested)
{
    stats->nodes_visited += visited;
    stats->triangles_tested += tested;
}

#endif
