/* sweep_sphere.h: the sphere sweep's exact test of one triangle: first contact with its face plane, edge
 * cylinders and vertex balls. Only for sweep_walk_kernel.h, which compiles it once per instruction set. */
#ifndef CBVH_QUERY_SWEEP_SPHERE_H
#define CBVH_QUERY_SWEEP_SPHERE_H

#include "query/closest.h"
#include "query/shape.h"
#include "query/sweep_features.h"

struct sphere_shape {
    cbvh_v3 center, delta;
    double radius;
};

static inline void sphere_shape_init(struct sphere_shape *s, const struct cbvh_local_shape *shape,
                                     const float delta[3])
{
    s->center = shape->p0;
    s->delta = v3_from_f(delta);
    s->radius = shape->radius;
}

/* Overlap at the start is t = 0 with the triangle's point nearest the center
 * and the normal from it to the center (cbvh_fallback_normal when the center
 * lies on the triangle), depth radius - distance along it. Otherwise the first
 * entry of the center into the triangle grown by the radius (sweep_features.h). */
static inline int sphere_triangle(const struct sphere_shape *s, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                                  int clear_at_start, struct cbvh_sweep_contact *out)
{
    if (clear_at_start)
        return cbvh_sweep_ball_triangle(s->center, s->delta, s->radius, a, b, c, tmax, out);
    const cbvh_v3 q = cbvh_closest_point_triangle(s->center, a, b, c);
    const cbvh_v3 away = v3_sub(s->center, q);
    if (v3_len2(away) <= s->radius * s->radius) {
        out->t = 0.0;
        out->point = q;
        out->normal = v3_len2(away) > 0.0 ? v3_normalize(away) : cbvh_fallback_normal(a, b, c, s->delta);
        out->depth = s->radius - v3_len(away);
        return 1;
    }
    return cbvh_sweep_ball_triangle(s->center, s->delta, s->radius, a, b, c, tmax, out);
}

#endif
