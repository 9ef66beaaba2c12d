/* sweep_features.c: first entry of a moving point into a ball, a cylinder side or a thickened face;
 * ball/triangle sweep. */
#include "query/sweep_features.h"

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
