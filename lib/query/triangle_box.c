/* triangle_box.c: the separating-axis test of a triangle and a box, static or moving (13 axes), and the
 * contact point. */
#include <math.h>

#include "query/triangle_box.h"

/* Every value below is finite (or, t_enter, t_exit and least_depth, infinite before their first axis): the
 * plain compares of cbvh_dmin and cbvh_dmax (MINSD and MAXSD) give what fmin and fmax (calls into libm) give.
 */
int cbvh_triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 delta,
                            double tmax, double *t, cbvh_v3 *normal, double *depth)
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
        const double lo = cbvh_dmin(p0, cbvh_dmin(p1, p2)) - radius,
                     hi = cbvh_dmax(p0, cbvh_dmax(p1, p2)) + radius;
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
                enter_normal =
                    s > 0.0 ? v3_scale(l, -1.0) : l; /* the box arrives from the side it moves away from */
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
    if (cbvh_dmax(t_enter, 0.0) > cbvh_dmin(t_exit, tmax))
        return 0;
    if (t_enter <= 0.0) {
        *t = 0.0;
        *normal = depth_normal;
        if (depth)
            *depth = cbvh_dmax(least_depth, 0.0);
    } else {
        *t = t_enter;
        *normal = enter_normal;
    }
    return 1;
}

/* Triangle and motion in the box's frame: p' = axes^T (p - center). */
static cbvh_v3 into_box(const struct cbvh_box *box, cbvh_v3 p)
{
    const double(*m)[3] = box->axes;
    return v3(m[0][0] * p.x + m[1][0] * p.y + m[2][0] * p.z, m[0][1] * p.x + m[1][1] * p.y + m[2][1] * p.z,
              m[0][2] * p.x + m[1][2] * p.y + m[2][2] * p.z);
}

static cbvh_v3 out_of_box(const struct cbvh_box *box, cbvh_v3 p)
{
    const double(*m)[3] = box->axes;
    return v3(m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z, m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z,
              m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z);
}

int cbvh_triangle_oriented_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box,
                                     cbvh_v3 delta, double tmax, double *t, cbvh_v3 *normal, double *depth)
{
    if (!box->rotated)
        return cbvh_triangle_box_sweep(a, b, c, box->center, box->half, delta, tmax, t, normal, depth);
    const cbvh_v3 o = box->center;
    if (!cbvh_triangle_box_sweep(into_box(box, v3_sub(a, o)), into_box(box, v3_sub(b, o)),
                                 into_box(box, v3_sub(c, o)), v3(0, 0, 0), box->half, into_box(box, delta),
                                 tmax, t, normal, depth))
        return 0;
    *normal = out_of_box(box, *normal);
    return 1;
}

/* Clips polygon p (n vertices) to the half space sign * (x[axis] - plane) <= 0. */
static int clip_polygon(const cbvh_v3 *p, int n, int axis, double plane, double sign, cbvh_v3 *out)
{
    int m = 0;
    for (int k = 0; k < n; k++) {
        const cbvh_v3 cur = p[k], next = p[k + 1 == n ? 0 : k + 1];
        const double dc = sign * (v3_get(cur, axis) - plane), dn = sign * (v3_get(next, axis) - plane);
        if (dc <= 0.0)
            out[m++] = cur;
        if ((dc < 0.0 && dn > 0.0) || (dc > 0.0 && dn < 0.0))
            out[m++] = v3_madd(cur, v3_sub(next, cur), dc / (dc - dn));
    }
    return m;
}

cbvh_v3 cbvh_box_contact_point(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box, cbvh_v3 center,
                               cbvh_v3 normal, double tol)
{
    /* An axis-aligned box is clipped where it is, so its points are those of the plain test. */
    const int turn = box->rotated;
    const cbvh_v3 mid = turn ? v3(0, 0, 0) : center;
    cbvh_v3 buf[2][12] = {{a, b, c}};
    if (turn)
        for (int k = 0; k < 3; k++)
            buf[0][k] = into_box(box, v3_sub(buf[0][k], center));
    int n = 3, cur = 0;
    for (int axis = 0; axis < 3 && n > 0; axis++) {
        const double m = v3_get(mid, axis), h = v3_get(box->half, axis) + tol;
        n = clip_polygon(buf[cur], n, axis, m + h, 1.0, buf[1 - cur]);
        cur = 1 - cur;
        n = clip_polygon(buf[cur], n, axis, m - h, -1.0, buf[1 - cur]);
        cur = 1 - cur;
    }
    if (n > 0) {
        cbvh_v3 sum = v3(0, 0, 0);
        for (int k = 0; k < n; k++)
            sum = v3_add(sum, buf[cur][k]);
        const cbvh_v3 mean = v3_scale(sum, 1.0 / n);
        return turn ? v3_add(center, out_of_box(box, mean)) : mean;
    }
    const double da = v3_dot(a, normal), db = v3_dot(b, normal), dc = v3_dot(c, normal);
    return da >= db && da >= dc ? a : db >= dc ? b : c;
}
