/* ray_box.h: the slab test of a ray against a dequantized node box, robust to 0, -0, inf and NaN. */
#ifndef CBVH_QUERY_RAY_BOX_H
#define CBVH_QUERY_RAY_BOX_H

#include <stdint.h>

#include "common/format.h"
#include "layout/tree.h"
#include "query/ray_setup.h"

/* Ize 2013: the far distance times 1 + 2^-21 (> 1 + 2 gamma(3)) covers the rounding of (plane - org) *
 * rcp, so no box the ray touches is missed. */
#define CBVH_BOX_PAD 0x1.00001p0f

/* For each axis, the grid coordinate index (cbvh_tree_box_coord) of the plane the ray meets first
 * (near) and last (far): the minimum for a positive reciprocal, else the maximum. */
struct cbvh_slab_select {
    uint32_t near_x, near_y, near_z, far_x, far_y, far_z;
};

/* The selection for each octant (bit a: a negative direction on axis a). */
#define CBVH_SLAB_NEAR(octant, axis) ((axis) + 3u * ((octant) >> (axis)&1u))
#define CBVH_SLAB_SELECT(o)                                                                                  \
    {                                                                                                        \
        CBVH_SLAB_NEAR(o, 0), CBVH_SLAB_NEAR(o, 1), CBVH_SLAB_NEAR(o, 2), 3u - CBVH_SLAB_NEAR(o, 0),         \
            5u - CBVH_SLAB_NEAR(o, 1), 7u - CBVH_SLAB_NEAR(o, 2)                                             \
    }
static const struct cbvh_slab_select cbvh_slab_selects[8] = {
    CBVH_SLAB_SELECT(0u), CBVH_SLAB_SELECT(1u), CBVH_SLAB_SELECT(2u), CBVH_SLAB_SELECT(3u),
    CBVH_SLAB_SELECT(4u), CBVH_SLAB_SELECT(5u), CBVH_SLAB_SELECT(6u), CBVH_SLAB_SELECT(7u)};
#undef CBVH_SLAB_SELECT

static inline struct cbvh_slab_select cbvh_slab_select_of(uint32_t octant)
{
    return cbvh_slab_selects[octant & 7u];
}

/* Slab test on dequantized near/far planes; a NaN distance (0 * inf) fails the ordered compares and decides
 * nothing. Returns 1 when [tmin, tmax] overlaps the box, and the entry distance in *entry. */
CBVH_KERNEL int cbvh_slab_test(float nx, float ny, float nz, float fx, float fy, float fz, const float org[3],
                               const float rcp[3], float tmin, float tmax, float *entry)
{
    float tnx = (nx - org[0]) * rcp[0], tny = (ny - org[1]) * rcp[1], tnz = (nz - org[2]) * rcp[2];
    float tfx = (fx - org[0]) * rcp[0], tfy = (fy - org[1]) * rcp[1], tfz = (fz - org[2]) * rcp[2];
    float tnear = tmin, tfar = tmax;
    tnear = tnx > tnear ? tnx : tnear;
    tnear = tny > tnear ? tny : tnear;
    tnear = tnz > tnear ? tnz : tnear;
    tfar = tfx < tfar ? tfx : tfar;
    tfar = tfy < tfar ? tfy : tfar;
    tfar = tfz < tfar ? tfz : tfar;
    *entry = tnear;
    return tnear <= tfar * CBVH_BOX_PAD;
}

/* A ray as the walks test it against nodes: everything kept in locals for the walk's duration. */
struct cbvh_box_ray {
    float origin[3], scale[3]; /* the file's grid */
    float org[3], rcp[3];
    struct cbvh_slab_select sel;
};

static inline void cbvh_box_ray_init(struct cbvh_box_ray *b, const float grid_origin[3],
                                     const float grid_scale[3], const float org[3], const float rcp[3],
                                     uint32_t octant)
{
    for (int a = 0; a < 3; a++) {
        b->origin[a] = grid_origin[a];
        b->scale[a] = grid_scale[a];
        b->org[a] = org[a];
        b->rcp[a] = rcp[a];
    }
    b->sel = cbvh_slab_select_of(octant);
}

/* Puts the box test on the axes of `axes` (a ray's box_halve) at half scale (grid and origin halved,
 * reciprocal doubled): the same distances exactly, but a plane - org past FLT_MAX no longer overflows. */
static inline void cbvh_box_ray_halve(struct cbvh_box_ray *b, uint32_t axes)
{
    for (int a = 0; a < 3; a++) {
        if (axes >> a & 1u) {
            b->origin[a] *= 0.5f;
            b->scale[a] *= 0.5f;
            b->org[a] *= 0.5f;
            b->rcp[a] *= 2.0f;
        }
    }
}

/* Ray against box `box` of the file's tree, dequantizing the six planes the test needs. */
CBVH_KERNEL int cbvh_box_ray_test(const struct cbvh_box_ray *b, const struct cbvh_file *f,
                                  const uint32_t layout, uint32_t box, float tmin, float tmax, float *entry)
{
    const struct cbvh_slab_select s = b->sel;
    const float *o = b->origin, *sc = b->scale;
    return cbvh_slab_test(cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.near_x), o[0], sc[0]),
                          cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.near_y), o[1], sc[1]),
                          cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.near_z), o[2], sc[2]),
                          cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.far_x), o[0], sc[0]),
                          cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.far_y), o[1], sc[1]),
                          cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, s.far_z), o[2], sc[2]), b->org,
                          b->rcp, tmin, tmax, entry);
}

#endif
