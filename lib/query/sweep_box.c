/* sweep_box.c: axis-aligned box sweeps: exact separating-axis time of impact per triangle, contact point by clipping. */
#include <math.h>

#include "query/sweep_walk.h"
#include "query/triangle_box.h"

struct box_shape {
    cbvh_v3 center, half, delta;
};

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

/* A point of the triangle where it touches the box (center, half): the mean
 * of the triangle clipped to the box grown by tol (the contact set is a point,
 * segment or polygon; the mean of a convex polygon lies in it). When rounding
 * leaves nothing, the triangle's vertex farthest along the contact normal. */
static cbvh_v3 contact_point(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 normal, double tol)
{
    cbvh_v3 buf[2][12] = {{a, b, c}};
    int n = 3, cur = 0;
    for (int axis = 0; axis < 3 && n > 0; axis++) {
        const double mid = v3_get(center, axis), h = v3_get(half, axis) + tol;
        n = clip_polygon(buf[cur], n, axis, mid + h, 1.0, buf[1 - cur]);
        cur = 1 - cur;
        n = clip_polygon(buf[cur], n, axis, mid - h, -1.0, buf[1 - cur]);
        cur = 1 - cur;
    }
    if (n > 0) {
        cbvh_v3 sum = v3(0, 0, 0);
        for (int k = 0; k < n; k++)
            sum = v3_add(sum, buf[cur][k]);
        return v3_scale(sum, 1.0 / n);
    }
    const double da = v3_dot(a, normal), db = v3_dot(b, normal), dc = v3_dot(c, normal);
    return da >= db && da >= dc ? a : db >= dc ? b : c;
}

static int box_triangle(const void *shape, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax, struct cbvh_sweep_contact *out)
{
    const struct box_shape *s = shape;
    double t;
    cbvh_v3 n;
    if (!cbvh_triangle_box_sweep(a, b, c, s->center, s->half, s->delta, tmax, &t, &n))
        return 0;
    const cbvh_v3 at = v3_madd(s->center, s->delta, t);
    const double size = fmax(fmax(s->half.x, s->half.y), s->half.z) + v3_len(s->delta) +
                        fmax(v3_len(v3_sub(b, a)), v3_len(v3_sub(c, a))) + fabs(at.x) + fabs(at.y) + fabs(at.z);
    out->t = t;
    out->normal = n;
    out->point = contact_point(a, b, c, at, s->half, n, 1e-6 * size);
    return 1;
}

CBVH_API int cbvh_sweep_box(const cbvh_file *file, const float center[3], const float half_extent[3],
                            const float delta[3], cbvh_sweep_hit *hit)
{
    if (!file || !center || !half_extent || !delta || !cbvh_all_finite(center, 3) ||
        !cbvh_all_finite(half_extent, 3) || !cbvh_all_finite(delta, 3) ||
        !(half_extent[0] >= 0.0f && half_extent[1] >= 0.0f && half_extent[2] >= 0.0f))
        return cbvh_sweep_miss(hit);
    if (half_extent[0] == 0.0f && half_extent[1] == 0.0f && half_extent[2] == 0.0f)
        return cbvh_sweep_as_ray(file, center, delta, hit);
    const struct box_shape s = {v3_from_f(center), v3_from_f(half_extent), v3_from_f(delta)};
    return cbvh_sweep_walk(file, center, half_extent, delta, box_triangle, &s, hit);
}
