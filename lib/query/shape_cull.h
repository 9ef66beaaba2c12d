/* shape_cull.h: cheap tests that a shape, still or swept, cannot touch a triangle or surely does, before the exact ones. */
#ifndef CBVH_QUERY_SHAPE_CULL_H
#define CBVH_QUERY_SHAPE_CULL_H

#include "query/shape.h"

/* Plain compares (one instruction each), not fmin/fmax, which GCC leaves as calls into libm; the values are
 * never NaN. */
static inline double cull_max(double x, double y) { return x > y ? x : y; }
static inline double cull_min(double x, double y) { return x < y ? x : y; }
static inline float cull_maxf(float x, float y) { return x > y ? x : y; }
static inline float cull_minf(float x, float y) { return x < y ? x : y; }
static inline double cull_max_abs(cbvh_v3 v) { return cull_max(cull_max(fabs(v.x), fabs(v.y)), fabs(v.z)); }

/* The box [lo, hi] of a triangle's float vertices, exact: a walk's node test on it culls the triangle as it
 * would cull a leaf holding that triangle alone. */
static inline void cbvh_triangle_bounds(const float a[3], const float b[3], const float c[3], float lo[3],
                                        float hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = cull_minf(cull_minf(a[k], b[k]), c[k]);
        hi[k] = cull_maxf(cull_maxf(a[k], b[k]), c[k]);
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

/* What the cheap tests tell of a shape moved by t * delta for t in [0, tmax] and a triangle. */
enum cbvh_cull_verdict {
    CBVH_CULL_MAY_TOUCH,      /* they cannot tell: the exact tests decide */
    CBVH_CULL_CLEAR_AT_START, /* the shape at t = 0 cannot touch the triangle; later it may */
    CBVH_CULL_CLEAR,          /* no contact for any t in [0, tmax] */
    CBVH_CULL_TOUCHES         /* the shape at t = 0 surely touches the triangle (asked for only) */
};

/* 1 when point p lies within `reach` of a vertex of triangle (a, b, c). */
static inline int cull_point_near_vertex(cbvh_v3 p, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double reach)
{
    const double r2 = reach * reach;
    return (v3_len2(v3_sub(p, a)) <= r2) | (v3_len2(v3_sub(p, b)) <= r2) | (v3_len2(v3_sub(p, c)) <= r2);
}

/* 1 when point p, whose height over the plane of triangle (a, b, c) is s / |n| (n = (b - a) x (c - a),
 * nn = |n|^2), lies within `reach` of the plane and projects into the triangle: its three edge functions
 * (barycentrics times nn) at least tol. */
static inline int cull_point_over(cbvh_v3 p, double s, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 n, double nn,
                                  double reach, double tol)
{
    const double e0 = v3_dot(v3_cross(v3_sub(b, a), v3_sub(p, a)), n);
    const double e1 = v3_dot(v3_cross(v3_sub(c, b), v3_sub(p, b)), n);
    const double e2 = v3_dot(v3_cross(v3_sub(a, c), v3_sub(p, c)), n);
    return (s * s <= reach * reach * nn) & (e0 >= tol) & (e1 >= tol) & (e2 >= tol);
}

/* The cheap tests of shape s against triangle (a, b, c), in double, with margins that put their verdicts
 * beyond the rounding of the exact tests:
 * - CBVH_CULL_CLEAR (or _AT_START): the shape, at t = 0 and moved by t * delta for every t in [0, tmax]
 *   (at t = 0 only), lies on one side of the triangle's plane. The swept shape is the hull of its core
 *   points (center, or capsule ends, at t = 0 and t = tmax) grown by its reach along the normal (radius,
 *   or half extents on the box's axes). The margin, 2^-30 of span^2 times size (span: the longest edge
 *   from a on an axis; size: the sum of the largest coordinates of a vertex, the shape and the motion, of
 *   span and of the shape's own size), is 2^23 times this test's own error bound in double (normal
 *   included, slivers too), and leaves a gap of about 2^-32 of size: far above the rounding of the exact
 *   tests, a few ulps of it, for any shape larger than a millionth of its distance to the vertices.
 * - CBVH_CULL_TOUCHES, asked for by want_touches (overlaps: the exact tests tell no more than yes or no
 *   there): a ball or capsule with an end point within the radius less 2^-20 size of a vertex, or of the
 *   plane where it projects into the triangle, each barycentric at least 2^-28 span^3 size / |n|^2; the
 *   triangle no sliver (|n|^2 >= 2^-20 span^4). The exact tests' closest points are then within 2^-28
 *   size of true ones no farther than that vertex or projection, so they find a distance below the
 *   radius.
 * CBVH_CULL_MAY_TOUCH otherwise, always for a triangle of no area. Safe on any finite input. */
static inline enum cbvh_cull_verdict cbvh_cull_triangle(const struct cbvh_local_shape *s, cbvh_v3 delta,
                                                        double tmax, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                                                        const int want_touches)
{
    const cbvh_v3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), n = v3_cross(e1, e2), motion = v3_scale(delta, tmax);
    const double s0 = v3_dot(n, v3_sub(s->p0, a)), s1 = v3_dot(n, v3_sub(s->p1, a)), m = v3_dot(n, motion);
    const double lo = cull_min(s0, s1), hi = cull_max(s0, s1);
    const double span = cull_max(cull_max_abs(e1), cull_max_abs(e2));
    const double size = cull_max_abs(a) + span + cull_max(cull_max_abs(s->p0), cull_max_abs(s->p1)) +
                        cull_max_abs(motion) + s->radius + s->half.x + s->half.y + s->half.z;
    const double gap = cull_reach_along(s, n) + 0x1p-30 * span * span * size;
    if (lo + cull_min(m, 0.0) > gap || hi + cull_max(m, 0.0) < -gap)
        return CBVH_CULL_CLEAR;
    if (lo > gap || hi < -gap)
        return CBVH_CULL_CLEAR_AT_START;
    if (!want_touches || s->kind == CBVH_SHAPE_BOX)
        return CBVH_CULL_MAY_TOUCH;
    const double nn = v3_len2(n), span2 = span * span, reach = s->radius - 0x1p-20 * size;
    const double tol = 0x1p-28 * span2 * span * size;
    if (!(nn >= 0x1p-20 * span2 * span2) || !(reach > 0.0))
        return CBVH_CULL_MAY_TOUCH;
    const int ends = s->kind == CBVH_SHAPE_CAPSULE ? 2 : 1;
    for (int k = 0; k < ends; k++) {
        const cbvh_v3 p = k ? s->p1 : s->p0;
        if (cull_point_near_vertex(p, a, b, c, reach) || cull_point_over(p, k ? s1 : s0, a, b, c, n, nn, reach, tol))
            return CBVH_CULL_TOUCHES;
    }
    return CBVH_CULL_MAY_TOUCH;
}

#endif
