/* triangle_box.c: the separating-axis test of a triangle and an axis-aligned box, static or moving (13 axes). */
#include <math.h>

#include "query/triangle_box.h"

int cbvh_triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 delta, double tmax,
                            double *t, cbvh_v3 *normal)
{
    const cbvh_v3 v[3] = {v3_sub(a, center), v3_sub(b, center), v3_sub(c, center)};
    const cbvh_v3 f[3] = {v3_sub(v[1], v[0]), v3_sub(v[2], v[1]), v3_sub(v[0], v[2])};
    const cbvh_v3 box_axis[3] = {v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)};
    cbvh_v3 axes[13];
    double min_len2[13];
    int count = 0;
    for (int k = 0; k < 3; k++) {
        axes[count] = box_axis[k];
        min_len2[count++] = 0.0;
    }
    axes[count] = v3_cross(f[0], f[1]);
    min_len2[count++] = 0.0;
    for (int k = 0; k < 3; k++) {
        for (int j = 0; j < 3; j++) {
            axes[count] = v3_cross(box_axis[k], f[j]);
            /* An edge (nearly) parallel to a box axis gives no axis: the others cover it. */
            min_len2[count++] = 1e-24 * v3_len2(f[j]);
        }
    }

    double t_enter = -INFINITY, t_exit = INFINITY, least_depth = INFINITY;
    cbvh_v3 enter_normal = v3(0, 0, 1), depth_normal = v3(0, 0, 1);
    for (int k = 0; k < count; k++) {
        const double len2 = v3_len2(axes[k]);
        if (!(len2 > min_len2[k]))
            continue;
        const cbvh_v3 l = v3_scale(axes[k], 1.0 / sqrt(len2));
        const double p0 = v3_dot(v[0], l), p1 = v3_dot(v[1], l), p2 = v3_dot(v[2], l);
        const double radius = half.x * fabs(l.x) + half.y * fabs(l.y) + half.z * fabs(l.z);
        /* The box center's projection s*t must lie in [lo, hi] for the projections to meet. */
        const double lo = fmin(p0, fmin(p1, p2)) - radius, hi = fmax(p0, fmax(p1, p2)) + radius;
        const double s = v3_dot(delta, l);
        if (s == 0.0) {
            if (lo > 0.0 || hi < 0.0)
                return 0;
        } else {
            double ta = lo / s, tb = hi / s;
            if (ta > tb) {
                double tmp = ta;
                ta = tb;
                tb = tmp;
            }
            if (ta > t_enter) {
                t_enter = ta;
                enter_normal = s > 0.0 ? v3_scale(l, -1.0) : l; /* the box arrives from the side it moves away from */
            }
            if (tb < t_exit)
                t_exit = tb;
        }
        /* Moving the box by hi along l, or by -lo along -l, would separate it at t = 0. */
        if (hi < least_depth) {
            least_depth = hi;
            depth_normal = l;
        }
        if (-lo < least_depth) {
            least_depth = -lo;
            depth_normal = v3_scale(l, -1.0);
        }
    }
    if (fmax(t_enter, 0.0) > fmin(t_exit, tmax))
        return 0;
    if (t_enter <= 0.0) {
        *t = 0.0;
        *normal = depth_normal;
    } else {
        *t = t_enter;
        *normal = enter_normal;
    }
    return 1;
}
