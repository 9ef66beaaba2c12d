/* leaf.h: testing one ray against the triangles of a leaf, for closest-hit and any-hit walks. */
#ifndef CBVH_QUERY_LEAF_H
#define CBVH_QUERY_LEAF_H

#include <float.h>

#include "common/file.h"
#include "layout/triangle_encodings.h"
#include "query/lanes.h"
#include "query/ray_setup.h"
#include "query/ray_triangle.h"

/* The lowest set bit of a non-empty 4-bit mask as a slot or lane number. */
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

/* The tie rule every ray path shares, which makes the answer independent of the visit order: nearer, or
 * exactly as near with a lower cooked index. */
static inline int cbvh_hit_better(float t, uint32_t tri, float best_t, uint32_t best_tri)
{
    return t < best_t || (t == best_t && tri < best_tri);
}

/* The culling and hit filter of a query with options (raycast.c fills it in): check returns the
 * cbvh_filter_result for cooked triangle k hit at the kernels' t with barycentrics u, v. */
struct cbvh_hit_gate {
    int (*check)(const struct cbvh_hit_gate *gate, const struct cbvh_file *f, uint32_t k, float t, float u,
                 float v);
    cbvh_cull cull;
    cbvh_hit_filter_fn filter;
    void *user;
    struct cbvh_t_frame t_frame; /* the kernels' t on the caller's ray */
    float dir[3];                /* the ray direction in the mesh's frame */
    int placed;                  /* a query transform: records are rotated into the world by `rotation` */
    double rotation[3][3];
};

/* Triangle k, hit at t in the ray's range: any hit: 1 (the walk stops) unless the gate rejects it; closest
 * hit: the best when better (cbvh_hit_better) and not rejected; 1 when the gate says stop. */
CBVH_KERNEL int leaf_take(const struct cbvh_file *restrict f, const struct cbvh_hit_gate *gate, uint32_t k,
                          float t, float u, float v, const int any, float *restrict best_t,
                          struct cbvh_best_hit *restrict best)
{
    if (!any && !cbvh_hit_better(t, k, *best_t, best->tri))
        return 0;
    const int verdict = gate ? gate->check(gate, f, k, t, u, v) : CBVH_FILTER_ACCEPT;
    if (verdict == CBVH_FILTER_REJECT)
        return 0;
    if (any)
        return 1;
    /* the answer reads k's REMAP entry: requested now, while the walk goes on */
    if (f->remap)
        CBVH_PREFETCH(cbvh_remap_entry(f, k));
    *best_t = t;
    best->tri = k;
    best->t = t;
    best->u = u;
    best->v = v;
    return verdict == CBVH_FILTER_STOP;
}

/* Triangle k's vertex positions (p[v]: vertex v) for the encodings tri_enc and vert_enc. */
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
/* Vertex i as (any, x, y, z): floats by one 16-byte load from 4 bytes before them (CBVH_SECTION_LEAD). */
CBVH_KERNEL __m128 leaf_vertex4(const void *restrict verts, const int vert_enc,
                                const float *restrict grid_origin, const float *restrict grid_scale,
                                uint32_t i)
{
    if (vert_enc == CBVH_VERTS_F32)
        return _mm_loadu_ps((const float *)(const void *)((const uint8_t *)verts + 12u * (size_t)i - 4u));
    const uint16_t *q = (const uint16_t *)verts + 3u * (size_t)i;
    return _mm_setr_ps(0.0f, cbvh_dequantize(q[0], grid_origin[0], grid_scale[0]),
                       cbvh_dequantize(q[1], grid_origin[1], grid_scale[1]),
                       cbvh_dequantize(q[2], grid_origin[2], grid_scale[2]));
}

/* Four triangles gathered for the SIMD filter: c[v][a][j] is axis a of vertex v of lane j's triangle. */
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
/* The LOCAL8 indices (layout/triangle_encodings.h) of eight triangles from k at once, by byte shuffles:
 * triangle k + j's offset bytes are at 4 + 3 (r + j) + v from its block (r = k % 8), 4 more past slot 7,
 * in the next block. Two 16-byte windows hold them (lanes 0-3 and 4-7); entry r has, per vertex v, the
 * shuffle moving each lane's byte into place, and `next`: the lanes that take the next block's base. The
 * caller checks that block exists (leaf_local8_window_fits) and masks lanes past the leaf, whose indices
 * are clamped below the vertex count. */
_Static_assert(CBVH_LOCAL8_BLOCK == 8u && CBVH_LOCAL8_TRIANGLE_BYTES == 3u && CBVH_LOCAL8_OFFSETS_AT == 4u,
               "the windows below are laid out for 8 triangles of 3 offset bytes after a 4-byte base");
#define L8W_NEXT(r, j) ((r) + (j) >= CBVH_LOCAL8_BLOCK)
#define L8W_LANE(r, j, v)                                                                                    \
    CBVH_LOCAL8_TRIANGLE_BYTES *((j) % 4) + (v) + CBVH_LOCAL8_OFFSETS_AT *L8W_NEXT(r, j), 0x80, 0x80, 0x80
#define L8W_SHUFFLE(r, v)                                                                                    \
    {                                                                                                        \
        L8W_LANE(r, 0, v), L8W_LANE(r, 1, v), L8W_LANE(r, 2, v), L8W_LANE(r, 3, v), L8W_LANE(r, 4, v),       \
            L8W_LANE(r, 5, v), L8W_LANE(r, 6, v), L8W_LANE(r, 7, v)                                          \
    }
#define L8W_MASK(r, j)                                                                                       \
    L8W_NEXT(r, j) * 0xFF, L8W_NEXT(r, j) * 0xFF, L8W_NEXT(r, j) * 0xFF, L8W_NEXT(r, j) * 0xFF
#define L8W_ENTRY(r)                                                                                         \
    {                                                                                                        \
        {L8W_SHUFFLE(r, 0), L8W_SHUFFLE(r, 1), L8W_SHUFFLE(r, 2)},                                           \
        {                                                                                                    \
            L8W_MASK(r, 0), L8W_MASK(r, 1), L8W_MASK(r, 2), L8W_MASK(r, 3), L8W_MASK(r, 4), L8W_MASK(r, 5),  \
                L8W_MASK(r, 6), L8W_MASK(r, 7)                                                               \
        }                                                                                                    \
    }
struct leaf_local8_window {
    _Alignas(32) uint8_t shuffle[3][32];
    _Alignas(32) uint8_t next[32];
};
static const struct leaf_local8_window leaf_local8_windows[CBVH_LOCAL8_BLOCK] = {
    L8W_ENTRY(0), L8W_ENTRY(1), L8W_ENTRY(2), L8W_ENTRY(3),
    L8W_ENTRY(4), L8W_ENTRY(5), L8W_ENTRY(6), L8W_ENTRY(7)};
#undef L8W_ENTRY
#undef L8W_MASK
#undef L8W_SHUFFLE
#undef L8W_LANE
#undef L8W_NEXT

/* Whether the windows of a group from k stay in a LOCAL8 section: the block after k's exists. */
static inline int leaf_local8_window_fits(uint32_t triangles, uint32_t k)
{
    return k / CBVH_LOCAL8_BLOCK + 1u < cbvh_local8_blocks(triangles);
}

/* idx[v], lane j: vertex v of triangle k + j; last_vertex: the vertex count - 1 in each lane. */
CBVH_KERNEL void leaf_local8_indices8(const void *restrict tris, uint32_t k, __m256i last_vertex,
                                      __m256i idx[3])
{
    const uint8_t *block = cbvh_local8_block(tris, k);
    const uint8_t *p = cbvh_local8_offsets(block, k % CBVH_LOCAL8_BLOCK);
    const struct leaf_local8_window *w = &leaf_local8_windows[k % CBVH_LOCAL8_BLOCK];
    const uint8_t *high = p + 4u * CBVH_LOCAL8_TRIANGLE_BYTES; /* lanes 4-7's triangles */
    const __m256i src =
        _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128((const __m128i *)(const void *)p)),
                                _mm_loadu_si128((const __m128i *)(const void *)high), 1);
    const __m256i base =
        _mm256_blendv_epi8(_mm256_set1_epi32((int)cbvh_read_u32(block)),
                           _mm256_set1_epi32((int)cbvh_read_u32(block + CBVH_LOCAL8_BLOCK_SIZE)),
                           _mm256_load_si256((const __m256i *)(const void *)w->next));
    CBVH_UNROLL(3)
    for (uint32_t v = 0; v < 3; v++)
        idx[v] = _mm256_min_epu32(
            _mm256_add_epi32(base, _mm256_shuffle_epi8(
                                       src, _mm256_load_si256((const __m256i *)(const void *)w->shuffle[v]))),
            last_vertex);
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

/* Where a leaf's groups start: expanded triangles (cbvh_file_expand_triangles) are read in place, four by
 * four from triangle 0, the lanes outside the leaf masked; else gathered from `first`. */
static inline uint32_t leaf_groups_begin(const struct leaf_quad *quads, uint32_t first)
{
    return quads ? first & ~3u : first;
}

/* Group k of a leaf [first, end), triangles k + j in lanes j of *mask: quads is the file's expanded
 * triangles or NULL (gathered into scratch). */
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
    leaf_gather4(tris, tri_enc, verts, vert_enc, grid_origin, grid_scale, k, lane, scratch);
    return scratch;
}

/* A group of CBVH_LANES triangles for the filter: lanes 4 h .. 4 h + 3 in quad[h], the used ones in mask. */
#define CBVH_LEAF_QUADS (CBVH_LANES / 4u)
struct leaf_group {
    const struct leaf_quad *quad[CBVH_LEAF_QUADS];
    uint32_t mask;
};

/* At most this many groups a leaf: read in place, the first starts up to 3 triangles before the leaf. */
#define CBVH_LEAF_GROUPS ((CBVH_MAX_LEAF_SIZE + 3u + CBVH_LANES - 1u) / CBVH_LANES)

#if defined(__AVX2__)
/* Eight lanes of triangle vertices as rows axis[v][a] (lane j: axis a of vertex idx[v] lane j; lanes 4-7
 * only when `both`), by one 4 x 4 transpose per 128-bit half. With `permute`, each row is first permuted by
 * `order` so the rows come out in the ray's sheared order. */
CBVH_KERNEL void leaf_gather8_axes(const void *restrict verts, const __m256i idx[3], const int both,
                                   const int permute, __m256i order, __m256 axis[3][3])
{
    CBVH_UNROLL(3)
    for (uint32_t v = 0; v < 3; v++) {
        /* each lane's float offset, 3 i (< 2^32), read back to index the loads */
        const __m256i i = idx[v];
        _Alignas(32) uint32_t at[8];
        _mm256_store_si256((__m256i *)(void *)at, _mm256_add_epi32(i, _mm256_add_epi32(i, i)));
        const float *row = (const float *)verts - 1; /* (any, x, y, z): the float before each vertex */
        __m256 r[4];
        CBVH_UNROLL(4)
        for (uint32_t j = 0; j < 4; j++) {
            r[j] = both ? _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(row + at[j])),
                                               _mm_loadu_ps(row + at[j + 4]), 1)
                        : _mm256_broadcast_ps((const __m128 *)(const void *)(row + at[j]));
            if (permute)
                r[j] = _mm256_permutevar_ps(r[j], order);
        }
        const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpacklo_ps(r[2], r[3]);
        const __m256 t2 = _mm256_unpackhi_ps(r[0], r[1]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
        axis[v][0] = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
        axis[v][1] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
        axis[v][2] = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
    }
}
#endif

/* Group k of a leaf [first, end) in CBVH_LANES lanes: leaf_group_load on each quad (the first stands in for
 * those past the end, masked); with AVX2, LOCAL8 and float vertices gathered eight at once. */
CBVH_KERNEL void leaf_group_lanes(const struct cbvh_file *restrict f, const struct leaf_quad *restrict quads,
                                  const int tri_enc, const int vert_enc, const float *restrict grid_origin,
                                  const float *restrict grid_scale, uint32_t first, uint32_t end, uint32_t k,
                                  struct leaf_quad scratch[CBVH_LEAF_QUADS], struct leaf_group *restrict g)
{
    const void *restrict tris = f->triangles, *restrict verts = f->vertices;
#if defined(__AVX2__)
    /* the files' usual encodings: both halves gathered at once */
    if (!quads && tri_enc == CBVH_TRIS_LOCAL8 && vert_enc == CBVH_VERTS_F32 &&
        leaf_local8_window_fits(f->info.triangle_count, k)) {
        const uint32_t n = end - k < CBVH_LANES ? end - k : CBVH_LANES;
        const int both = n > 4u;
        __m256i idx[3];
        leaf_local8_indices8(tris, k, _mm256_set1_epi32((int)(f->info.vertex_count - 1u)), idx);
        __m256 axis[3][3];
        leaf_gather8_axes(verts, idx, both, 0, _mm256_setzero_si256(), axis);
        CBVH_UNROLL(9)
        for (uint32_t c = 0; c < 9; c++) {
            _mm_store_ps(scratch[0].c[c / 3][c % 3], _mm256_castps256_ps128(axis[c / 3][c % 3]));
            if (both)
                _mm_store_ps(scratch[1].c[c / 3][c % 3], _mm256_extractf128_ps(axis[c / 3][c % 3], 1));
        }
        g->quad[0] = &scratch[0];
        g->quad[1] = both ? &scratch[1] : &scratch[0];
        g->mask = (1u << n) - 1u;
        return;
    }
#endif
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

/* Of `candidates` (lanes whose float edge functions u, v, w are finite, of one sign, sum det), the bits
 * whose t the exact test (cbvh_ray_triangle_decide) would find outside [tmin, tmax] for sure; *within: those
 * it would find inside. px, py, pz: the sheared vertices as leaf_reject_rows has them. t is Woop's float
 * interpolation, with a margin docs/EXACTNESS.md derives; lanes near an edge go to the exact test. */
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

/* A group's vertices for the filter: lane j of c[v][a] is axis (kx, ky, kz)[a] of vertex v of triangle j. */
struct leaf_rows {
    cbvh_lanes c[3][3];
};

/* The rows of group g for the ray sheared by s. */
CBVH_KERNEL void leaf_group_rows(const struct cbvh_ray_shear *restrict s, const struct leaf_group *restrict g,
                                 struct leaf_rows *restrict rows)
{
    const uint32_t axis[3] = {s->kx, s->ky, s->kz};
    const struct leaf_quad *restrict lo = g->quad[0], *restrict hi = g->quad[CBVH_LEAF_QUADS - 1u];
    (void)hi;
    CBVH_UNROLL(9)
    for (uint32_t c = 0; c < 9; c++)
        rows->c[c / 3][c % 3] = lanes_load_halves(lo->c[c / 3][axis[c % 3]], hi->c[c / 3][axis[c % 3]]);
}

/* The first test of cbvh_ray_triangle on the CBVH_LANES triangles of rows at once, lane for lane the same
 * float operations (the build contracts no multiply-add), the edge functions left in edge[e][j]. Returns
 * the lanes it rejects for sure and, when `ranged`, those outside [tmin, tmax] for sure
 * (leaf_outside_lanes, which fills *within; else 0); the exact test (leaf_rows_visit) decides every other
 * lane as the scalar test would, so answers do not depend on the filter. */
CBVH_KERNEL uint32_t leaf_reject_rows(const struct cbvh_ray_shear *restrict s,
                                      const struct leaf_rows *restrict rows, const int ranged, float tmin,
                                      float tmax, float edge[3][CBVH_LANES], uint32_t *restrict within)
{
    const cbvh_lanes sx = lanes_set1(s->sx), sy = lanes_set1(s->sy);
    const cbvh_lanes ox = lanes_set1(s->org[s->kx]), oy = lanes_set1(s->org[s->ky]);
    const cbvh_lanes oz = lanes_set1(s->org[s->kz]);
    cbvh_lanes px[3], py[3], pz[3];
    CBVH_UNROLL(3)
    for (int v = 0; v < 3; v++) {
        pz[v] = lanes_sub(rows->c[v][2], oz);
        px[v] = lanes_sub(lanes_sub(rows->c[v][0], ox), lanes_mul(sx, pz[v]));
        py[v] = lanes_sub(lanes_sub(rows->c[v][1], oy), lanes_mul(sy, pz[v]));
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

/* The vertices of lane j of group g, as the filter read them. */
CBVH_KERNEL void leaf_group_vertices(const struct leaf_group *restrict g, uint32_t j, cbvh_v3 vert[3])
{
    const struct leaf_quad *restrict q = g->quad[j / 4u];
    const uint32_t i = j % 4u;
    CBVH_UNROLL(3)
    for (uint32_t c = 0; c < 3; c++)
        vert[c] = v3(q->c[c][0][i], q->c[c][1][i], q->c[c][2][i]);
}

/* Triangles k + j (lanes j of `mask`, their filter rows in rows) against the ray: leaf_reject_rows (`ranged`
 * as it says), then the exact test (cbvh_ray_triangle_decide) on the lanes it keeps, lowest first, each hit
 * offered to leaf_take. Vertices for the exact test: group g's, or (`direct`) the float vertices
 * verts[id[v][j]]. An occlusion (any hit without a gate) also ends at a lane the filter finds within the
 * range. Returns 1 when the ray's walk stops (leaf_take). */
CBVH_KERNEL int leaf_rows_visit(const struct cbvh_file *restrict f, const struct cbvh_ray_shear *restrict s,
                                const struct leaf_rows *restrict rows, const struct leaf_group *restrict g,
                                const int direct, const float *restrict verts,
                                const uint32_t (*id)[CBVH_LANES], uint32_t mask, uint32_t k,
                                const struct cbvh_hit_gate *gate, const int ranged, const int any,
                                const int want_uv, float tmin, float *restrict best_t,
                                struct cbvh_best_hit *restrict best)
{
    float edge[3][CBVH_LANES], t, u, v;
    uint32_t within;
    const uint32_t rejected = leaf_reject_rows(s, rows, ranged, tmin, *best_t, edge, &within);
    if (any && !gate && (within & mask))
        return 1;
    for (uint32_t kept = ~rejected & mask; kept; kept &= kept - 1u) {
        const uint32_t j = lanes_lowest(kept);
        cbvh_v3 vert[3];
        if (direct)
            for (uint32_t c = 0; c < 3; c++)
                vert[c] = v3_from_f(verts + 3u * (size_t)id[c][j]);
        else
            leaf_group_vertices(g, j, vert);
        if (cbvh_ray_triangle_decide(s, vert, edge[0][j], edge[1][j], edge[2][j], tmin, *best_t, want_uv, &t,
                                     &u, &v) &&
            leaf_take(f, gate, k + j, t, u, v, any, best_t, best))
            return 1;
    }
    return 0;
}
#endif

/* The leaf's triangles [first, first + count) against the ray, as cbvh_leaf_visit says; `near`: the leaf's
 * box holds the ray's start (its filter then also tests the range). */
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
    /* CBVH_LANES triangles at a time through the SIMD filter; the exact test on the lanes it keeps */
    if (!scalar && count > 1) {
        const struct leaf_quad *restrict quads = (const struct leaf_quad *)f->quads;
        const uint32_t end = first + count;
#if defined(__AVX2__)
        /* LOCAL8 and float vertices gathered straight into the filter's rows; else through quads */
        const int direct = !quads && tri_enc == CBVH_TRIS_LOCAL8 && vert_enc == CBVH_VERTS_F32 &&
                           leaf_local8_window_fits(f->info.triangle_count, end - 1u);
        const __m256i order = _mm256_setr_epi32(0, 1 + (int)s->kx, 1 + (int)s->ky, 1 + (int)s->kz, 0,
                                                1 + (int)s->kx, 1 + (int)s->ky, 1 + (int)s->kz);
        _Alignas(32) uint32_t id[3][CBVH_LANES];
#else
        const int direct = 0;
        const uint32_t(*id)[CBVH_LANES] = NULL;
#endif
        for (uint32_t k = direct ? first : leaf_groups_begin(quads, first); k < end; k += CBVH_LANES) {
            struct leaf_quad scratch[CBVH_LEAF_QUADS];
            struct leaf_group g;
            struct leaf_rows rows;
            if (direct) {
#if defined(__AVX2__)
                const uint32_t n = end - k < CBVH_LANES ? end - k : CBVH_LANES;
                __m256i idx[3];
                leaf_local8_indices8(tris, k, _mm256_set1_epi32((int)(f->info.vertex_count - 1u)), idx);
                leaf_gather8_axes(verts, idx, n > 4u, 1, order, rows.c);
                CBVH_UNROLL(3)
                for (uint32_t c = 0; c < 3; c++) /* for the exact test of the lanes the filter keeps */
                    _mm256_store_si256((__m256i *)(void *)id[c], idx[c]);
                g.mask = (1u << n) - 1u;
#endif
            } else {
                leaf_group_lanes(f, quads, tri_enc, vert_enc, origin, scale, first, end, k, scratch, &g);
                leaf_group_rows(s, &g, &rows);
            }
            if (leaf_rows_visit(f, s, &rows, &g, direct, (const float *)verts, id, g.mask, k, gate,
                                near || occlusion, any, want_uv, tmin, &best_t, best))
                return 1;
        }
        *tmax = best_t;
        return 0;
    }
#else
    (void)scalar;
    (void)near;
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

/* The leaf step of every single-ray walk: the cooked triangles [first, first + count). Any hit: 1 when the
 * leaf occludes the ray. Closest hit: updates best and *tmax (ties compete by index), returns 0 (1: a
 * filter stopped the walk). The lossless encodings get loops of their own; the others share one. */
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
