/* sweep_capsule.c: capsule sweeps, exact: end balls, triangle vertices against the capsule side, edges
 * against the segment. */
#include "query/closest.h"
#include "query/shape.h"
#include "query/sweep_walk.h"

struct capsule_shape {
    cbvh_v3 p0, p1, delta;
    double radius;
};

/* A positive distance between segment S and triangle T is attained by an
 * endpoint of S against T, or by S against an edge of T. So the first contact
 * of S + t*delta grown by r is the earliest of: the end balls swept against T
 * (face, edge cylinders, vertex balls), each vertex v of T entering the
 * capsule side (the point v - t*delta against the cylinder around S), and
 * each edge E of T against S: the point p0 + t*delta entering the
 * parallelogram E - (S - p0) grown by r. With r = 0 the balls and cylinders
 * have no volume and the faces alone bound the swept prism. */
static int capsule_triangle(const void *shape, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                            int clear_at_start, struct cbvh_sweep_contact *out)
{
    const struct capsule_shape *s = shape;
    const double r = s->radius;
    cbvh_v3 on_seg, on_tri, n;
    if (!clear_at_start && cbvh_closest_segment_triangle(s->p0, s->p1, a, b, c, &on_seg, &on_tri) <= r * r) {
        const cbvh_v3 away = v3_sub(on_seg, on_tri);
        out->t = 0.0;
        out->point = on_tri;
        if (v3_len2(away) > 0.0) {
            out->normal = v3_normalize(away);
            out->depth = r - v3_len(away);
        } else { /* the axis reaches the triangle: lift its lower end radius above the plane along the normal
                  */
            out->normal = cbvh_fallback_normal(a, b, c, s->delta);
            const double h0 = v3_dot(v3_sub(s->p0, on_tri), out->normal);
            out->depth = r - fmin(h0, v3_dot(v3_sub(s->p1, on_tri), out->normal));
        }
        return 1;
    }
    const cbvh_v3 v[3] = {a, b, c}, axis = v3_sub(s->p1, s->p0), back = v3_scale(s->delta, -1.0);
    double t, alpha, beta;
    int found = 0;
    for (int e = 0; e < 2; e++) {
        if (cbvh_sweep_ball_triangle(e ? s->p1 : s->p0, s->delta, r, a, b, c, tmax, out)) {
            tmax = out->t;
            found = 1;
        }
    }
    for (int k = 0; k < 3 && r > 0.0; k++) {
        if (cbvh_enter_cylinder(v[k], back, s->p0, s->p1, r, tmax, &t, &n, &alpha)) {
            out->t = tmax = t;
            out->point = v[k];
            out->normal = v3_scale(n, -1.0); /* n points from the capsule axis to the vertex */
            found = 1;
        }
    }
    for (int e = 0; e < 3; e++) {
        const cbvh_v3 q0 = v[e], q1 = v[e == 2 ? 0 : e + 1];
        if (cbvh_enter_face(s->p0, s->delta, q0, v3_sub(q1, q0), v3_scale(axis, -1.0), 1, r, tmax, &t, &n,
                            &alpha, &beta)) {
            out->t = tmax = t;
            out->point = v3_madd(q0, v3_sub(q1, q0), alpha);
            out->normal = n;
            found = 1;
        }
    }
    if (found && r == 0.0) /* touching with no thickness: the face normal against the motion */
        out->normal = cbvh_fallback_normal(a, b, c, s->delta);
    return found;
}

int cbvh_sweep_capsule_shape(const struct cbvh_file *f, const struct cbvh_local_shape *shape,
                             const float delta[3], const struct cbvh_sweep_rules *rules,
                             struct cbvh_sweep_found *found)
{
    const struct capsule_shape s = {shape->p0, shape->p1, v3_from_f(delta), shape->radius};
    return cbvh_sweep_walk(f, shape, delta, capsule_triangle, &s, rules, found);
}
