/* sweep_features.c: first entry of a moving point into a ball, a cylinder side or a thickened face;
 * ball/triangle sweep. */
#include "query/sweep_features.h"

/* Smallest root of a t^2 + 2 h t + c = 0 for an approaching point (h < 0)
 * starting outside (c > 0), in the cancellation-free form t = c / (-h + sqrt(h^2 - a c)). */
static int first_root(double a, double h, double c, double tmax, double *t)
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

int cbvh_enter_ball(cbvh_v3 o, cbvh_v3 d, cbvh_v3 c, double r, double tmax, double *t, cbvh_v3 *normal)
{
    const cbvh_v3 m = v3_sub(o, c);
    if (!first_root(v3_len2(d), v3_dot(m, d), v3_len2(m) - r * r, tmax, t))
        return 0;
    *normal = v3_normalize(v3_madd(m, d, *t));
    return 1;
}

int cbvh_enter_cylinder(cbvh_v3 o, cbvh_v3 d, cbvh_v3 p, cbvh_v3 q, double r, double tmax, double *t,
                        cbvh_v3 *normal, double *axis)
{
    const cbvh_v3 ab = v3_sub(q, p);
    const double len2 = v3_len2(ab);
    if (!(len2 > 0.0))
        return 0;
    /* Components of the start offset and of the motion across the axis. */
    const cbvh_v3 po = v3_sub(o, p);
    const cbvh_v3 m = v3_madd(po, ab, -v3_dot(po, ab) / len2);
    const cbvh_v3 n = v3_madd(d, ab, -v3_dot(d, ab) / len2);
    if (!first_root(v3_len2(n), v3_dot(m, n), v3_len2(m) - r * r, tmax, t))
        return 0;
    const double s = v3_dot(v3_madd(po, d, *t), ab) / len2;
    if (s < 0.0 || s > 1.0)
        return 0;
    *axis = s;
    *normal = v3_normalize(v3_madd(m, n, *t));
    return 1;
}

int cbvh_enter_face(cbvh_v3 o, cbvh_v3 d, cbvh_v3 base, cbvh_v3 e1, cbvh_v3 e2, int parallelogram, double r,
                    double tmax, double *t, cbvh_v3 *normal, double *a, double *b)
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
    /* Entry point projected onto the piece's plane, in (e1, e2) coordinates:
     * w = aa e1 + bb e2 gives aa = (w x e2).cross / |cross|^2 and bb =
     * (e1 x w).cross / |cross|^2, whose errors scale with the edge lengths.
     * (The Gram-matrix solve, det = |e1|^2 |e2|^2 - (e1.e2)^2, cancels
     * catastrophically on a sliver: finding F4 put the contact at the
     * midpoint of a long edge, 3 radii from the sphere.) */
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

int cbvh_sweep_ball_triangle(cbvh_v3 o, cbvh_v3 d, double r, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                             struct cbvh_sweep_contact *out)
{
    const cbvh_v3 v[3] = {a, b, c};
    cbvh_v3 n;
    double t, s, u;
    int found = 0;
    if (cbvh_enter_face(o, d, a, v3_sub(b, a), v3_sub(c, a), 0, r, tmax, &t, &n, &s, &u)) {
        out->t = tmax = t;
        out->normal = n;
        out->point = v3_madd(v3_madd(a, v3_sub(b, a), s), v3_sub(c, a), u);
        found = 1;
    }
    /* With r = 0 the cylinders and balls have no volume: the face alone is hit. */
    for (int e = 0; e < 3 && r > 0.0; e++) {
        const cbvh_v3 p = v[e], q = v[e == 2 ? 0 : e + 1];
        if (cbvh_enter_cylinder(o, d, p, q, r, tmax, &t, &n, &s) && t <= tmax) {
            out->t = tmax = t;
            out->normal = n;
            out->point = v3_madd(p, v3_sub(q, p), s);
            found = 1;
        }
    }
    for (int k = 0; k < 3 && r > 0.0; k++) {
        if (cbvh_enter_ball(o, d, v[k], r, tmax, &t, &n) && t <= tmax) {
            out->t = tmax = t;
            out->normal = n;
            out->point = v[k];
            found = 1;
        }
    }
    return found;
}

cbvh_v3 cbvh_fallback_normal(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 d)
{
    cbvh_v3 n = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
    if (v3_len2(n) == 0.0) {
        n = v3_normalize(v3_scale(d, -1.0));
        return v3_len2(n) == 0.0 ? v3(0.0, 0.0, 1.0) : n;
    }
    return v3_dot(n, d) > 0.0 ? v3_scale(n, -1.0) : n;
}
