/* walk.h: the walk skeleton every tree query takes (single rays, the streams' tails, sweeps, overlaps). */
#ifndef CBVH_QUERY_WALK_H
#define CBVH_QUERY_WALK_H

#ifdef CBVH_HAVE_SIMD
#include <immintrin.h>
#endif

#include "layout/tree.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"
#include "query/shape_walk.h"

/* How a walk orders the children a ray enters. */
enum cbvh_walk_order {
    CBVH_WALK_SORTED,   /* the precomputed order for the ray's octant (the sort byte): no run-time sort */
    CBVH_WALK_UNSORTED, /* stored order */
    CBVH_WALK_DISTANCE  /* by box entry distance, computed at run time */
};

/* A walk's variant: a constant in each instance (raycast_walks.c), which keeps only its own code, but for
 * `scalar` in the wide layout's SSE2 instances (kernel_choice.c), read at run time. */
struct cbvh_walk_mode {
    enum cbvh_walk_order order;
    int any;    /* any hit: stop at the first triangle hit */
    int scalar; /* no SIMD: child boxes one at a time, leaf triangles without the filter */
};

/* Box `box` against the ray: quantized from the file, or float_boxes[6 box ...]. */
CBVH_KERNEL int walk_box_test(const struct cbvh_box_ray *restrict box, const struct cbvh_file *restrict f,
                              const uint32_t layout, const float *restrict float_boxes, uint32_t id,
                              float tmin, float tmax, float *entry)
{
    if (!float_boxes)
        return cbvh_box_ray_test(box, f, layout, id, tmin, tmax, entry);
    const struct cbvh_slab_select s = box->sel;
    const float *b = float_boxes + 6 * (size_t)id;
    return cbvh_slab_test(b[s.near_x], b[s.near_y], b[s.near_z], b[s.far_x], b[s.far_y], b[s.far_z], box->org,
                          box->rcp, tmin, tmax, entry);
}

/* Two hit children in visit order: swapped when the second is nearer by
 * `order` (the sort byte bit of the ray's octant, or the entry distance). */
CBVH_KERNEL uint32_t walk_order_pair(const enum cbvh_walk_order order, int second_first, cbvh_ref a, float ea,
                                     cbvh_ref b, float eb, cbvh_ref out[CBVH_TREE_WIDTH],
                                     float entry[CBVH_TREE_WIDTH])
{
    const int swap = order == CBVH_WALK_SORTED ? second_first : order == CBVH_WALK_DISTANCE ? eb < ea : 0;
    out[0] = swap ? b : a;
    entry[0] = swap ? eb : ea;
    out[1] = swap ? a : b;
    entry[1] = swap ? ea : eb;
    return 2;
}

/* The ray as the wide layout's SIMD box test reads it, set up once per walk (empty without SIMD). The
 * affine test computes a plane's distance as q * a + b, a = scale * rcp, b = (origin - org) * rcp, padded
 * so that it enters every box the exact test enters (docs/EXACTNESS.md gives the bound); a ray it cannot
 * serve takes the exact test (`exact`) on `box`. offset: the byte offsets in a node of the six planes used
 * (near x, y, z, far x, y, z; plane j on axis j % 3). */
struct cbvh_w4_simd_ray {
#ifdef CBVH_HAVE_SIMD
    __m128 a[3], near_b[3], far_b[3]; /* the affine test's, per axis, in all four lanes */
    const struct cbvh_box_ray *box;   /* the exact test's origin, scale, org and rcp */
    __m128 tmin;
    const uint8_t *offset; /* walk_w4_plane_offsets of the ray's octant */
    int exact;
#else
    int unused;
#endif
};

#ifdef CBVH_HAVE_SIMD
/* Lane k of v in all four lanes. */
#define CBVH_LANE(v, k) _mm_shuffle_ps((v), (v), _MM_SHUFFLE(k, k, k, k))

/* Per octant, the byte offsets in a node of the six planes the test uses (struct cbvh_w4_simd_ray). */
#define W4_PLANE_OFFSETS(o)                                                                                  \
    {                                                                                                        \
        CBVH_W4_PLANE_OFFSET(CBVH_SLAB_NEAR(o, 0), 0), CBVH_W4_PLANE_OFFSET(CBVH_SLAB_NEAR(o, 1), 0),        \
            CBVH_W4_PLANE_OFFSET(CBVH_SLAB_NEAR(o, 2), 0),                                                   \
            CBVH_W4_PLANE_OFFSET(3u - CBVH_SLAB_NEAR(o, 0), 0),                                              \
            CBVH_W4_PLANE_OFFSET(5u - CBVH_SLAB_NEAR(o, 1), 0),                                              \
            CBVH_W4_PLANE_OFFSET(7u - CBVH_SLAB_NEAR(o, 2), 0)                                               \
    }
static const uint8_t walk_w4_plane_offsets[8][6] = {
    W4_PLANE_OFFSETS(0u), W4_PLANE_OFFSETS(1u), W4_PLANE_OFFSETS(2u), W4_PLANE_OFFSETS(3u),
    W4_PLANE_OFFSETS(4u), W4_PLANE_OFFSETS(5u), W4_PLANE_OFFSETS(6u), W4_PLANE_OFFSETS(7u)};
#undef W4_PLANE_OFFSETS

/* Sets up w for the ray (origin org, reciprocal rcp, octant) against the grid; `box`: the exact test's box
 * ray, which the caller fills when w->exact is set (box_halve sets it). */
CBVH_KERNEL void walk_w4_simd_ray_init(struct cbvh_w4_simd_ray *w, const struct cbvh_box_ray *restrict box,
                                       const float grid_origin[3], const float grid_scale[3],
                                       const float org_in[3], const float rcp_in[3], uint32_t octant,
                                       uint32_t box_halve, float tmin)
{
    const __m128 origin = cbvh_load3(grid_origin), scale = cbvh_load3(grid_scale);
    const __m128 org = cbvh_load3(org_in), rcp = cbvh_load3(rcp_in);
    const __m128 sign = _mm_set1_ps(-0.0f);
    /* lane 3 is 0 in every input: 0 there too, finite */
    const __m128 span = _mm_mul_ps(_mm_andnot_ps(sign, scale), _mm_set1_ps((float)CBVH_Q_MAX));
    const __m128 reach =
        _mm_max_ps(_mm_andnot_ps(sign, origin), _mm_andnot_ps(sign, _mm_add_ps(origin, span)));
    const __m128 gap = _mm_sub_ps(origin, org);
    const __m128 size =
        _mm_mul_ps(_mm_andnot_ps(sign, rcp), _mm_add_ps(_mm_add_ps(span, reach), _mm_andnot_ps(sign, gap)));
    const __m128 pad = _mm_add_ps(_mm_mul_ps(size, _mm_set1_ps(0x1p-20f)), _mm_set1_ps(0x1p-120f));
    const __m128 a = _mm_mul_ps(scale, rcp), b = _mm_mul_ps(gap, rcp);
    const __m128 near_b = _mm_sub_ps(b, pad), far_b = _mm_add_ps(b, pad);
    /* ordered: NaN (an infinite rcp times 0) fails it */
    w->exact = box_halve || (_mm_movemask_ps(_mm_cmple_ps(size, _mm_set1_ps(0x1p100f))) & 7) != 7;
    w->a[0] = CBVH_LANE(a, 0);
    w->a[1] = CBVH_LANE(a, 1);
    w->a[2] = CBVH_LANE(a, 2);
    w->near_b[0] = CBVH_LANE(near_b, 0);
    w->near_b[1] = CBVH_LANE(near_b, 1);
    w->near_b[2] = CBVH_LANE(near_b, 2);
    w->far_b[0] = CBVH_LANE(far_b, 0);
    w->far_b[1] = CBVH_LANE(far_b, 1);
    w->far_b[2] = CBVH_LANE(far_b, 2);
    w->box = box;
    w->offset = walk_w4_plane_offsets[octant & 7u];
    w->tmin = _mm_set1_ps(tmin);
}

/* q a + b in four lanes: a fused multiply-add where the file is built with FMA (one rounding, within the
 * pad), else the product and the sum. */
#if defined(__FMA__) || (defined(_MSC_VER) && defined(__AVX2__))
#define CBVH_AFFINE4(q, a, b) _mm_fmadd_ps((q), (a), (b))
#else
#define CBVH_AFFINE4(q, a, b) _mm_add_ps(_mm_mul_ps((q), (a)), (b))
#endif

/* Plane j of the four slots (struct cbvh_w4_simd_ray) as grid coordinates, lane s for slot s. */
CBVH_KERNEL __m128 walk_w4_plane_q(const uint8_t *restrict node, const struct cbvh_w4_simd_ray *restrict w,
                                   uint32_t j)
{
    const __m128i q = _mm_loadl_epi64((const __m128i *)(const void *)(node + w->offset[j]));
    return _mm_cvtepi32_ps(_mm_unpacklo_epi16(q, _mm_setzero_si128()));
}

/* Plane j of the four slots as a distance along the ray with the normative arithmetic of ray_box.h:
 * ((origin + (float)q * scale) - org) * rcp. j is a constant at every call. */
CBVH_KERNEL __m128 walk_w4_plane_distance(const uint8_t *restrict node,
                                          const struct cbvh_w4_simd_ray *restrict w, uint32_t j)
{
    const uint32_t a = j % 3u;
    const struct cbvh_box_ray *b = w->box;
    return _mm_mul_ps(_mm_sub_ps(_mm_add_ps(_mm_set1_ps(b->origin[a]), _mm_mul_ps(walk_w4_plane_q(node, w, j),
                                                                                  _mm_set1_ps(b->scale[a]))),
                                 _mm_set1_ps(b->org[a])),
                      _mm_set1_ps(b->rcp[a]));
}

/* The slab test on the four slots at once: the affine form (struct cbvh_w4_simd_ray) where it serves, else
 * ray_box.h's lane for lane (MAXPS and MINPS ignore a NaN distance as its compares do). Returns the hit
 * bits (bit s: slot s) and each slot's entry distance. */
CBVH_KERNEL uint32_t walk_w4_test_sse2(const uint8_t *restrict node,
                                       const struct cbvh_w4_simd_ray *restrict w, float tmax,
                                       float entry[CBVH_W4_WIDTH])
{
    __m128 tnear, tfar;
    if (CBVH_LIKELY(!w->exact)) {
        const __m128 n0 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 0), w->a[0], w->near_b[0]);
        const __m128 n1 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 1), w->a[1], w->near_b[1]);
        const __m128 n2 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 2), w->a[2], w->near_b[2]);
        const __m128 f0 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 3), w->a[0], w->far_b[0]);
        const __m128 f1 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 4), w->a[1], w->far_b[1]);
        const __m128 f2 = CBVH_AFFINE4(walk_w4_plane_q(node, w, 5), w->a[2], w->far_b[2]);
        tnear = _mm_max_ps(_mm_max_ps(n0, n1), _mm_max_ps(n2, w->tmin));
        tfar = _mm_min_ps(_mm_min_ps(f0, f1), _mm_min_ps(f2, _mm_set1_ps(tmax)));
    } else {
        tnear = w->tmin;
        tfar = _mm_set1_ps(tmax);
        tnear = _mm_max_ps(walk_w4_plane_distance(node, w, 0), tnear);
        tnear = _mm_max_ps(walk_w4_plane_distance(node, w, 1), tnear);
        tnear = _mm_max_ps(walk_w4_plane_distance(node, w, 2), tnear);
        tfar = _mm_min_ps(walk_w4_plane_distance(node, w, 3), tfar);
        tfar = _mm_min_ps(walk_w4_plane_distance(node, w, 4), tfar);
        tfar = _mm_min_ps(walk_w4_plane_distance(node, w, 5), tfar);
        tfar = _mm_mul_ps(tfar, _mm_set1_ps(CBVH_BOX_PAD));
    }
    _mm_storeu_ps(entry, tnear);
    return (uint32_t)_mm_movemask_ps(_mm_cmple_ps(tnear, tfar));
}
#endif

/* Requests a wide node's four child nodes (consecutive from its first child) and the first lines of its
 * leaves' triangle entries while its boxes are tested, whichever it holds (a prefetch never faults). A
 * node's leaves hold at most 32 LOCAL8 triangles (140 bytes): three lines hold all but the largest. */
#define CBVH_W4_LEAF_ENTRY_LINES 3u
CBVH_KERNEL void walk_w4_prefetch_children(const struct cbvh_file *restrict f, const uint8_t *restrict node)
{
    /* addresses as integers: the lines past the arrays are no object's */
    const uintptr_t children = (uintptr_t)cbvh_w4_node(f->nodes, cbvh_w4_first_child(node));
    const uintptr_t entries =
        (uintptr_t)cbvh_indices_entry(f->triangles, (int)f->triangle_encoding, cbvh_w4_first_triangle(node));
    CBVH_UNROLL(4)
    for (uintptr_t k = 0; k < CBVH_W4_WIDTH; k++)
        CBVH_PREFETCH((const void *)(children + k * CBVH_W4_NODE_SIZE));
    CBVH_UNROLL(3)
    for (uintptr_t k = 0; k < CBVH_W4_LEAF_ENTRY_LINES; k++)
        CBVH_PREFETCH((const void *)(entries + 64u * k));
}

/* Requests three lines of vertices of the leaf `next` from its first triangle's entry (cbvh_vertex_hint),
 * for meshes with vertices_far; a node next requests triangle 0's, without a branch. */
CBVH_KERNEL void walk_w4_prefetch_leaf_vertices(const struct cbvh_file *restrict f, cbvh_ref next)
{
    const uint32_t k = next & CBVH_W4_FIRST_MASK & (0u - (next >> 31));
    const uintptr_t v =
        (uintptr_t)cbvh_vertex_address(f, cbvh_vertex_hint(f->triangles, (int)f->triangle_encoding, k));
    CBVH_UNROLL(3)
    for (uintptr_t line = 0; line < 3u; line++)
        CBVH_PREFETCH((const void *)(v + 64u * line));
}

/* An entry of a walk's stack: a child still to visit and where the ray enters its box. */
struct cbvh_walk_entry {
    cbvh_ref ref;
    float entry;
};

#ifdef CBVH_HAVE_SIMD
/* Bit s of a 4-bit mask into bit 0 of byte s (the multiplier shifts bit s to bit 8 s, no carries). */
static inline uint32_t walk_w4_bits_to_bytes(uint32_t mask4)
{
    return mask4 * 0x00204081u & 0x01010101u;
}

/* Bytes 0-3 of x into lanes 0-3, zero-extended. */
CBVH_KERNEL __m128i walk_w4_byte_lanes(uint32_t x)
{
#if defined(__AVX2__)
    return _mm_cvtepu8_epi32(_mm_cvtsi32_si128((int)x));
#else
    const __m128i zero = _mm_setzero_si128();
    return _mm_unpacklo_epi16(_mm_unpacklo_epi8(_mm_cvtsi32_si128((int)x), zero), zero);
#endif
}

/* cbvh_w4_child_ref of the four slots at once, lane s for slot s (unused slots: a value to ignore), with no
 * branch on which are leaves: byte s of a count word times 0x01010100 sums the slots before s. */
CBVH_KERNEL __m128i walk_w4_refs(const uint8_t *restrict node, uint64_t meta)
{
    const uint32_t m = (uint32_t)meta;
    uint32_t minus_one = m & 0xFFFFu; /* nibble s (a leaf's count - 1, else 0) into byte s */
    minus_one = (minus_one | minus_one << 8) & 0x00FF00FFu;
    minus_one = (minus_one | minus_one << 4) & 0x0F0F0F0Fu;
    const uint32_t inner = walk_w4_bits_to_bytes(cbvh_w4_internal(meta));
    const uint32_t leaves = walk_w4_bits_to_bytes(cbvh_w4_used(meta) & ~cbvh_w4_internal(meta));
    const uint32_t triangles_before = (minus_one + leaves) * 0x01010100u;
    const uint32_t nodes_before = inner * 0x01010100u;
    const __m128i inner_ref =
        _mm_add_epi32(_mm_set1_epi32((int)cbvh_w4_first_child(node)), walk_w4_byte_lanes(nodes_before));
    const __m128i leaf_ref =
        _mm_or_si128(_mm_add_epi32(_mm_set1_epi32((int)(cbvh_w4_first_triangle(node) | CBVH_W4_LEAF_BIT)),
                                   walk_w4_byte_lanes(triangles_before)),
                     _mm_slli_epi32(walk_w4_byte_lanes(minus_one), CBVH_W4_COUNT_SHIFT));
    /* all ones in the lanes of internal slots: each byte 0 or 0xFF, then 0 or -1 as a lane */
    const __m128i is_inner = _mm_srai_epi32(_mm_slli_epi32(walk_w4_byte_lanes(inner * 0xFFu), 24), 24);
    return _mm_or_si128(_mm_and_si128(is_inner, inner_ref), _mm_andnot_si128(is_inner, leaf_ref));
}

/* The SIMD walks' step down the wide layout, in the node's order for the octant or slot order
 * (cbvh_wide4_descents): the first child the ray enters into *next, the others onto the stack, the last
 * deepest. Three entries are always stored (those above the new top dead): no branch on how many are
 * entered. Returns 0, changing nothing, when none is. *boxes_tested, unless NULL, grows by those tested. */
CBVH_KERNEL int walk_w4_descend(const struct cbvh_file *restrict f, cbvh_ref r,
                                const struct cbvh_w4_simd_ray *restrict w, const int sorted, uint32_t octant,
                                float tmax, struct cbvh_walk_entry *restrict stack, uint32_t *restrict sp,
                                cbvh_ref *restrict next, float *restrict next_entry,
                                uint64_t *restrict boxes_tested)
{
    const uint8_t *restrict node = cbvh_w4_node(f->nodes, r);
    const uint64_t meta = cbvh_w4_meta(node);
    const uint32_t used = cbvh_w4_used(meta);
    _Alignas(16) float e[CBVH_W4_WIDTH];
    walk_w4_prefetch_children(f, node);
    if (boxes_tested)
        *boxes_tested += cbvh_w4_popcount(used);
    const uint32_t hits = walk_w4_test_sse2(node, w, tmax, e) & used;
    if (!hits)
        return 0;
    const uint32_t descent = cbvh_wide4_descents[sorted ? cbvh_w4_order(meta, octant) : 0u][hits];
    const __m128i refs = walk_w4_refs(node, meta);
    struct cbvh_walk_entry *restrict top = stack + *sp;
#if defined(__AVX2__)
    /* slots in descent order by one permutation each of the references and the entry distances */
    const __m128i lanes = _mm_cvtepu8_epi32(_mm_cvtsi32_si128((int)descent));
    const __m128 ref_lanes = _mm_permutevar_ps(_mm_castsi128_ps(refs), lanes);
    const __m128 entry_lanes = _mm_permutevar_ps(_mm_load_ps(e), lanes);
    _mm_storeu_ps((float *)(void *)top, _mm_unpacklo_ps(ref_lanes, entry_lanes));
    _mm_storeu_ps((float *)(void *)(top + 2), _mm_unpackhi_ps(ref_lanes, entry_lanes));
    *next = (cbvh_ref)_mm_extract_epi32(_mm_castps_si128(ref_lanes), 3);
    *next_entry = e[descent >> 24];
#else
    _Alignas(16) uint32_t ref[CBVH_W4_WIDTH];
    _mm_store_si128((__m128i *)(void *)ref, refs);
    CBVH_UNROLL(3)
    for (uint32_t j = 0; j < CBVH_W4_WIDTH - 1u; j++) {
        const uint32_t s = descent >> (8u * j) & 3u;
        top[j].ref = ref[s];
        top[j].entry = e[s];
    }
    *next = ref[descent >> 24];
    *next_entry = e[descent >> 24];
#endif
    if (f->vertices_far) /* a predictable branch: the file's */
        walk_w4_prefetch_leaf_vertices(f, *next);
    *sp += cbvh_w4_popcount(hits) - 1u;
    return 1;
}
#endif

/* walk_children_hit for the wide layout (the SIMD walks in the node's or slot order take walk_w4_descend). */
CBVH_KERNEL uint32_t walk_w4_children_hit(const struct cbvh_file *restrict f, cbvh_ref r,
                                          const struct cbvh_box_ray *restrict box,
                                          const struct cbvh_w4_simd_ray *restrict w,
                                          const float *restrict float_boxes, const enum cbvh_walk_order order,
                                          const int scalar, uint32_t octant, float tmin, float tmax,
                                          cbvh_ref out[CBVH_TREE_WIDTH], float entry[CBVH_TREE_WIDTH],
                                          uint64_t *restrict boxes_tested)
{
    const uint8_t *restrict node = cbvh_w4_node(f->nodes, r);
    const uint64_t meta = cbvh_w4_meta(node);
    const uint32_t used = cbvh_w4_used(meta);
    float e[CBVH_W4_WIDTH];
    uint32_t hits = 0;
    walk_w4_prefetch_children(f, node);
    *boxes_tested += cbvh_w4_popcount(used);
#ifdef CBVH_HAVE_SIMD
    if (!float_boxes && !scalar) {
        hits = walk_w4_test_sse2(node, w, tmax, e) & used;
    } else
#endif
    {
        (void)scalar;
        (void)w;
        for (uint32_t s = 0; s < CBVH_W4_WIDTH; s++)
            if ((used >> s & 1u) && walk_box_test(box, f, CBVH_LAYOUT_WIDE4, float_boxes,
                                                  CBVH_W4_WIDTH * r + s, tmin, tmax, &e[s]))
                hits |= 1u << s;
    }
    if (!hits)
        return 0;
    if (!(hits & (hits - 1u))) { /* one child: no order to choose */
        const uint32_t s = cbvh_lowest_lane(hits);
        out[0] = cbvh_w4_child_ref(node, meta, s);
        entry[0] = e[s];
        return 1;
    }
    if (order != CBVH_WALK_DISTANCE) { /* the node's order for the ray's octant, or slot order */
        const uint32_t o = order == CBVH_WALK_SORTED ? cbvh_w4_order(meta, octant) : 0u;
        const uint32_t visit = cbvh_wide4_visits[o][hits], n = cbvh_w4_popcount(hits);
        for (uint32_t j = 0; j < n; j++) {
            const uint32_t s = visit >> (2u * j) & 3u;
            out[j] = cbvh_w4_child_ref(node, meta, s);
            entry[j] = e[s];
        }
        return n;
    }
    uint32_t n = 0;
    for (uint32_t s = 0; s < CBVH_W4_WIDTH; s++) {
        if (hits >> s & 1u) {
            cbvh_ref rs = cbvh_w4_child_ref(node, meta, s);
            float es = e[s];
            uint32_t j = n++;
            /* by distance: insertion in entry order, ties keep the slot order */
            for (; j > 0 && es < entry[j - 1]; j--) {
                out[j] = out[j - 1];
                entry[j] = entry[j - 1];
            }
            out[j] = rs;
            entry[j] = es;
        }
    }
    return n;
}

/* The children of r whose boxes the ray enters within [tmin, tmax], in visit order, with their entry
 * distances; returns how many. *boxes_tested grows by the boxes tested. */
CBVH_KERNEL uint32_t walk_children_hit(const struct cbvh_file *restrict f, const uint32_t layout, cbvh_ref r,
                                       const struct cbvh_box_ray *restrict box,
                                       const struct cbvh_w4_simd_ray *restrict w,
                                       const float *restrict float_boxes, const enum cbvh_walk_order order,
                                       uint32_t octant, float tmin, float tmax, cbvh_ref out[CBVH_TREE_WIDTH],
                                       float entry[CBVH_TREE_WIDTH], uint64_t *restrict boxes_tested,
                                       const int scalar)
{
    if (layout == CBVH_LAYOUT_WIDE4)
        return walk_w4_children_hit(f, r, box, w, float_boxes, order, scalar, octant, tmin, tmax, out, entry,
                                    boxes_tested);
    struct cbvh_child c[CBVH_TREE_WIDTH];
    cbvh_tree_children(f, layout, r, CBVH_NO_OCTANT, c);
    float e0, e1;
    const int h0 = walk_box_test(box, f, layout, float_boxes, c[0].box, tmin, tmax, &e0);
    const int h1 = walk_box_test(box, f, layout, float_boxes, c[1].box, tmin, tmax, &e1);
    *boxes_tested += 2;
    if (h0 && h1)
        return walk_order_pair(order, cbvh_tree_second_first(f, layout, r, octant), c[0].ref, e0, c[1].ref,
                               e1, out, entry);
    out[0] = h0 ? c[0].ref : c[1].ref;
    entry[0] = h0 ? e0 : e1;
    return (uint32_t)(h0 | h1);
}

/* A walk in progress: the ray's box test set up, the stack of children still to visit, and the node or
 * leaf visited next. */
struct cbvh_walk_state {
    struct cbvh_box_ray box;
    struct cbvh_w4_simd_ray w;
    cbvh_ref r;
    float r_entry; /* where the ray enters r's box (the root's: taken as its start) */
    float tmax;    /* the ray's, shrinking with each closer hit */
    uint32_t sp;
    uint64_t visited, tested;
    /* walk_w4_descend stores up to CBVH_TREE_WIDTH - 2 dead entries above the top */
    struct cbvh_walk_entry stack[(CBVH_TREE_WIDTH - 1u) * CBVH_MAX_DEPTH + CBVH_TREE_WIDTH];
};

/* Starts st's walk at `root`, entered at `entry`, with the reach tmax and an empty stack. */
CBVH_KERNEL void walk_state_start(struct cbvh_walk_state *st, cbvh_ref root, float entry, float tmax)
{
    st->sp = 0;
    st->r = root;
    st->r_entry = entry;
    st->tmax = tmax;
    st->visited = 0;
    st->tested = 0;
}

/* What a walk step leaves: more to do, the walk over, or (any hit) a triangle occludes the ray. */
enum cbvh_walk_step_result { CBVH_WALK_MORE, CBVH_WALK_DONE, CBVH_WALK_HIT };

/* Whether a walk in `mode` tests boxes one at a time on st->box (ray_box.h) rather than with the wide
 * layout's SIMD test on st->w, which reads st->box only for the rays its affine form cannot serve. */
CBVH_KERNEL int walk_reads_box_ray(const uint32_t layout, const struct cbvh_walk_mode mode,
                                   const float *float_boxes, const struct cbvh_w4_simd_ray *w)
{
#ifdef CBVH_HAVE_SIMD
    return layout != CBVH_LAYOUT_WIDE4 || float_boxes || mode.scalar || w->exact;
#else
    (void)layout;
    (void)mode;
    (void)float_boxes;
    (void)w;
    return 1;
#endif
}

/* Sets up a walk in `mode` of the subtree `root`, whose box the caller tested (or root_box, tested here
 * when not CBVH_NO_BOX), for the ray up to `tmax`. Returns 0 when the ray misses root_box. */
CBVH_KERNEL int cbvh_walk_begin(const struct cbvh_file *restrict f, const uint32_t layout,
                                const struct cbvh_ray_ctx *restrict ray, const struct cbvh_walk_mode mode,
                                cbvh_ref root, uint32_t root_box, const float *restrict float_boxes,
                                float tmax, struct cbvh_walk_state *restrict st)
{
    /* set for every layout (unread by the binary layout's instances: the compiler drops it) */
#ifdef CBVH_HAVE_SIMD
    walk_w4_simd_ray_init(&st->w, &st->box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp,
                          ray->octant, float_boxes ? 0u : ray->box_halve, ray->tmin);
#endif
    /* only where it is read: a ray's set-up is bound by its stores */
    if (root_box != CBVH_NO_BOX || walk_reads_box_ray(layout, mode, float_boxes, &st->w)) {
        cbvh_box_ray_init(&st->box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
        if (ray->box_halve && !float_boxes)
            cbvh_box_ray_halve(&st->box, ray->box_halve);
    }
    walk_state_start(st, root, ray->tmin, tmax);
    if (root_box == CBVH_NO_BOX)
        return 1;
    float entry;
    st->visited++;
    return walk_box_test(&st->box, f, layout, float_boxes, root_box, ray->tmin, tmax, &entry);
}

/* A shape query's policies (sweeps and overlaps, shape_walk.h): `enter` for each child box or `enter4` for
 * four wide slots at once, children in the order of `octant`; `leaf` with `query` the callbacks' state;
 * `limit`, when not NULL, its best contact so far, read after each leaf as the walk's reach. */
struct cbvh_shape_policy {
    cbvh_shape_enter_fn enter;
    cbvh_shape_enter4_fn enter4;
    cbvh_shape_leaf_fn leaf;
    void *query;
    uint32_t octant;
    const float *limit;
};

/* Pushes the entered children c[1..n) (n >= 1), the farthest deepest, and makes c[0] the walk's next. */
CBVH_KERNEL void walk_enter_children(struct cbvh_walk_state *restrict st, const cbvh_ref *c, const float *e,
                                     uint32_t n)
{
    for (uint32_t k = n; k-- > 1;) {
        st->stack[st->sp].ref = c[k];
        st->stack[st->sp].entry = e[k];
        st->sp++;
    }
    st->r = c[0];
    st->r_entry = e[0];
}

/* Requests the wide nodes and leaf triangle entries of the children c[1..n) a walk pushed. */
CBVH_KERNEL void walk_prefetch_pushed(const struct cbvh_file *restrict f, const uint32_t layout,
                                      const cbvh_ref *c, uint32_t n)
{
    if (layout != CBVH_LAYOUT_WIDE4)
        return;
    for (uint32_t k = n; k-- > 1;) {
        if (!cbvh_w4_ref_is_leaf(c[k]))
            CBVH_PREFETCH(cbvh_w4_node(f->nodes, c[k]));
        else
            CBVH_PREFETCH(
                cbvh_indices_entry(f->triangles, (int)f->triangle_encoding, cbvh_w4_ref_first(c[k])));
    }
}

/* The ray's node test: node st->r's entered children onto the stack, the nearest next; 0 when none. */
CBVH_KERNEL int walk_ray_node(const struct cbvh_file *restrict f, const uint32_t layout,
                              const struct cbvh_ray_ctx *restrict ray, const struct cbvh_walk_mode mode,
                              const float *restrict float_boxes, int count,
                              struct cbvh_walk_state *restrict st)
{
    (void)count; /* read by the SIMD step only */
    /* nearest first, but an any-hit walk from among the triangles farthest first (ray->any_flip) */
    const uint32_t octant = ray->octant ^ (mode.any ? ray->any_flip : 0u);
#ifdef CBVH_HAVE_SIMD
    if (layout == CBVH_LAYOUT_WIDE4 && !float_boxes && !mode.scalar && mode.order != CBVH_WALK_DISTANCE)
        return walk_w4_descend(f, st->r, &st->w, mode.order == CBVH_WALK_SORTED, octant, st->tmax, st->stack,
                               &st->sp, &st->r, &st->r_entry, count ? &st->visited : NULL);
#endif
    cbvh_ref c[CBVH_TREE_WIDTH];
    float e[CBVH_TREE_WIDTH];
    const uint32_t n = walk_children_hit(f, layout, st->r, &st->box, &st->w, float_boxes, mode.order, octant,
                                         ray->tmin, st->tmax, c, e, &st->visited, mode.scalar);
    if (n == 0)
        return 0;
    walk_prefetch_pushed(f, layout, c, n);
    walk_enter_children(st, c, e, n);
    return 1;
}

/* The shape's node test (struct cbvh_shape_policy): as walk_ray_node. */
CBVH_KERNEL int walk_shape_node(const struct cbvh_file *restrict f, const uint32_t layout,
                                const struct cbvh_shape_policy *shape, struct cbvh_walk_state *restrict st)
{
    cbvh_ref c[CBVH_TREE_WIDTH];
    float e[CBVH_TREE_WIDTH];
    const uint32_t n =
        cbvh_shape_children(f, layout, st->r, shape->octant, shape->enter, shape->enter4, shape->query, c, e);
    if (n == 0)
        return 0;
    walk_enter_children(st, c, e, n);
    return 1;
}

/* Pops the next reference still in reach: the padded test of ray_box.h against st->tmax, or any when the
 * query has no reach (`bounded` clear: an overlap). Returns 0 when the stack is empty. */
CBVH_KERNEL int walk_pop(struct cbvh_walk_state *restrict st, const int bounded)
{
    uint32_t sp = st->sp;
    do {
        if (sp == 0)
            return 0;
        sp--;
    } while (bounded && !(st->stack[sp].entry <= st->tmax * CBVH_BOX_PAD));
    st->sp = sp;
    st->r = st->stack[sp].ref;
    st->r_entry = st->stack[sp].entry;
    return 1;
}

/* One step of the walk skeleton, which every tree query takes but the stackless walk (raycast_walks.c) and
 * the streams' batch walk (stream_walk.h): node st->r's entered children (the nearest next, the others onto
 * the stack with their entry distances), or leaf st->r's triangles; then the next reference off the stack
 * still within st->tmax. The query is a ray (`ray` in `mode`) or, `shape` not NULL, a shape (ray, mode,
 * float_boxes, count and best unread). The loader checked depth <= CBVH_MAX_DEPTH, so the stack cannot
 * overflow. Closest hit: best and st->tmax follow each closer hit. `count`: whether st->visited counts. */
CBVH_KERNEL enum cbvh_walk_step_result
cbvh_walk_step(const struct cbvh_file *restrict f, const uint32_t layout,
               const struct cbvh_ray_ctx *restrict ray, const struct cbvh_walk_mode mode,
               const float *restrict float_boxes, int count, const struct cbvh_shape_policy *shape,
               struct cbvh_walk_state *restrict st, struct cbvh_best_hit *restrict best)
{
    const cbvh_ref r = st->r;
    if (!cbvh_tree_is_leaf(f, layout, r)) {
        if (shape ? walk_shape_node(f, layout, shape, st)
                  : walk_ray_node(f, layout, ray, mode, float_boxes, count, st))
            return CBVH_WALK_MORE;
    } else {
        uint32_t first, n;
        cbvh_tree_leaf(f, layout, r, &first, &n);
        st->tested += n;
        if (shape) {
            if (shape->leaf(shape->query, first, n))
                return CBVH_WALK_HIT;
            if (shape->limit)
                st->tmax = *shape->limit;
        } else if (cbvh_leaf_visit(f, first, n, ray, mode.any, mode.scalar, st->r_entry <= ray->tmin,
                                   &st->tmax, best)) {
            return CBVH_WALK_HIT;
        }
    }
    return walk_pop(st, !shape || shape->limit) ? CBVH_WALK_MORE : CBVH_WALK_DONE;
}

/* The walk of the subtree `root` (root_box as cbvh_walk_begin's): any hit: 1 when a triangle occludes the
 * ray; closest: 0, with best filled. Counters go to stats when not NULL. float_boxes: NULL for the file's
 * quantized boxes, else six floats per box id (min xyz, max xyz; cbvh report's exact reference). */
CBVH_KERNEL int cbvh_walk(const struct cbvh_file *restrict f, const uint32_t layout,
                          const struct cbvh_ray_ctx *restrict ray, cbvh_ref root, uint32_t root_box,
                          const struct cbvh_walk_mode mode, const float *restrict float_boxes,
                          struct cbvh_best_hit *restrict best, cbvh_query_stats *restrict stats)
{
    struct cbvh_walk_state st;
    enum cbvh_walk_step_result step = CBVH_WALK_DONE;
    if (cbvh_walk_begin(f, layout, ray, mode, root, root_box, float_boxes, ray->tmax, &st))
        do
            step = cbvh_walk_step(f, layout, ray, mode, float_boxes, stats != NULL, NULL, &st, best);
        while (step == CBVH_WALK_MORE);
    if (stats)
        cbvh_stats_add(stats, st.visited, st.tested);
    return step == CBVH_WALK_HIT;
}

/* A shape query's walk on the skeleton, with the policies of struct cbvh_shape_policy (octant
 * CBVH_NO_OCTANT: stored order). Force-inlined so each query's callbacks are direct calls. */
CBVH_KERNEL void cbvh_shape_walk(const struct cbvh_file *f, const uint32_t layout, uint32_t octant,
                                 cbvh_shape_enter_fn enter, cbvh_shape_enter4_fn enter4,
                                 cbvh_shape_leaf_fn leaf, void *query, const float *limit)
{
    const uint32_t root_box = cbvh_tree_root_box(f, layout);
    if (root_box != CBVH_NO_BOX) {
        uint32_t q[6];
        float entry;
        cbvh_shape_box_coords(f, layout, root_box, q);
        if (!enter(query, q, &entry))
            return;
    }
    const struct cbvh_shape_policy shape = {enter, enter4, leaf, query, octant, limit};
    const struct cbvh_walk_mode unread = {CBVH_WALK_SORTED, 0, 0};
    struct cbvh_walk_state st;
    walk_state_start(&st, cbvh_tree_root(f, layout), 0.0f, limit ? *limit : INFINITY);
    while (cbvh_walk_step(f, layout, NULL, unread, NULL, 0, &shape, &st, NULL) == CBVH_WALK_MORE)
        ;
}

/* X(name, order, any) for each walk mode the library instantiates (raycast_walks.c, and for AVX2
 * raycast_walks_avx2.c): its order and whether it stops at the first hit. */
#define CBVH_WALK_INSTANCES(X)                                                                               \
    X(closest_sorted, CBVH_WALK_SORTED, 0)                                                                   \
    X(closest_unsorted, CBVH_WALK_UNSORTED, 0)                                                               \
    X(closest_distance, CBVH_WALK_DISTANCE, 0)                                                               \
    X(any_sorted, CBVH_WALK_SORTED, 1)                                                                       \
    X(any_unsorted, CBVH_WALK_UNSORTED, 1)                                                                   \
    X(any_distance, CBVH_WALK_DISTANCE, 1)

#ifdef CBVH_HAVE_AVX2
/* The wide layout's instances compiled for AVX2, for CPUs that have it (the caller checks): cbvh_walk on
 * the subtree `start`, whose box the caller tested. */
#define CBVH_WALK_AVX2_DECLARE(name, order, any)                                                             \
    int cbvh_walk_##name##_wide4_avx2(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,             \
                                      cbvh_ref start, struct cbvh_best_hit *best, cbvh_query_stats *stats);
CBVH_WALK_INSTANCES(CBVH_WALK_AVX2_DECLARE)
#undef CBVH_WALK_AVX2_DECLARE
#endif

#endif
