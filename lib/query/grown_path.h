/* grown_path.h: a point's path center + t * delta against boxes grown by an extent, rounded outwards: the
 * node and triangle-box test of sweeps, and the node test of capsule overlaps. */
#ifndef CBVH_QUERY_GROWN_PATH_H
#define CBVH_QUERY_GROWN_PATH_H

#include <float.h>
#include <math.h>

#include "common/file.h"
#include "layout/wide4.h"
#include "query/lanes.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/shape_walk.h"
#include "query/vec3d.h"

/* The path center + t * delta of a float box center +- extent, octant and rcp its direction's as a ray's;
 * with SIMD the same in every lane (CBVH_LANES), and the file's grid in four. */
struct cbvh_grown_path {
    float center[3], extent[3], rcp[3];
    uint32_t octant;
#ifdef CBVH_HAVE_SIMD
    cbvh_lanes center_lanes[3], extent_lanes[3], rcp_lanes[3];
    __m128 origin4[3], scale4[3]; /* for the four slots of a wide node */
#endif
};

/* The float box center +- extent that surely holds the double box [lo, hi]. */
static inline void cbvh_sweep_bounds(cbvh_v3 lo, cbvh_v3 hi, float center[3], float extent[3])
{
    for (int a = 0; a < 3; a++) {
        const double l = v3_get(lo, a), h = v3_get(hi, a);
        center[a] = (float)(0.5 * (l + h));
        const double above = h - center[a], below = center[a] - l, e = above > below ? above : below;
        float ef = (float)e;
        if ((double)ef < e)
            ef = nextafterf(ef, INFINITY);
        extent[a] = ef;
    }
}

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
        p->center_lanes[a] = lanes_set1(center[a]);
        p->extent_lanes[a] = lanes_set1(extent[a]);
        p->rcp_lanes[a] = lanes_set1(p->rcp[a]);
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
CBVH_FORCE_INLINE cbvh_lanes grown_path_outward(cbvh_lanes x, float sign)
{
    const cbvh_lanes away = lanes_mul(lanes_andnot(lanes_set1(-0.0f), x), lanes_set1(0x1p-22f));
    return sign < 0.0f ? lanes_sub(lanes_sub(x, away), lanes_set1(FLT_MIN))
                       : lanes_add(lanes_add(x, away), lanes_set1(FLT_MIN));
}

/* One axis of cbvh_grown_path_box on CBVH_LANES boxes [lo, hi] (a lane each), lane for lane the same float
 * operations in the same order (lanes_max(a, b) is a > b ? a : b, as the slab test's selections):
 * *tnear and *tfar narrowed to the times the path spends in the grown slabs. */
CBVH_FORCE_INLINE void grown_path_axis(const struct cbvh_grown_path *p, int a, cbvh_lanes box_lo,
                                       cbvh_lanes box_hi, cbvh_lanes *tnear, cbvh_lanes *tfar)
{
    const cbvh_lanes lo = grown_path_outward(lanes_sub(box_lo, p->extent_lanes[a]), -1.0f);
    const cbvh_lanes hi = grown_path_outward(lanes_add(box_hi, p->extent_lanes[a]), 1.0f);
    const int back = p->octant >> a & 1u;
    const cbvh_lanes tn = lanes_mul(lanes_sub(back ? hi : lo, p->center_lanes[a]), p->rcp_lanes[a]);
    const cbvh_lanes tf = lanes_mul(lanes_sub(back ? lo : hi, p->center_lanes[a]), p->rcp_lanes[a]);
    *tnear = lanes_max(tn, *tnear);
    *tfar = lanes_min(tf, *tfar);
}

/* The lanes whose grown box the path crosses, from the narrowed times. */
CBVH_FORCE_INLINE uint32_t grown_path_crossed(cbvh_lanes tnear, cbvh_lanes tfar)
{
    return (uint32_t)lanes_bits(lanes_le(tnear, lanes_mul(tfar, lanes_set1(CBVH_BOX_PAD))));
}

/* cbvh_grown_path_grid on the four slots of wide node `node` at once, each plane dequantized as
 * cbvh_dequantize does it: the same boxes with the same keys (bit s for slot s, used or not). */
CBVH_FORCE_INLINE uint32_t cbvh_grown_path_node4(const struct cbvh_grown_path *p, const uint8_t *node,
                                                 float limit, float entry[4])
{
    cbvh_lanes tnear = lanes_zero(), tfar = lanes_set1(limit);
    for (uint32_t a = 0; a < 3; a++) {
        __m128 lo, hi;
        cbvh_w4_planes4(node, a, p->origin4[a], p->scale4[a], &lo, &hi);
        grown_path_axis(p, (int)a, lanes_from4(lo), lanes_from4(hi), &tnear, &tfar);
    }
    _mm_storeu_ps(entry, lanes_low4(tnear));
    return grown_path_crossed(tnear, tfar) & 0xFu;
}

/* cbvh_grown_path_box on the boxes of CBVH_LANES triangles, corners c[v][axis] (cbvh_triangle_bounds:
 * exact), lane by lane. */
CBVH_FORCE_INLINE uint32_t cbvh_grown_path_triangle_lanes(const struct cbvh_grown_path *p,
                                                          const cbvh_lanes c[3][3], float limit)
{
    cbvh_lanes tnear = lanes_zero(), tfar = lanes_set1(limit);
    for (int a = 0; a < 3; a++)
        grown_path_axis(p, a, lanes_min(lanes_min(c[0][a], c[1][a]), c[2][a]),
                        lanes_max(lanes_max(c[0][a], c[1][a]), c[2][a]), &tnear, &tfar);
    return grown_path_crossed(tnear, tfar);
}

#endif

#endif
