/* sweep_capsule.h: the capsule sweep's exact test of one triangle: end balls, triangle vertices against the
 * capsule side, edges against the segment. Only for sweep_walk_kernel.h, which compiles it once per
 * instruction set. */
#ifndef CBVH_QUERY_SWEEP_CAPSULE_H
#define CBVH_QUERY_SWEEP_CAPSULE_H

#include <math.h>

#include "common/compiler.h"
#include "query/closest.h"
#include "query/shape.h"
#include "query/shape_cull.h"
#include "query/sweep_features.h"

struct capsule_shape {
    cbvh_v3 p0, p1, delta;
    double radius;
    cbvh_v3 axis, back; /* p1 - p0 and -delta */
    double core_size;   /* the largest coordinate of p0 or p1, plus the radius */
};

/* Narrows [*t0, *t1] to the times t when the point p0 + t*delta lies in the slab along u around the
 * triangle (vertices p0 + w[k]) swept by -axis and grown by r and the margin 2^-30 size |u|_1 (see
 * capsule_slabs). Returns 0 when no time is left. */
CBVH_FORCE_INLINE int capsule_slab(const struct capsule_shape *s, const cbvh_v3 w[3], cbvh_v3 u, double size,
                                   double *t0, double *t1)
{
    const double d0 = v3_dot(u, w[0]), d1 = v3_dot(u, w[1]), d2 = v3_dot(u, w[2]);
    const double along = -v3_dot(u, s->axis), speed = v3_dot(u, s->delta);
    const double grow = s->radius * v3_len(u) + 0x1p-30 * size * (fabs(u.x) + fabs(u.y) + fabs(u.z));
    const double lo = cbvh_dmin(cbvh_dmin(d0, d1), d2) + cbvh_dmin(along, 0.0) - grow;
    const double hi = cbvh_dmax(cbvh_dmax(d0, d1), d2) + cbvh_dmax(along, 0.0) + grow;
    if (speed == 0.0)
        return !(lo > 0.0 || hi < 0.0);
    const double inv = 1.0 / speed, enter = (speed > 0.0 ? lo : hi) * inv,
                 leave = (speed > 0.0 ? hi : lo) * inv;
    *t0 = cbvh_dmax(*t0, enter);
    *t1 = cbvh_dmin(*t1, leave);
    return !(*t0 > *t1);
}

/* Where the capsule can first touch triangle (a, b, c), bounded by slabs: the point p0 + t*delta touches
 * the triangle swept by -axis and grown by r only inside every slab {x : lo <= u.x <= hi} around that
 * set, for any direction u (lo and hi from u's dot products with the vertices, the axis and r |u|). Seven
 * directions, those that reject most often first: the edges crossed with the axis (the set's side faces
 * when it is a prism), the edges' outward normals in the plane (n x e), and the face normal n. Returns 0
 * when t in [0, tmax] leaves some slab, so the capsule misses the triangle; else 1, with *t_lo the earliest
 * t the slabs allow (above 0: the capsule is clear of the triangle at t = 0). The slabs are grown by
 * 2^-30 size |u|_1 (size: the largest coordinates of a vertex, the core and the motion, the span and the
 * radius), far beyond the rounding of the dot products and of the times (the directions need no accuracy:
 * a slab is a slab for any u) and of the exact feature tests on a triangle no sliver. On a sliver
 * (|n|^2 < 2^-20 span^4), on a triangle of extreme size (span below 2^-160 or size beyond 2^160, where the
 * products could underflow or overflow) it returns 1 with *t_lo 0; a NaN from any product keeps the
 * triangle too. */
static inline int capsule_slabs(const struct capsule_shape *s, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                                double *t_lo)
{
    const cbvh_v3 e[3] = {v3_sub(b, a), v3_sub(c, b), v3_sub(a, c)},
                  w[3] = {v3_sub(a, s->p0), v3_sub(b, s->p0), v3_sub(c, s->p0)};
    const cbvh_v3 n = v3_cross(e[0], v3_scale(e[2], -1.0));
    const double span = cbvh_dmax(cull_max_abs(e[0]), cull_max_abs(e[2])), span2 = span * span;
    const double size = cull_max_abs(a) + span + s->core_size + cull_max_abs(v3_scale(s->delta, tmax));
    *t_lo = 0.0;
    if (!(v3_len2(n) >= 0x1p-20 * span2 * span2 && span >= 0x1p-160 && size <= 0x1p160))
        return 1;
    double t0 = 0.0, t1 = tmax;
    for (int k = 0; k < 3; k++)
        if (!capsule_slab(s, w, v3_cross(e[k], s->axis), size, &t0, &t1))
            return 0;
    for (int k = 0; k < 3; k++)
        if (!capsule_slab(s, w, v3_cross(n, e[k]), size, &t0, &t1))
            return 0;
    if (!capsule_slab(s, w, n, size, &t0, &t1))
        return 0;
    *t_lo = t0;
    return 1;
}

/* A positive distance between segment S and triangle T is attained by an
 * endpoint of S against T, or by S against an edge of T. So the first contact
 * of S + t*delta grown by r is the earliest of: the end balls swept against T
 * (face, edge cylinders, vertex balls), each vertex v of T entering the
 * capsule side (the point v - t*delta against the cylinder around S), and
 * each edge E of T against S: the point p0 + t*delta entering the
 * parallelogram E - (S - p0) grown by r. With r = 0 the balls and cylinders
 * have no volume and the faces alone bound the swept prism. */
static inline int capsule_triangle(const struct capsule_shape *s, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                                   double tmax, int clear_at_start, struct cbvh_sweep_contact *out)
{
    const double r = s->radius;
    cbvh_v3 on_seg, on_tri, n;
    double t_lo;
    if (!capsule_slabs(s, a, b, c, tmax, &t_lo))
        return 0;
    if (t_lo > 0.0)
        clear_at_start = 1;
    if (!clear_at_start && cbvh_closest_segment_triangle(s->p0, s->p1, a, b, c, &on_seg, &on_tri) <= r * r) {
        const cbvh_v3 away = v3_sub(on_seg, on_tri);
        out->t = 0.0;
        out->point = on_tri;
        if (v3_len2(away) > 0.0) {
            out->normal = v3_normalize(away);
            out->depth = r - v3_len(away);
        } else { /* the axis reaches the triangle: its lower end lifted r above the plane along the normal */
            out->normal = cbvh_fallback_normal(a, b, c, s->delta);
            const double h0 = v3_dot(v3_sub(s->p0, on_tri), out->normal);
            out->depth = r - fmin(h0, v3_dot(v3_sub(s->p1, on_tri), out->normal));
        }
        return 1;
    }
    const cbvh_v3 v[3] = {a, b, c}, axis = s->axis, back = s->back, e1 = v3_sub(b, a), e2 = v3_sub(c, a);
    double t, alpha, beta;
    int found = 0;
    /* Face first: with both ends on one side of the plane, clear at t = 0, the capsule comes within r of the
     * plane first where its lower end does (the ends' heights change alike). When that end enters the face
     * inside the triangle, no contact can come earlier: that is the answer. */
    const cbvh_v3 normal = v3_cross(e1, e2);
    const double h0 = v3_dot(normal, v3_sub(s->p0, a)), h1 = v3_dot(normal, v3_sub(s->p1, a));
    if (((h0 > 0.0 && h1 > 0.0) || (h0 < 0.0 && h1 < 0.0)) &&
        cbvh_enter_face(fabs(h0) <= fabs(h1) ? s->p0 : s->p1, s->delta, a, e1, e2, 0, r, tmax, &t, &n, &alpha,
                        &beta))
        return cbvh_sweep_take(out, &tmax, t, r > 0.0 ? n : cbvh_fallback_normal(a, b, c, s->delta),
                               v3_madd(v3_madd(a, e1, alpha), e2, beta));
    for (int e = 0; e < 2; e++) {
        if (cbvh_sweep_ball_triangle(e ? s->p1 : s->p0, s->delta, r, a, b, c, tmax, out)) {
            tmax = out->t;
            found = 1;
        }
    }
    for (int k = 0; k < 3 && r > 0.0; k++) /* n points from the capsule axis to the vertex */
        if (cbvh_enter_cylinder(v[k], back, s->p0, s->p1, r, tmax, &t, &n, &alpha))
            found = cbvh_sweep_take(out, &tmax, t, v3_scale(n, -1.0), v[k]);
    for (int e = 0; e < 3; e++) {
        const cbvh_v3 q0 = v[e], q1 = v[e == 2 ? 0 : e + 1];
        if (cbvh_enter_face(s->p0, s->delta, q0, v3_sub(q1, q0), v3_scale(axis, -1.0), 1, r, tmax, &t, &n,
                            &alpha, &beta))
            found = cbvh_sweep_take(out, &tmax, t, n, v3_madd(q0, v3_sub(q1, q0), alpha));
    }
    if (found && r == 0.0) /* touching with no thickness: the face normal against the motion */
        out->normal = cbvh_fallback_normal(a, b, c, s->delta);
    return found;
}

static inline void capsule_shape_init(struct capsule_shape *s, const struct cbvh_local_shape *shape,
                                      const float delta[3])
{
    const cbvh_v3 d = v3_from_f(delta);
    *s = (struct capsule_shape){shape->p0,
                                shape->p1,
                                d,
                                shape->radius,
                                v3_sub(shape->p1, shape->p0),
                                v3_scale(d, -1.0),
                                cbvh_dmax(cull_max_abs(shape->p0), cull_max_abs(shape->p1)) + shape->radius};
}

#endif
