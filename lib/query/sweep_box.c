/* sweep_box.c: box sweeps (axis-aligned or oriented): exact separating-axis time of impact per triangle,
 * contact point by clipping. */
#include <math.h>
#include <string.h>

#include "query/shape.h"
#include "query/sweep_walk.h"
#include "query/triangle_box.h"

struct box_shape {
    struct cbvh_box box;
    cbvh_v3 delta;
};

/* The separating-axis sweep finds the overlap at t = 0 on the way: clear_at_start would save nothing. */
static int box_triangle(const void *shape, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax, int clear_at_start,
                        struct cbvh_sweep_contact *out)
{
    (void)clear_at_start;
    const struct box_shape *s = shape;
    double t, depth = 0.0;
    cbvh_v3 n;
    if (!cbvh_triangle_oriented_box_sweep(a, b, c, &s->box, s->delta, tmax, &t, &n, &depth))
        return 0;
    const cbvh_v3 at = v3_madd(s->box.center, s->delta, t), half = s->box.half;
    const double size = fmax(fmax(half.x, half.y), half.z) + v3_len(s->delta) +
                        fmax(v3_len(v3_sub(b, a)), v3_len(v3_sub(c, a))) + fabs(at.x) + fabs(at.y) +
                        fabs(at.z);
    out->t = t;
    out->normal = n;
    out->point = cbvh_box_contact_point(a, b, c, &s->box, at, n, 1e-6 * size);
    out->depth = depth;
    return 1;
}

int cbvh_sweep_box_shape(const struct cbvh_file *f, const struct cbvh_local_shape *shape,
                         const float delta[3], const struct cbvh_sweep_rules *rules,
                         struct cbvh_sweep_found *found)
{
    struct box_shape s = {{shape->p0, shape->half, shape->rotated, {{0}}}, v3_from_f(delta)};
    memcpy(s.box.axes, shape->axes, sizeof s.box.axes);
    return cbvh_sweep_walk(f, shape, delta, box_triangle, &s, rules, found);
}
