/* shape_cull.h: cheap tests that a shape, still or swept, cannot touch a triangle, run before the exact tests. */
#ifndef CBVH_QUERY_SHAPE_CULL_H
#define CBVH_QUERY_SHAPE_CULL_H

#include "query/shape.h"

/* Plain compares, not fmin/fmax, which GCC leaves as calls into libm; the values are never NaN. */
static inline double cull_max(double x, double y) { return x > y ? x : y; }
static inline double cull_min(double x, double y) { return x < y ? x : y; }
static inline double cull_max_abs(cbvh_v3 v) { return cull_max(cull_max(fabs(v.x), fabs(v.y)), fabs(v.z)); }

/* The box [lo, hi] of a triangle's float vertices, exact: a walk's node test on it culls the triangle as it
 * would cull a leaf holding that triangle alone. */
static inline void cbvh_triangle_bounds(const float a[3], const float b[3], const float c[3], float lo[3],
                                        float hi[3])
{
    for (int k = 0; k < 3; k++) {
        const float ab_lo = a[k] < b[k] ? a[k] : b[k], ab_hi = a[k] < b[k] ? b[k] : a[k];
        lo[k] = c[k] < ab_lo ? c[k] : ab_lo;
        hi[k] = c[k] > ab_hi ? c[k] : ab_hi;
    }
}

/* How far the shape reaches along n from its core, times |n|. */
static inline double cull_reach_along(const struct cbvh_local_shape *s, cbvh_v3 n)
{
    if (s->kind != CBVH_SHAPE_BOX)
        return s->radius * v3_len(n);
    if (!s->rotated)
        return fabs(n.x) * s->half.x + fabs(n.y) * s->half.y + fabs(n.z) * s->half.z;
    const double(*m)[3] = s->axes; /* columns are the box's axes */
    return fabs(n.x * m[0][0] + n.y * m[1][0] + n.z * m[2][0]) * s->half.x +
           fabs(n.x * m[0][1] + n.y * m[1][1] + n.z * m[2][1]) * s->half.y +
           fabs(n.x * m[0][2] + n.y * m[1][2] + n.z * m[2][2]) * s->half.z;
}

/* What the plane of a triangle tells about a shape moved by t * delta for t in [0, tmax]. */
enum cbvh_plane_clearance {
    CBVH_PLANE_MAY_TOUCH, /* the plane cannot tell */
    CBVH_PLANE_CLEAR_AT_START, /* the shape at t = 0 cannot touch the triangle; later it may */
    CBVH_PLANE_CLEAR /* no contact for any t in [0, tmax] */
};

/* Whether the shape s, at t = 0 and moved by t * delta for every t in [0, tmax], lies on one side of the
 * plane of triangle (a, b, c) by more than any rounding of the exact tests: then no exact sweep or overlap
 * test can find a contact there, and the caller skips them (CBVH_PLANE_MAY_TOUCH, always, for a triangle
 * of no area). The swept shape is the hull of its core points (center, or capsule ends, at t = 0 and
 * t = tmax) grown by its reach along the normal (radius, or half extents on the box's axes). The margin,
 * 2^-30 of (longest edge from a)^2 times the size of everything the test reads (coordinates, motion,
 * shape), is 2^23 times this test's own error bound in double (normal included, slivers too), and leaves a
 * gap of about 2^-32 of that size: far above the rounding of the exact tests, a few ulps of it, for any
 * shape larger than a millionth of its distance to the vertices. Safe on any finite input. */
static inline enum cbvh_plane_clearance cbvh_shape_plane_clearance(const struct cbvh_local_shape *s,
                                                                   cbvh_v3 delta, double tmax, cbvh_v3 a,
                                                                   cbvh_v3 b, cbvh_v3 c)
{
    const cbvh_v3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), n = v3_cross(e1, e2), motion = v3_scale(delta, tmax);
    const double s0 = v3_dot(n, v3_sub(s->p0, a)), s1 = v3_dot(n, v3_sub(s->p1, a)), m = v3_dot(n, motion);
    const double lo = cull_min(s0, s1), hi = cull_max(s0, s1);
    const double span = cull_max(cull_max_abs(e1), cull_max_abs(e2));
    const double size = cull_max_abs(a) + cull_max(cull_max_abs(s->p0), cull_max_abs(s->p1)) +
                        cull_max_abs(motion) + s->radius + s->half.x + s->half.y + s->half.z;
    const double gap = cull_reach_along(s, n) + 0x1p-30 * span * span * size;
    if (lo + cull_min(m, 0.0) > gap || hi + cull_max(m, 0.0) < -gap)
        return CBVH_PLANE_CLEAR;
    return lo > gap || hi < -gap ? CBVH_PLANE_CLEAR_AT_START : CBVH_PLANE_MAY_TOUCH;
}

#endif
