/* sweep_features.h: first entry of a moving point into a ball, a finite cylinder side, or a thickened face.
 */
#ifndef CBVH_QUERY_SWEEP_FEATURES_H
#define CBVH_QUERY_SWEEP_FEATURES_H

#include "common/compiler.h"
#include "query/vec3d.h"

/* A first contact: time, point on the triangle, unit normal from the triangle towards the shape, and at
 * t = 0 how far the shape reaches into the triangle along the normal (0 otherwise). */
struct cbvh_sweep_contact {
    double t;
    cbvh_v3 point;
    cbvh_v3 normal;
    double depth;
};

/* The moving point is o + t*d for t in [0, tmax]. Each test below reports the
 * first time the point enters one convex piece of a Minkowski sum (the shape
 * dilated by radius r) from outside; a point already inside reports nothing,
 * the caller checks overlap at t = 0 first. The pieces are those of a
 * sphere-swept triangle (or parallelogram): the thickened face, the edge
 * cylinders and the vertex balls. The first entry into their union is the
 * earliest entry into any of them, so each can be tested on its own. */

/* Smallest root of a t^2 + 2 h t + c = 0 for an approaching point (h < 0)
 * starting outside (c > 0), in the cancellation-free form t = c / (-h + sqrt(h^2 - a c)). */
CBVH_FORCE_INLINE int cbvh_first_root(double a, double h, double c, double tmax, double *t)
{
    if (!(c > 0.0) || !(h < 0.0) || !(a > 0.0))
        return 0;
    const double disc = h * h - a * c;
    if (disc < 0.0)
        return 0;
    const double root = c / (-h + sqrt(disc));
    if (!(root <= tmax))
        return 0;
    *t = root;
    return 1;
}

/* Ball of radius r around c. Writes t and the unit outward normal at entry. */
CBVH_FORCE_INLINE int cbvh_enter_ball(cbvh_v3 o, cbvh_v3 d, cbvh_v3 c, double r, double tmax, double *t,
                                      cbvh_v3 *normal)
{
    const cbvh_v3 m = v3_sub(o, c);
    if (!cbvh_first_root(v3_len2(d), v3_dot(m, d), v3_len2(m) - r * r, tmax, t))
        return 0;
    *normal = v3_normalize(v3_madd(m, d, *t));
    return 1;
}

/* Side of the cylinder of radius r around segment p-q (caps excluded: the
 * end balls cover them). Writes t, the radial unit normal and the axis
 * parameter in [0, 1] of the entry point. */
CBVH_FORCE_INLINE int cbvh_enter_cylinder(cbvh_v3 o, cbvh_v3 d, cbvh_v3 p, cbvh_v3 q, double r, double tmax,
                                          double *t, cbvh_v3 *normal, double *axis)
{
    const cbvh_v3 ab = v3_sub(q, p);
    const double len2 = v3_len2(ab);
    if (!(len2 > 0.0))
        return 0;
    /* Components of the start offset and of the motion across the axis. */
    const cbvh_v3 po = v3_sub(o, p);
    const cbvh_v3 m = v3_madd(po, ab, -v3_dot(po, ab) / len2);
    const cbvh_v3 n = v3_madd(d, ab, -v3_dot(d, ab) / len2);
    if (!cbvh_first_root(v3_len2(n), v3_dot(m, n), v3_len2(m) - r * r, tmax, t))
        return 0;
    const double s = v3_dot(v3_madd(po, d, *t), ab) / len2;
    if (s < 0.0 || s > 1.0)
        return 0;
    *axis = s;
    *normal = v3_normalize(v3_madd(m, n, *t));
    return 1;
}

/* One of the two faces at distance r of the flat piece base + a*e1 + b*e2
 * (triangle: a, b >= 0, a + b <= 1; parallelogram: a, b in [0, 1]). Writes t,
 * the unit face normal on the side of o, and (a, b) of the entry point. */
CBVH_FORCE_INLINE int cbvh_enter_face(cbvh_v3 o, cbvh_v3 d, cbvh_v3 base, cbvh_v3 e1, cbvh_v3 e2,
                                      int parallelogram, double r, double tmax, double *t, cbvh_v3 *normal,
                                      double *a, double *b)
{
    const cbvh_v3 cross = v3_cross(e1, e2);
    const double cc = v3_len2(cross);
    if (!(cc > 0.0))
        return 0; /* flat piece of no area: its edges and vertices cover it */
    cbvh_v3 n = v3_scale(cross, 1.0 / sqrt(cc));
    double dist = v3_dot(v3_sub(o, base), n);
    if (dist < 0.0) {
        n = v3_scale(n, -1.0);
        dist = -dist;
    }
    const double speed = v3_dot(d, n);
    if (!(dist > r) || !(speed < 0.0))
        return 0;
    const double tt = (dist - r) / -speed;
    if (!(tt <= tmax))
        return 0;
    /* Entry point projected onto the piece's plane, in (e1, e2) coordinates, as
     * cbvh_triangle_frame_barycentrics computes them (triangle_frame.h says why). */
    const cbvh_v3 w = v3_madd(v3_sub(v3_madd(o, d, tt), base), n, -r);
    const double aa = v3_dot(v3_cross(w, e2), cross) / cc, bb = v3_dot(v3_cross(e1, w), cross) / cc;
    if (aa < 0.0 || bb < 0.0 || (parallelogram ? (aa > 1.0 || bb > 1.0) : aa + bb > 1.0))
        return 0;
    *t = tt;
    *normal = n;
    *a = aa;
    *b = bb;
    return 1;
}

/* Makes the contact at t (normal, point on the triangle) *out and t the reach of the tests after it;
 * returns 1. */
CBVH_FORCE_INLINE int cbvh_sweep_take(struct cbvh_sweep_contact *out, double *tmax, double t, cbvh_v3 normal,
                                      cbvh_v3 point)
{
    out->t = *tmax = t;
    out->normal = normal;
    out->point = point;
    return 1;
}

/* A ball of radius r >= 0 centred at o moving by d, which does not overlap
 * triangle (a, b, c) at t = 0: first contact with t <= tmax over face, edges
 * and vertices (the face only when r = 0). Returns 1 and fills *out (point
 * on the triangle). */
CBVH_FORCE_INLINE int cbvh_sweep_ball_triangle(cbvh_v3 o, cbvh_v3 d, double r, cbvh_v3 a, cbvh_v3 b,
                                               cbvh_v3 c, double tmax, struct cbvh_sweep_contact *out)
{
    const cbvh_v3 v[3] = {a, b, c};
    cbvh_v3 n;
    double t, s, u;
    int found = 0;
    if (cbvh_enter_face(o, d, a, v3_sub(b, a), v3_sub(c, a), 0, r, tmax, &t, &n, &s, &u))
        found = cbvh_sweep_take(out, &tmax, t, n, v3_madd(v3_madd(a, v3_sub(b, a), s), v3_sub(c, a), u));
    /* With r = 0 the cylinders and balls have no volume: the face alone is hit. */
    for (int e = 0; e < 3 && r > 0.0; e++) {
        const cbvh_v3 p = v[e], q = v[e == 2 ? 0 : e + 1];
        if (cbvh_enter_cylinder(o, d, p, q, r, tmax, &t, &n, &s) && t <= tmax)
            found = cbvh_sweep_take(out, &tmax, t, n, v3_madd(p, v3_sub(q, p), s));
    }
    for (int k = 0; k < 3 && r > 0.0; k++)
        if (cbvh_enter_ball(o, d, v[k], r, tmax, &t, &n) && t <= tmax)
            found = cbvh_sweep_take(out, &tmax, t, n, v[k]);
    return found;
}

/* The normal used when shape and triangle touch with no separating
 * direction (a zero-distance contact): the face normal turned against the
 * motion d (as wound when d is parallel to the face or zero); -d or +z for
 * a degenerate triangle. */
cbvh_v3 cbvh_fallback_normal(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 d);

#endif
