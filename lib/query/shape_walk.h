/* shape_walk.h: sweeps' and overlaps' node and leaf tests for the walk skeleton (walk.h). */
#ifndef CBVH_QUERY_SHAPE_WALK_H
#define CBVH_QUERY_SHAPE_WALK_H

#ifdef CBVH_HAVE_SIMD
#include <emmintrin.h>
#endif

#include "layout/tree.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"

/* 1 when the walk enters the box of grid coordinates q (cbvh_tree_box_coord's order: qmin x, y, z, qmax
 * x, y, z), with *entry its key for the walk's limit (below). */
typedef int (*cbvh_shape_enter_fn)(void *query, const uint32_t q[6], float *entry);
/* The leaf's cooked triangles [first, first + count). Returns 1 to end the walk. */
typedef int (*cbvh_shape_leaf_fn)(void *query, uint32_t first, uint32_t count);
/* `enter` on the four slots of wide node `node` at once: bit s when the walk enters slot s's box (used or
 * not: the walk masks the unused), with entry[s] its key. */
typedef uint32_t (*cbvh_shape_enter4_fn)(void *query, const uint8_t *node, float entry[4]);

/* A box as ranges of grid coordinates, lo <= q <= hi per axis (an overlap's region: overlap.c): a node box
 * meets it when on every axis its min coordinate is at most hi and its max at least lo. The walk tests it
 * itself, four wide slots at once with SIMD; `enter` must give the same answers (cbvh_grid_range_meets). */
struct cbvh_grid_range {
    int32_t lo[3], hi[3];
};

static inline int cbvh_grid_range_meets(const struct cbvh_grid_range *g, const uint32_t q[6])
{
    return ((int32_t)q[0] <= g->hi[0]) & ((int32_t)q[1] <= g->hi[1]) & ((int32_t)q[2] <= g->hi[2]) &
           ((int32_t)q[3] >= g->lo[0]) & ((int32_t)q[4] >= g->lo[1]) & ((int32_t)q[5] >= g->lo[2]);
}

/* 1 when no node box can meet the range: a coordinate at most -1, or at least CBVH_Q_MAX + 1. */
static inline int cbvh_grid_range_empty(const struct cbvh_grid_range *g)
{
    const int32_t top = (int32_t)CBVH_Q_MAX;
    return (g->hi[0] < 0) | (g->hi[1] < 0) | (g->hi[2] < 0) | (g->lo[0] > top) | (g->lo[1] > top) |
           (g->lo[2] > top);
}

/* The grid coordinates of box `box` in cbvh_tree_box_coord's order. */
static inline void cbvh_shape_box_coords(const struct cbvh_file *f, const uint32_t layout, uint32_t box,
                                         uint32_t q[6])
{
    q[0] = cbvh_tree_box_coord(f, layout, box, 0);
    q[1] = cbvh_tree_box_coord(f, layout, box, 1);
    q[2] = cbvh_tree_box_coord(f, layout, box, 2);
    q[3] = cbvh_tree_box_coord(f, layout, box, 3);
    q[4] = cbvh_tree_box_coord(f, layout, box, 4);
    q[5] = cbvh_tree_box_coord(f, layout, box, 5);
}

#ifdef CBVH_HAVE_SIMD
/* The grid coordinates of axis a's (0, 1, 2) min and max planes of the four slots of wide node `node` (used
 * or not), unsigned 16-bit in the low four lanes: a node's plane k of all four slots is one 8-byte load
 * (layout/wide4.h). */
CBVH_FORCE_INLINE void cbvh_w4_grid_planes4(const uint8_t *node, uint32_t a, __m128i *qmin, __m128i *qmax)
{
    *qmin = _mm_loadl_epi64((const __m128i *)(const void *)(node + cbvh_w4_plane_offset(a, 0)));
    *qmax = _mm_loadl_epi64((const __m128i *)(const void *)(node + cbvh_w4_plane_offset(3u + a, 0)));
}

/* A non-empty grid range as the four-slot test reads it: per axis, lo and hi (clamped into 16 bits, which
 * changes no answer once the range is not empty) in every 16-bit lane. */
struct cbvh_grid_range4 {
    __m128i lo[3], hi[3];
};

static inline void cbvh_grid_range4_of(const struct cbvh_grid_range *g, struct cbvh_grid_range4 *w)
{
    for (int a = 0; a < 3; a++) {
        const int32_t hi = g->hi[a] > (int32_t)CBVH_Q_MAX ? (int32_t)CBVH_Q_MAX : g->hi[a];
        w->lo[a] = _mm_set1_epi16((short)(uint16_t)g->lo[a]);
        w->hi[a] = _mm_set1_epi16((short)(uint16_t)hi);
    }
}

/* cbvh_grid_range_meets on the four slots of wide node `node` at once: bit s for slot s (used or not).
 * x <= y for unsigned 16-bit x, y exactly when the saturated x - y is 0. */
static inline uint32_t cbvh_grid_range4_hits(const uint8_t *node, const struct cbvh_grid_range4 *w)
{
    const __m128i zero = _mm_setzero_si128();
    __m128i in = _mm_set1_epi16(-1);
    for (uint32_t a = 0; a < 3; a++) {
        __m128i qmin, qmax;
        cbvh_w4_grid_planes4(node, a, &qmin, &qmax);
        in = _mm_and_si128(in, _mm_cmpeq_epi16(_mm_subs_epu16(qmin, w->hi[a]), zero));
        in = _mm_and_si128(in, _mm_cmpeq_epi16(_mm_subs_epu16(w->lo[a], qmax), zero));
    }
    return (uint32_t)_mm_movemask_epi8(_mm_packs_epi16(in, in)) & 0xFu;
}
#endif

#ifdef CBVH_HAVE_SIMD
/* The planes of axis a (0, 1, 2) of the four slots of wide node `node` (used or not), dequantized lane by
 * lane with the same two float operations as cbvh_dequantize, origin and scale the file's grid's on that axis
 * in every lane. */
CBVH_FORCE_INLINE void cbvh_w4_planes4(const uint8_t *node, uint32_t a, __m128 origin, __m128 scale,
                                       __m128 *lo, __m128 *hi)
{
    const __m128i zero = _mm_setzero_si128();
    __m128i qlo, qhi;
    cbvh_w4_grid_planes4(node, a, &qlo, &qhi);
    *lo = _mm_add_ps(origin, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(qlo, zero)), scale));
    *hi = _mm_add_ps(origin, _mm_mul_ps(_mm_cvtepi32_ps(_mm_unpacklo_epi16(qhi, zero)), scale));
}
#endif

/* Children c[0..m) with entry keys e[0..m) (m <= CBVH_TREE_WIDTH) sorted by key, nearest first, ties kept
 * in their order: a sweep's closest contact found early shrinks its reach before the farther subtrees, which
 * the walk then drops unopened (the octant's precomputed order guesses from the boxes' centres only). */
CBVH_KERNEL void cbvh_shape_sort_nearest(cbvh_ref c[CBVH_TREE_WIDTH], float e[CBVH_TREE_WIDTH], uint32_t m)
{
    for (uint32_t k = 1; k < m; k++) {
        const cbvh_ref ck = c[k];
        const float ek = e[k];
        uint32_t j = k;
        for (; j > 0 && e[j - 1] > ek; j--) {
            c[j] = c[j - 1];
            e[j] = e[j - 1];
        }
        c[j] = ck;
        e[j] = ek;
    }
}

/* The children of non-leaf r the walk enters, nearest entry key first (cbvh_shape_sort_nearest) from the
 * order of `octant` (CBVH_NO_OCTANT: slot order, unsorted, for queries whose keys are all 0), with their
 * entry keys: four at once
 * through `enter4` for a wide node when the query has it (and SIMD is built), else box by box through
 * `enter`, without branching on the outcome (hard to predict). Returns how many. */
CBVH_KERNEL uint32_t cbvh_shape_children(const struct cbvh_file *f, const uint32_t layout, cbvh_ref r,
                                         uint32_t octant, cbvh_shape_enter_fn enter,
                                         cbvh_shape_enter4_fn enter4, void *query,
                                         cbvh_ref in[CBVH_TREE_WIDTH], float in_entry[CBVH_TREE_WIDTH])
{
    uint32_t m = 0;
#ifdef CBVH_HAVE_SIMD
    if (enter4 && layout == CBVH_LAYOUT_WIDE4) {
        const uint8_t *node = cbvh_w4_node(f->nodes, r);
        const uint64_t meta = cbvh_w4_meta(node);
        float e[CBVH_W4_WIDTH];
        const uint32_t hits = enter4(query, node, e) & cbvh_w4_used(meta);
        /* the slots entered in the octant's order (order 0: slot order), counted by the table */
        const uint32_t visit =
            cbvh_wide4_visits[octant == CBVH_NO_OCTANT ? 0u : cbvh_w4_order(meta, octant)][hits];
        m = cbvh_w4_popcount(hits);
        for (uint32_t k = 0; k < m; k++) {
            const uint32_t s = visit >> (2u * k) & 3u;
            in[k] = cbvh_w4_child_ref(node, meta, s);
            in_entry[k] = e[s];
        }
        if (octant != CBVH_NO_OCTANT)
            cbvh_shape_sort_nearest(in, in_entry, m);
        return m;
    }
#else
    (void)enter4;
#endif
    struct cbvh_child children[CBVH_TREE_WIDTH];
    const uint32_t n = cbvh_tree_children(f, layout, r, octant, children);
    uint32_t q[6];
    for (uint32_t k = 0; k < n; k++) {
        cbvh_shape_box_coords(f, layout, children[k].box, q);
        in[m] = children[k].ref;
        m += enter(query, q, &in_entry[m]) != 0;
    }
    if (octant != CBVH_NO_OCTANT)
        cbvh_shape_sort_nearest(in, in_entry, m);
    return m;
}

#endif
