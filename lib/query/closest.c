/* closest.c: closest points between a point, a segment and a triangle, in double precision. */
#include "query/closest.h"

cbvh_v3 cbvh_closest_point_triangle(cbvh_v3 p, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c)
{
    const cbvh_v3 ab = v3_sub(b, a), ac = v3_sub(c, a), ap = v3_sub(p, a);
    const double d1 = v3_dot(ab, ap), d2 = v3_dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0)
        return a;
    const cbvh_v3 bp = v3_sub(p, b);
    const double d3 = v3_dot(ab, bp), d4 = v3_dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3)
        return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
        return v3_madd(a, ab, d1 / (d1 - d3));
    const cbvh_v3 cp = v3_sub(p, c);
    const double d5 = v3_dot(ab, cp), d6 = v3_dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6)
        return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
        return v3_madd(a, ac, d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return v3_madd(b, v3_sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double sum = va + vb + vc;
    if (!(sum > 0.0)) /* degenerate triangle that fell through the edge regions */
        return a;
    const double v = vb / sum, w = vc / sum;
    return v3_madd(v3_madd(a, ab, v), ac, w);
}

static double clamp01(double x) { return x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x; }

double cbvh_closest_segments(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 q0, cbvh_v3 q1, cbvh_v3 *on_p, cbvh_v3 *on_q)
{
    const cbvh_v3 d1 = v3_sub(p1, p0), d2 = v3_sub(q1, q0), r = v3_sub(p0, q0);
    const double a = v3_len2(d1), e = v3_len2(d2), f = v3_dot(d2, r);
    double s, t;
    if (a <= 0.0 && e <= 0.0) {
        s = t = 0.0;
    } else if (a <= 0.0) {
        s = 0.0;
        t = clamp01(f / e);
    } else {
        const double c = v3_dot(d1, r);
        if (e <= 0.0) {
            t = 0.0;
            s = clamp01(-c / a);
        } else {
            const double b = v3_dot(d1, d2), denom = a * e - b * b;
            s = denom > 0.0 ? clamp01((b * f - c * e) / denom) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = clamp01(-c / a);
            } else if (t > 1.0) {
                t = 1.0;
                s = clamp01((b - c) / a);
            }
        }
    }
    *on_p = v3_madd(p0, d1, s);
    *on_q = v3_madd(q0, d2, t);
    return v3_len2(v3_sub(*on_p, *on_q));
}

/* Where segment p0-p1 crosses the triangle's plane inside the triangle, if it does (non-coplanar case). */
static int segment_crosses_triangle(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 *x)
{
    const cbvh_v3 n = v3_cross(v3_sub(b, a), v3_sub(c, a));
    const double s0 = v3_dot(v3_sub(p0, a), n), s1 = v3_dot(v3_sub(p1, a), n);
    if ((s0 > 0.0 && s1 > 0.0) || (s0 < 0.0 && s1 < 0.0) || s0 == s1)
        return 0;
    const cbvh_v3 q = v3_madd(p0, v3_sub(p1, p0), s0 / (s0 - s1));
    /* Inside when q is on the inner side of all three edges (same orientation as n). */
    if (v3_dot(v3_cross(v3_sub(b, a), v3_sub(q, a)), n) < 0.0 || v3_dot(v3_cross(v3_sub(c, b), v3_sub(q, b)), n) < 0.0 ||
        v3_dot(v3_cross(v3_sub(a, c), v3_sub(q, c)), n) < 0.0)
        return 0;
    *x = q;
    return 1;
}

double cbvh_closest_segment_triangle(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 *on_seg,
                                     cbvh_v3 *on_tri)
{
    cbvh_v3 x;
    if (segment_crosses_triangle(p0, p1, a, b, c, &x)) {
        *on_seg = *on_tri = x;
        return 0.0;
    }
    *on_seg = p0;
    *on_tri = cbvh_closest_point_triangle(p0, a, b, c);
    double best = v3_len2(v3_sub(*on_seg, *on_tri));
    const cbvh_v3 q = cbvh_closest_point_triangle(p1, a, b, c);
    double d = v3_len2(v3_sub(p1, q));
    if (d < best) {
        best = d;
        *on_seg = p1;
        *on_tri = q;
    }
    const cbvh_v3 edge[3][2] = {{a, b}, {b, c}, {c, a}};
    for (int e = 0; e < 3; e++) {
        cbvh_v3 sp, tp;
        d = cbvh_closest_segments(p0, p1, edge[e][0], edge[e][1], &sp, &tp);
        if (d < best) {
            best = d;
            *on_seg = sp;
            *on_tri = tp;
        }
    }
    return best;
}
