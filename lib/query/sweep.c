/* sweep.c: the public sweeps: sphere, capsule and box by their own entry points, and any shape with options
 * (cbvh_sweep_with). */
#include <string.h>

#include "query/raycast.h"
#include "query/shape.h"
#include "query/sweep_walk.h"

/* The sweep of a shape in the mesh's frame: a point is a ray, else each kind's exact sweep. */
static int sweep_local(const struct cbvh_file *f, const struct cbvh_local_shape *s, const float delta[3],
                       const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found)
{
    found->tri = UINT32_MAX;
    if (cbvh_shape_is_point(s)) {
        float at[3];
        v3_to_f(s->p0, at);
        return cbvh_sweep_as_ray(f, at, delta, rules, found);
    }
    return cbvh_sweep_walk(f, s, delta, rules, found);
}

/* A sweep without options: invalid input (see cbvh.h; shape NULL for a NULL argument) is a miss. */
static int sweep_plain(const cbvh_file *file, const cbvh_shape *shape, const float delta[3],
                       cbvh_sweep_hit *hit)
{
    struct cbvh_local_shape local;
    struct cbvh_sweep_found found = {UINT32_MAX, {0.0, {0, 0, 0}, {0, 0, 0}, 0.0}};
    if (file && shape && delta && cbvh_all_finite(delta, 3) && cbvh_shape_to_mesh(shape, NULL, &local))
        sweep_local(file, &local, delta, NULL, &found);
    if (hit) {
        hit->tri = found.tri == UINT32_MAX ? CBVH_NO_HIT : cbvh_original_id(file, found.tri);
        hit->t = (float)found.contact.t;
        v3_to_f(found.contact.point, hit->point);
        v3_to_f(found.contact.normal, hit->normal);
    }
    return found.tri != UINT32_MAX;
}

/* The plain entry points' shape from its parts: a is the center (sphere, box) or p0 (capsule), b is p1
 * (capsule) or the half extents (box). A NULL part the kind needs is invalid input: a miss. */
static int sweep_parts(const cbvh_file *file, cbvh_shape_kind kind, const float *a, const float *b,
                       float radius, const float delta[3], cbvh_sweep_hit *hit)
{
    if (!a || (kind != CBVH_SHAPE_SPHERE && !b))
        return sweep_plain(file, NULL, delta, hit);
    cbvh_shape s;
    memset(&s, 0, sizeof s);
    s.kind = kind;
    s.radius = radius;
    memcpy(kind == CBVH_SHAPE_CAPSULE ? s.p0 : s.center, a, sizeof s.center);
    if (b)
        memcpy(kind == CBVH_SHAPE_CAPSULE ? s.p1 : s.half_extent, b, sizeof s.p1);
    return sweep_plain(file, &s, delta, hit);
}

CBVH_API int cbvh_sweep_sphere(const cbvh_file *file, const float center[3], float radius,
                               const float delta[3], cbvh_sweep_hit *hit)
{
    return sweep_parts(file, CBVH_SHAPE_SPHERE, center, NULL, radius, delta, hit);
}

CBVH_API int cbvh_sweep_capsule(const cbvh_file *file, const float p0[3], const float p1[3], float radius,
                                const float delta[3], cbvh_sweep_hit *hit)
{
    return sweep_parts(file, CBVH_SHAPE_CAPSULE, p0, p1, radius, delta, hit);
}

CBVH_API int cbvh_sweep_box(const cbvh_file *file, const float center[3], const float half_extent[3],
                            const float delta[3], cbvh_sweep_hit *hit)
{
    return sweep_parts(file, CBVH_SHAPE_BOX, center, half_extent, 0.0f, delta, hit);
}

CBVH_API cbvh_result cbvh_sweep_with(const cbvh_file *file, const cbvh_shape *shape, const float delta[3],
                                     const cbvh_query_options *options, cbvh_sweep_record *record)
{
    if (!record)
        return CBVH_ERROR_INVALID_ARGUMENT;
    memset(record, 0, sizeof *record);
    record->tri = CBVH_NO_HIT;
    cbvh_query_options o;
    struct cbvh_placement placement;
    const struct cbvh_placement *p;
    if (!file || !shape || !delta || !cbvh_all_finite(delta, 3) ||
        cbvh_query_options_read(options, &o) != CBVH_OK ||
        !cbvh_placement_of_option(o.transform, &placement, &p))
        return CBVH_ERROR_INVALID_ARGUMENT;
    struct cbvh_local_shape local;
    float local_delta[3];
    v3_to_f(p ? cbvh_vector_to_mesh(p, v3_from_f(delta)) : v3_from_f(delta), local_delta);
    if (!cbvh_shape_to_mesh(shape, p, &local) || !cbvh_all_finite(local_delta, 3))
        return CBVH_ERROR_INVALID_ARGUMENT;
    const struct cbvh_sweep_rules rules = {o.cull, o.filter, o.filter_user, p};
    struct cbvh_sweep_found found;
    if (!sweep_local(file, &local, local_delta, &rules, &found))
        return CBVH_OK;
    const struct cbvh_sweep_contact *c = &found.contact;
    record->tri = cbvh_original_id(file, found.tri);
    record->t = (float)c->t;
    v3_to_f(p ? cbvh_point_to_world(p, c->point) : c->point, record->point);
    v3_to_f(p ? cbvh_rotate(p->rotation, c->normal) : c->normal, record->normal);
    record->depth = (float)(p ? c->depth * p->scale : c->depth);
    record->material = cbvh_cooked_material(file, found.tri);
    return CBVH_OK;
}
