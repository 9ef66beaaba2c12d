/* brute_force.c: double-precision reference geometry used to check query answers (Ericson; Akenine-Moller). */
#include <math.h>

#include "brute_force.h"

static void sub(double r[3], const double a[3], const double b[3])
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross(double r[3], const double a[3], const double b[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

int bf_ray_triangle(const double org[3], const double dir[3], double tmin, double tmax, const double a[3],
                    const double b[3], const double c[3], double *t, double *u, double *v, double *margin)
{
    double e1[3], e2[3], p[3], s[3], q[3];
    sub(e1, b, a);
    sub(e2, c, a);
    cross(p, dir, e2);
    double det = dot(e1, p);
    if (det == 0.0)
        return 0;
    double inv = 1.0 / det;
    sub(s, org, a);
    double uu = dot(s, p) * inv;
    cross(q, s, e1);
    double vv = dot(dir, q) * inv;
    double tt = dot(e2, q) * inv;
    if (uu < 0 || vv < 0 || uu + vv > 1 || !(tt >= tmin && tt <= tmax))
        return 0;
    *t = tt;
    *u = uu;
    *v = vv;
    double w = 1 - uu - vv, m = uu < vv ? uu : vv;
    *margin = w < m ? w : m;
    return 1;
}

double bf_point_triangle_dist2(const double p[3], const double a[3], const double b[3], const double c[3])
{
    /* Ericson, Real-Time Collision Detection 5.1.5, in barycentric form. */
    double ab[3], ac[3], ap[3], bp[3], cp[3], closest[3], d[3];
    sub(ab, b, a);
    sub(ac, c, a);
    sub(ap, p, a);
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    double wa, wb, wc; /* weights of a, b, c */
    sub(bp, p, b);
    double d3 = dot(ab, bp), d4 = dot(ac, bp);
    sub(cp, p, c);
    double d5 = dot(ab, cp), d6 = dot(ac, cp);
    double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0) {
        wa = 1, wb = 0, wc = 0;
    } else if (d3 >= 0 && d4 <= d3) {
        wa = 0, wb = 1, wc = 0;
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double s = d1 - d3 != 0 ? d1 / (d1 - d3) : 0;
        wa = 1 - s, wb = s, wc = 0;
    } else if (d6 >= 0 && d5 <= d6) {
        wa = 0, wb = 0, wc = 1;
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double s = d2 - d6 != 0 ? d2 / (d2 - d6) : 0;
        wa = 1 - s, wb = 0, wc = s;
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double s = (d4 - d3) + (d5 - d6) != 0 ? (d4 - d3) / ((d4 - d3) + (d5 - d6)) : 0;
        wa = 0, wb = 1 - s, wc = s;
    } else {
        double den = va + vb + vc;
        if (den == 0) { /* collinear corners: the nearest of the three edges */
            double d_ab = bf_segment_segment_dist2(p, p, a, b), d_bc = bf_segment_segment_dist2(p, p, b, c);
            double d_ca = bf_segment_segment_dist2(p, p, c, a);
            double m = d_ab < d_bc ? d_ab : d_bc;
            return m < d_ca ? m : d_ca;
        }
        wb = vb / den;
        wc = vc / den;
        wa = 1 - wb - wc;
    }
    for (int k = 0; k < 3; k++)
        closest[k] = wa * a[k] + wb * b[k] + wc * c[k];
    sub(d, p, closest);
    return dot(d, d);
}

double bf_segment_segment_dist2(const double p0[3], const double p1[3], const double q0[3], const double q1[3])
{
    /* Ericson 5.1.9. */
    double d1[3], d2[3], r[3];
    sub(d1, p1, p0);
    sub(d2, q1, q0);
    sub(r, p0, q0);
    double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    double s, t;
    if (a <= 0 && e <= 0) {
        s = t = 0;
    } else if (a <= 0) {
        s = 0;
        t = clamp01(f / e);
    } else {
        double c = dot(d1, r);
        if (e <= 0) {
            t = 0;
            s = clamp01(-c / a);
        } else {
            double b = dot(d1, d2), denom = a * e - b * b;
            s = denom > 0 ? clamp01((b * f - c * e) / denom) : 0;
            t = (b * s + f) / e;
            if (t < 0) {
                t = 0;
                s = clamp01(-c / a);
            } else if (t > 1) {
                t = 1;
                s = clamp01((b - c) / a);
            }
        }
    }
    double diff[3];
    for (int k = 0; k < 3; k++)
        diff[k] = (p0[k] + d1[k] * s) - (q0[k] + d2[k] * t);
    return dot(diff, diff);
}

double bf_segment_triangle_dist2(const double p0[3], const double p1[3], const double a[3], const double b[3],
                                 const double c[3])
{
    double dir[3], t, u, v, margin;
    sub(dir, p1, p0);
    if (bf_ray_triangle(p0, dir, 0.0, 1.0, a, b, c, &t, &u, &v, &margin))
        return 0.0;
    /* Otherwise the minimum is attained at an endpoint or on an edge. */
    double best = bf_point_triangle_dist2(p0, a, b, c), d;
    if ((d = bf_point_triangle_dist2(p1, a, b, c)) < best)
        best = d;
    if ((d = bf_segment_segment_dist2(p0, p1, a, b)) < best)
        best = d;
    if ((d = bf_segment_segment_dist2(p0, p1, b, c)) < best)
        best = d;
    if ((d = bf_segment_segment_dist2(p0, p1, c, a)) < best)
        best = d;
    return best;
}

/* Projections of the three (box-relative) corners on `axis` against the box's projection radius. */
static int separated(const double axis[3], const double v[3][3], const double half[3])
{
    double p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
    double lo = fmin(p0, fmin(p1, p2)), hi = fmax(p0, fmax(p1, p2));
    double r = half[0] * fabs(axis[0]) + half[1] * fabs(axis[1]) + half[2] * fabs(axis[2]);
    return lo > r || hi < -r;
}

int bf_box_triangle_overlap(const double center[3], const double half[3], const double a[3], const double b[3],
                            const double c[3])
{
    double v[3][3], e[3][3];
    sub(v[0], a, center);
    sub(v[1], b, center);
    sub(v[2], c, center);
    sub(e[0], v[1], v[0]);
    sub(e[1], v[2], v[1]);
    sub(e[2], v[0], v[2]);
    for (int i = 0; i < 3; i++) { /* box face normals */
        double axis[3] = { 0, 0, 0 };
        axis[i] = 1;
        if (separated(axis, v, half))
            return 0;
    }
    double n[3];
    cross(n, e[0], e[1]);
    if (separated(n, v, half))
        return 0;
    for (int i = 0; i < 3; i++) /* box axis x triangle edge */
        for (int j = 0; j < 3; j++) {
            double unit[3] = { 0, 0, 0 }, axis[3];
            unit[i] = 1;
            cross(axis, unit, e[j]);
            if (separated(axis, v, half))
                return 0;
        }
    return 1;
}
