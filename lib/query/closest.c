/* closest.c: closest points between a point, a segment and a triangle, in double precision. */
#include "config.h"

#include "common/compiler.h"
#include "query/closest.h"
#include "query/triangle_frame.h"

cbvh_v3 cbvh_closest_point_triangle(cbvh_v3 p, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c)
{
    const cbvh_v3 v[3] = {a, b, c};
    return cbvh_closest_point_in_triangle(p, v);
}

/* cbvh_closest_segments, inlined into the segment-triangle test's three calls, which know d1 = p1 - p0 and
 * d2 = q1 - q0 and their squared lengths a and e already. */
CBVH_FORCE_INLINE double closest_segments_known(cbvh_v3 p0, cbvh_v3 d1, double a, cbvh_v3 q0, cbvh_v3 d2,
                                                double e, cbvh_v3 *on_p, cbvh_v3 *on_q)
{
    const cbvh_v3 r = v3_sub(p0, q0);
    const double f = v3_dot(d2, r);
    double s, t;
    if (a <= 0.0 && e <= 0.0) {
        s = t = 0.0;
    } else if (a <= 0.0) {
        s = 0.0;
        t = cbvh_clamp01(f / e);
    } else {
        const double c = v3_dot(d1, r);
        if (e <= 0.0) {
            t = 0.0;
            s = cbvh_clamp01(-c / a);
        } else {
            /* Ericson's a e - b^2 and b f - c e as |d1 x d2|^2 and (d1 x d2).(d2 x r): no cancellation */
            const double b = v3_dot(d1, d2);
            const cbvh_v3 n = v3_cross(d1, d2);
            const double denom = v3_len2(n);
            s = denom > 0.0 ? cbvh_clamp01(v3_dot(n, v3_cross(d2, r)) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = cbvh_clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = cbvh_clamp01((b - c) / a);
            }
        }
    }
    *on_p = v3_madd(p0, d1, s);
    *on_q = v3_madd(q0, d2, t);
    return v3_len2(v3_sub(*on_p, *on_q));
}

double cbvh_closest_segments(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 q0, cbvh_v3 q1, cbvh_v3 *on_p, cbvh_v3 *on_q)
{
    const cbvh_v3 d1 = v3_sub(p1, p0), d2 = v3_sub(q1, q0);
    return closest_segments_known(p0, d1, v3_len2(d1), q0, d2, v3_len2(d2), on_p, on_q);
}

/* Where segment p0-p1 crosses the plane of triangle v (frame f) inside the triangle, if it does
 * (non-coplanar case): the crossing's barycentrics in the triangle's frame decide, and the point is built
 * from them. */
CBVH_FORCE_INLINE int segment_crosses_triangle(cbvh_v3 p0, cbvh_v3 p1, const cbvh_v3 v[3],
                                               const struct cbvh_triangle_frame *f, cbvh_v3 *x)
{
    const cbvh_v3 o = v[f->base];
    const double s0 = v3_dot(v3_sub(p0, o), f->n), s1 = v3_dot(v3_sub(p1, o), f->n);
    if ((s0 > 0.0 && s1 > 0.0) || (s0 < 0.0 && s1 < 0.0) || s0 == s1 || !(f->nn > 0.0))
        return 0;
    const cbvh_v3 q = v3_madd(p0, v3_sub(p1, p0), s0 / (s0 - s1));
    double bx, by;
    cbvh_triangle_frame_barycentrics(f, v3_sub(q, o), &bx, &by);
    if (!(bx >= 0.0 && by >= 0.0 && bx + by <= 1.0))
        return 0;
    *x = v3_madd(v3_madd(o, f->e1, bx), f->e2, by);
    return 1;
}

double cbvh_closest_segment_triangle_of(cbvh_v3 p0, cbvh_v3 p1, const cbvh_v3 v[3], cbvh_v3 *on_seg,
                                        cbvh_v3 *on_tri)
{
    struct cbvh_triangle_edges e;
    struct cbvh_triangle_frame f;
    cbvh_triangle_edges_of(v, &e);
    cbvh_triangle_frame_of_edges(v, &e, &f);
    cbvh_v3 x;
    if (segment_crosses_triangle(p0, p1, v, &f, &x)) {
        *on_seg = *on_tri = x;
        return 0.0;
    }
    /* An endpoint whose nearest point of the triangle lies on an edge is a pair of that edge's test below,
     * so only the endpoints' projections inside the triangle are candidates of their own. */
    double best = INFINITY, d;
    *on_seg = p0;
    *on_tri = v[0];
    for (int k = 0; k < 2; k++) {
        const cbvh_v3 end = k ? p1 : p0;
        if (cbvh_projection_inside(v3_sub(end, v[f.base]), v, &f, &x) &&
            (d = v3_len2(v3_sub(end, x))) < best) {
            best = d;
            *on_seg = end;
            *on_tri = x;
        }
    }
    const cbvh_v3 d1 = v3_sub(p1, p0);
    const double a = v3_len2(d1);
    for (int k = 0; k < 3; k++) {
        const int opposite = cbvh_frame_vertex(k, 2); /* edge v[k] to v[k + 1] is e.edge[k + 2] */
        cbvh_v3 sp, tp;
        d = closest_segments_known(p0, d1, a, v[k], e.edge[opposite], e.len2[opposite], &sp, &tp);
        if (d < best) {
            best = d;
            *on_seg = sp;
            *on_tri = tp;
        }
    }
    return best;
}

double cbvh_closest_segment_triangle(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 *on_seg,
                                     cbvh_v3 *on_tri)
{
    const cbvh_v3 v[3] = {a, b, c};
    return cbvh_closest_segment_triangle_of(p0, p1, v, on_seg, on_tri);
}
