/* sweep_sphere.c: sphere sweeps: exact first contact with each triangle's face plane, edge cylinders and vertex balls. */
#include "query/closest.h"
#include "query/sweep_walk.h"

struct sphere_shape {
    cbvh_v3 center, delta;
    double radius;
};

/* Overlap at the start is t = 0 with the triangle's point nearest the center
 * and the normal from it to the center (cbvh_fallback_normal when the center
 * lies on the triangle). Otherwise the first entry of the center into the
 * triangle grown by the radius (sweep_features.h). */
static int sphere_triangle(const void *shape, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax, struct cbvh_sweep_contact *out)
{
    const struct sphere_shape *s = shape;
    const cbvh_v3 q = cbvh_closest_point_triangle(s->center, a, b, c);
    const cbvh_v3 away = v3_sub(s->center, q);
    if (v3_len2(away) <= s->radius * s->radius) {
        out->t = 0.0;
        out->point = q;
        out->normal = v3_len2(away) > 0.0 ? v3_normalize(away) : cbvh_fallback_normal(a, b, c, s->delta);
        return 1;
    }
    return cbvh_sweep_ball_triangle(s->center, s->delta, s->radius, a, b, c, tmax, out);
}

CBVH_API int cbvh_sweep_sphere(const cbvh_file *file, const float center[3], float radius, const float delta[3],
                               cbvh_sweep_hit *hit)
{
    if (!file || !center || !delta || !cbvh_all_finite(center, 3) || !cbvh_all_finite(delta, 3) ||
        !isfinite(radius) || !(radius >= 0.0f))
        return cbvh_sweep_miss(hit);
    if (radius == 0.0f)
        return cbvh_sweep_as_ray(file, center, delta, hit);
    const struct sphere_shape s = {v3_from_f(center), v3_from_f(delta), radius};
    float box_center[3], extent[3];
    cbvh_sweep_bounds(v3_madd(s.center, v3(1, 1, 1), -s.radius), v3_madd(s.center, v3(1, 1, 1), s.radius), box_center,
                      extent);
    return cbvh_sweep_walk(file, box_center, extent, delta, sphere_triangle, &s, hit);
}
