/* grown_path.h: a point's path center + t * delta against boxes grown by an extent, rounded outwards: the
 * node and triangle-box test of sweeps, and the node test of capsule overlaps. */
#ifndef CBVH_QUERY_GROWN_PATH_H
#define CBVH_QUERY_GROWN_PATH_H

#include <float.h>
#include <math.h>

#ifdef CBVH_HAVE_SIMD
#include <emmintrin.h>
#endif

#include "common/file.h"
#include "layout/wide4.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/shape_walk.h"

/* The path center + t * delta of a float box center +- extent, octant and rcp its direction's as a ray's;
 * with SIMD the same in every lane, and the file's grid. */
struct cbvh_grown_path {
    float center[3], extent[3], rcp[3];
    uint32_t octant;
#ifdef CBVH_HAVE_SIMD
    __m128 center4[3], extent4[3], rcp4[3];
    __m128 origin4[3], scale4[3];
#endif
};

static inline void cbvh_grown_path_init(struct cbvh_grown_path *p, const struct cbvh_file *f,
                                        const float center[3], const float extent[3], const float delta[3])
{
    for (int a = 0; a < 3; a++) {
        p->center[a] = center[a];
        p->extent[a] = extent[a];
        p->rcp[a] = 1.0f / delta[a];
    }
    p->octant = cbvh_octant_of(p->rcp);
#ifdef CBVH_HAVE_SIMD
    for (int a = 0; a < 3; a++) {
        p->center4[a] = _mm_set1_ps(center[a]);
        p->extent4[a] = _mm_set1_ps(extent[a]);
        p->rcp4[a] = _mm_set1_ps(p->rcp[a]);
        p->origin4[a] = _mm_set1_ps(f->grid_origin[a]);
        p->scale4[a] = _mm_set1_ps(f->grid_scale[a]);
    }
#else
    (void)f;
#endif
}

/* x moved away from zero by 2^-22 of itself: more than the half ulp a float
 * addition may have rounded it inwards by. */
static inline float cbvh_outward_lo(float x)
{
    return x - fabsf(x) * 0x1p-22f - FLT_MIN;
}
static inline float cbvh_outward_hi(float x)
{
    return x + fabsf(x) * 0x1p-22f + FLT_MIN;
}

/* The box [box_lo, box_hi] grown by the path's extent, crossed by the center's path for t in [0, limit];
 * *entry is where the path enters it. */
static inline int cbvh_grown_path_box(const struct cbvh_grown_path *p, const float box_lo[3],
                                      const float box_hi[3], float limit, float *entry)
{
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = cbvh_outward_lo(box_lo[a] - p->extent[a]);
        hi[a] = cbvh_outward_hi(box_hi[a] + p->extent[a]);
    }
    /* A zero delta gives rcp = +inf on every axis: the slab test then
     * accepts exactly the boxes holding the center (NaNs are ignored). */
    const uint32_t o = p->octant;
    return cbvh_slab_test(o & 1u ? hi[0] : lo[0], o & 2u ? hi[1] : lo[1], o & 4u ? hi[2] : lo[2],
                          o & 1u ? lo[0] : hi[0], o & 2u ? lo[1] : hi[1], o & 4u ? lo[2] : hi[2], p->center,
                          p->rcp, 0.0f, limit, entry);
}

/* cbvh_grown_path_box on the box of grid coordinates q (cbvh_tree_box_coord's order), dequantized on the
 * file's grid. */
static inline int cbvh_grown_path_grid(const struct cbvh_grown_path *p, const struct cbvh_file *f,
                                       const uint32_t q[6], float limit, float *entry)
{
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = cbvh_dequantize(q[a], f->grid_origin[a], f->grid_scale[a]);
        hi[a] = cbvh_dequantize(q[3 + a], f->grid_origin[a], f->grid_scale[a]);
    }
    return cbvh_grown_path_box(p, lo, hi, limit, entry);
}

#ifdef CBVH_HAVE_SIMD
/* x moved away from zero as cbvh_outward_lo (sign -1) or cbvh_outward_hi (sign 1) move it, lane by lane. */
static inline __m128 grown_path_outward4(__m128 x, float sign)
{
    const __m128 away = _mm_mul_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), x), _mm_set1_ps(0x1p-22f));
    return sign < 0.0f ? _mm_sub_ps(_mm_sub_ps(x, away), _mm_set1_ps(FLT_MIN))
                       : _mm_add_ps(_mm_add_ps(x, away), _mm_set1_ps(FLT_MIN));
}

/* One axis of cbvh_grown_path_box on four boxes [lo, hi] (a lane each), lane for lane the same float
 * operations in the same order (_mm_max_ps(a, b) is a > b ? a : b, as the slab test's selections):
 * *tnear and *tfar narrowed to the times the path spends in the grown slabs. */
CBVH_FORCE_INLINE void grown_path_axis4(const struct cbvh_grown_path *p, int a, __m128 box_lo, __m128 box_hi,
                                        __m128 *tnear, __m128 *tfar)
{
    const __m128 lo = grown_path_outward4(_mm_sub_ps(box_lo, p->extent4[a]), -1.0f);
    const __m128 hi = grown_path_outward4(_mm_add_ps(box_hi, p->extent4[a]), 1.0f);
    const int back = p->octant >> a & 1u;
    const __m128 tn = _mm_mul_ps(_mm_sub_ps(back ? hi : lo, p->center4[a]), p->rcp4[a]);
    const __m128 tf = _mm_mul_ps(_mm_sub_ps(back ? lo : hi, p->center4[a]), p->rcp4[a]);
    *tnear = _mm_max_ps(tn, *tnear);
    *tfar = _mm_min_ps(tf, *tfar);
}

/* The lanes whose grown box the path crosses, from the narrowed times. */
CBVH_FORCE_INLINE uint32_t grown_path_crossed4(__m128 tnear, __m128 tfar)
{
    return (uint32_t)_mm_movemask_ps(_mm_cmple_ps(tnear, _mm_mul_ps(tfar, _mm_set1_ps(CBVH_BOX_PAD))));
}

/* cbvh_grown_path_grid on the four slots of wide node `node` at once, each plane dequantized as
 * cbvh_dequantize does it: the same boxes with the same keys (bit s for slot s, used or not). */
CBVH_FORCE_INLINE uint32_t cbvh_grown_path_node4(const struct cbvh_grown_path *p, const uint8_t *node,
                                                 float limit, float entry[4])
{
    __m128 tnear = _mm_setzero_ps(), tfar = _mm_set1_ps(limit);
    for (uint32_t a = 0; a < 3; a++) {
        __m128 lo, hi;
        cbvh_w4_planes4(node, a, p->origin4[a], p->scale4[a], &lo, &hi);
        grown_path_axis4(p, (int)a, lo, hi, &tnear, &tfar);
    }
    _mm_storeu_ps(entry, tnear);
    return grown_path_crossed4(tnear, tfar);
}

/* cbvh_grown_path_box on the boxes of four triangles (cbvh_triangle_bounds: exact), lane by lane. */
CBVH_FORCE_INLINE uint32_t cbvh_grown_path_triangles4(const struct cbvh_grown_path *p,
                                                      const struct leaf_quad *t, float limit)
{
    __m128 tnear = _mm_setzero_ps(), tfar = _mm_set1_ps(limit);
    for (int a = 0; a < 3; a++) {
        const __m128 c0 = _mm_load_ps(t->c[0][a]), c1 = _mm_load_ps(t->c[1][a]), c2 = _mm_load_ps(t->c[2][a]);
        grown_path_axis4(p, a, _mm_min_ps(_mm_min_ps(c0, c1), c2), _mm_max_ps(_mm_max_ps(c0, c1), c2), &tnear,
                         &tfar);
    }
    return grown_path_crossed4(tnear, tfar);
}
#endif

#endif
