/* sweep_box.h: the box sweep's exact test of one triangle (axis-aligned or oriented box): separating-axis
 * time of impact, contact point by clipping. Only for sweep_walk_kernel.h, which compiles it once per
 * instruction set. */
#ifndef CBVH_QUERY_SWEEP_BOX_H
#define CBVH_QUERY_SWEEP_BOX_H

#include <math.h>
#include <string.h>

#include "query/shape.h"
#include "query/sweep_features.h"
#include "query/triangle_box_kernel.h"

struct box_shape {
    struct cbvh_box box;
    cbvh_v3 delta;
};

/* The separating-axis sweep finds the overlap at t = 0 on the way: clear_at_start would save nothing. */
static inline int box_triangle(const struct box_shape *s, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                               int clear_at_start, struct cbvh_sweep_contact *out)
{
    (void)clear_at_start;
    double t, depth = 0.0;
    cbvh_v3 n;
    if (!triangle_oriented_box_sweep(a, b, c, &s->box, s->delta, tmax, &t, &n, &depth))
        return 0;
    const cbvh_v3 at = v3_madd(s->box.center, s->delta, t), half = s->box.half;
    /* Finite and >= 0 (the half extents are, the vertices and the motion are floats): cbvh_dmax is fmax. */
    const double size = cbvh_dmax(cbvh_dmax(half.x, half.y), half.z) + v3_len(s->delta) +
                        cbvh_dmax(v3_len(v3_sub(b, a)), v3_len(v3_sub(c, a))) + fabs(at.x) + fabs(at.y) +
                        fabs(at.z);
    out->t = t;
    out->normal = n;
    out->point = box_contact_point(a, b, c, &s->box, at, n, 1e-6 * size);
    out->depth = depth;
    return 1;
}

static inline void box_shape_init(struct box_shape *s, const struct cbvh_local_shape *shape,
                                  const float delta[3])
{
    *s = (struct box_shape){{shape->p0, shape->half, shape->rotated, {{0}}}, v3_from_f(delta)};
    memcpy(s->box.axes, shape->axes, sizeof s->box.axes);
}

#endif
