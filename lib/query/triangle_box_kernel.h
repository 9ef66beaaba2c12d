/* triangle_box_kernel.h: the separating-axis test of a triangle and a box, static or moving (13 axes), and
 * the contact point: the bodies of triangle_box.h's functions, for the file that compiles those
 * (triangle_box.c) and for the sweeps' walk kernel (sweep_walk_kernel.h), which compiles them again in each
 * of its instruction sets. */
#ifndef CBVH_QUERY_TRIANGLE_BOX_KERNEL_H
#define CBVH_QUERY_TRIANGLE_BOX_KERNEL_H

#include <math.h>

#include "common/compiler.h"
#include "query/triangle_box.h"

/* The 13 axes of the box frame's test, unnormalized, in the order of the search: the 3 box axes, the
 * triangle's normal, then the cross of box axis k with edge f[j] at 4 + 3k + j (written out:
 * e_x x f = (0, -f.z, f.y) and so on). min_len2: an axis no longer than that gives nothing (an edge (nearly)
 * parallel to a box axis: the others cover it). */
static inline void box_sweep_axes(const cbvh_v3 f[3], cbvh_v3 axes[13], double min_len2[13])
{
    axes[0] = v3(1, 0, 0);
    axes[1] = v3(0, 1, 0);
    axes[2] = v3(0, 0, 1);
    axes[3] = v3_cross(f[0], f[1]);
    for (int k = 0; k < 4; k++)
        min_len2[k] = 0.0;
    for (int j = 0; j < 3; j++) {
        const double floor = 1e-24 * v3_len2(f[j]);
        axes[4 + j] = v3(0.0, -f[j].z, f[j].y);
        axes[7 + j] = v3(f[j].z, 0.0, -f[j].x);
        axes[10 + j] = v3(-f[j].y, f[j].x, 0.0);
        min_len2[4 + j] = min_len2[7 + j] = min_len2[10 + j] = floor;
    }
}

/* The projections of the triangle v[] grown by the box's on axis l: the box center's s*t must lie in
 * [*lo, *hi] for them to meet. */
CBVH_FORCE_INLINE void box_sweep_range(const cbvh_v3 v[3], cbvh_v3 half, cbvh_v3 l, double *lo, double *hi)
{
    const double p0 = v3_dot(v[0], l), p1 = v3_dot(v[1], l), p2 = v3_dot(v[2], l);
    const double radius = half.x * fabs(l.x) + half.y * fabs(l.y) + half.z * fabs(l.z);
    *lo = cbvh_dmin(p0, cbvh_dmin(p1, p2)) - radius;
    *hi = cbvh_dmax(p0, cbvh_dmax(p1, p2)) + radius;
}

/* The times of a sweep so far: the box center's s*t lies in every axis's [lo, hi] for t in
 * [t_enter, t_exit]; enter_axis is the axis that set t_enter. */
struct box_sweep_times {
    double t_enter, t_exit, tmax;
    int enter_axis, enter_from_below;
};

/* Narrows the times by axis k's [lo, hi] and s (delta's projection): 0 when no time in [0, tmax] is left
 * (more axes only narrow the times further). */
CBVH_FORCE_INLINE int box_sweep_narrow(struct box_sweep_times *w, int k, double lo, double hi, double s)
{
    if (s == 0.0)
        return !(lo > 0.0 || hi < 0.0);
    double ta = lo / s, tb = hi / s;
    if (ta > tb) {
        double tmp = ta;
        ta = tb;
        tb = tmp;
    }
    if (ta > w->t_enter) {
        w->t_enter = ta;
        w->enter_axis = k;
        w->enter_from_below = s > 0.0; /* the box arrives from the side it moves away from */
    }
    if (tb < w->t_exit)
        w->t_exit = tb;
    return !(cbvh_dmax(w->t_enter, 0.0) > cbvh_dmin(w->t_exit, w->tmax));
}

/* Narrows the times by box axis k crossed with each edge f[j] (axis 4 + 3k + j), the axis written out with
 * the coordinates y, z that follow k: (0, -f.z, f.y) for k = 0. Inlined with k a constant, so the
 * coordinates are picked at compile time. */
CBVH_FORCE_INLINE int box_sweep_cross(struct box_sweep_times *w, int k, const cbvh_v3 v[3],
                                      const cbvh_v3 f[3], cbvh_v3 half, cbvh_v3 delta)
{
    const int y = k == 2 ? 0 : k + 1, z = k == 0 ? 2 : k - 1;
    const double hy = v3_get(half, y), hz = v3_get(half, z), dy = v3_get(delta, y), dz = v3_get(delta, z);
    for (int j = 0; j < 3; j++) {
        const double ly = -v3_get(f[j], z), lz = v3_get(f[j], y);
        if (!(ly * ly + lz * lz > 1e-24 * v3_len2(f[j])))
            continue;
        const double p0 = v3_get(v[0], y) * ly + v3_get(v[0], z) * lz,
                     p1 = v3_get(v[1], y) * ly + v3_get(v[1], z) * lz,
                     p2 = v3_get(v[2], y) * ly + v3_get(v[2], z) * lz;
        const double radius = hy * fabs(ly) + hz * fabs(lz);
        const double lo = cbvh_dmin(p0, cbvh_dmin(p1, p2)) - radius,
                     hi = cbvh_dmax(p0, cbvh_dmax(p1, p2)) + radius;
        if (!box_sweep_narrow(w, 4 + 3 * k + j, lo, hi, dy * ly + dz * lz))
            return 0;
    }
    return 1;
}

/* Every value below is finite (or, t_enter, t_exit and least_depth, infinite before their first axis): the
 * plain compares of cbvh_dmin and cbvh_dmax (MINSD and MAXSD) give what fmin and fmax (calls into libm) give.
 * The times come from the axes as they are (a time is the same on any multiple of an axis), and the test
 * stops at the first axis that leaves no time in [0, tmax]. On a box axis a projection is a coordinate and
 * on a cross one a sum of two products: the terms box_sweep_range's dot products would add as zeros are left
 * out, which changes no value. The normal of the entering axis is normalized once at the end; the depths,
 * which compare axes, are measured on unit axes in a second pass, only for a contact at t = 0 whose normal is
 * asked for. */
static inline int triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half,
                                     cbvh_v3 delta, double tmax, double *t, cbvh_v3 *normal, double *depth)
{
    const cbvh_v3 v[3] = {v3_sub(a, center), v3_sub(b, center), v3_sub(c, center)};
    const cbvh_v3 f[3] = {v3_sub(v[1], v[0]), v3_sub(v[2], v[1]), v3_sub(v[0], v[2])};
    struct box_sweep_times w = {-INFINITY, INFINITY, tmax, -1, 0};
    for (int k = 0; k < 3; k++) {
        const double p0 = v3_get(v[0], k), p1 = v3_get(v[1], k), p2 = v3_get(v[2], k), h = v3_get(half, k);
        const double lo = cbvh_dmin(p0, cbvh_dmin(p1, p2)) - h, hi = cbvh_dmax(p0, cbvh_dmax(p1, p2)) + h;
        if (!box_sweep_narrow(&w, k, lo, hi, v3_get(delta, k)))
            return 0;
    }
    const cbvh_v3 n = v3_cross(f[0], f[1]);
    if (v3_len2(n) > 0.0) {
        double lo, hi;
        box_sweep_range(v, half, n, &lo, &hi);
        if (!box_sweep_narrow(&w, 3, lo, hi, v3_dot(delta, n)))
            return 0;
    }
    if (!box_sweep_cross(&w, 0, v, f, half, delta) || !box_sweep_cross(&w, 1, v, f, half, delta) ||
        !box_sweep_cross(&w, 2, v, f, half, delta))
        return 0;
    cbvh_v3 axes[13];
    double min_len2[13];
    box_sweep_axes(f, axes, min_len2);
    if (w.t_enter > 0.0) {
        *t = w.t_enter;
        if (normal) {
            const cbvh_v3 l = v3_normalize(axes[w.enter_axis]);
            *normal = w.enter_from_below ? v3_scale(l, -1.0) : l;
        }
        return 1;
    }
    *t = 0.0;
    if (!normal)
        return 1;
    /* Moving the box by hi along l, or by -lo along -l (l a unit axis), would separate it at t = 0. */
    double least_depth = INFINITY;
    cbvh_v3 depth_normal = v3(0, 0, 1);
    for (int k = 0; k < 13; k++) {
        const double len2 = v3_len2(axes[k]);
        if (!(len2 > min_len2[k]))
            continue;
        const cbvh_v3 l = v3_scale(axes[k], 1.0 / sqrt(len2));
        double lo, hi;
        box_sweep_range(v, half, l, &lo, &hi);
        if (hi < least_depth) {
            least_depth = hi;
            depth_normal = l;
        }
        if (-lo < least_depth) {
            least_depth = -lo;
            depth_normal = v3_scale(l, -1.0);
        }
    }
    *normal = depth_normal;
    if (depth)
        *depth = cbvh_dmax(least_depth, 0.0);
    return 1;
}

/* Triangle and motion in the box's frame: p' = axes^T (p - center); the normal back by axes. */
static inline int triangle_oriented_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box,
                                              cbvh_v3 delta, double tmax, double *t, cbvh_v3 *normal,
                                              double *depth)
{
    if (!box->rotated)
        return triangle_box_sweep(a, b, c, box->center, box->half, delta, tmax, t, normal, depth);
    const double(*m)[3] = box->axes;
    const cbvh_v3 o = box->center;
    if (!triangle_box_sweep(cbvh_rotate_back(m, v3_sub(a, o)), cbvh_rotate_back(m, v3_sub(b, o)),
                            cbvh_rotate_back(m, v3_sub(c, o)), v3(0, 0, 0), box->half,
                            cbvh_rotate_back(m, delta), tmax, t, normal, depth))
        return 0;
    if (normal)
        *normal = cbvh_rotate(m, *normal);
    return 1;
}

/* Clips polygon p (n vertices) to the half space sign * (x[axis] - plane) <= 0. */
static inline int clip_polygon(const cbvh_v3 *p, int n, int axis, double plane, double sign, cbvh_v3 *out)
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

static inline cbvh_v3 box_contact_point(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box,
                                        cbvh_v3 center, cbvh_v3 normal, double tol)
{
    /* An axis-aligned box is clipped where it is, so its points are those of the plain test. */
    const int turn = box->rotated;
    const cbvh_v3 mid = turn ? v3(0, 0, 0) : center;
    cbvh_v3 buf[2][12] = {{a, b, c}};
    if (turn)
        for (int k = 0; k < 3; k++)
            buf[0][k] = cbvh_rotate_back(box->axes, v3_sub(buf[0][k], center));
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
        return turn ? v3_add(center, cbvh_rotate(box->axes, mean)) : mean;
    }
    const double da = v3_dot(a, normal), db = v3_dot(b, normal), dc = v3_dot(c, normal);
    return da >= db && da >= dc ? a : db >= dc ? b : c;
}

#endif
