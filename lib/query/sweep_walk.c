/* sweep_walk.c: the tree walk shared by the sphere, capsule and box sweeps, and their common helpers. */
#include <float.h>
#include <math.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/sweep_walk.h"
#include "query/shape.h"
#include "query/shape_cull.h"
#include "query/shape_walk.h"
#include "query/triangle_frame.h"

/* x moved away from zero by 2^-22 of itself: more than the half ulp a float
 * addition may have rounded it inwards by. */
static float outward_lo(float x) { return x - fabsf(x) * 0x1p-22f - FLT_MIN; }
static float outward_hi(float x) { return x + fabsf(x) * 0x1p-22f + FLT_MIN; }

/* A sweep as the shape walk sees it. */
struct sweep_query {
    const struct cbvh_file *f;
    const float *center, *extent, *delta;
    float rcp[3];
    uint32_t octant;
    cbvh_sweep_triangle_fn sweep;
    const void *shape;
    const struct cbvh_local_shape *bounds;
    const struct cbvh_sweep_rules *rules;
    struct cbvh_sweep_contact best;
    uint32_t best_tri;
    float limit; /* best.t as the box tests read it */
};

/* The box [box_lo, box_hi] grown by the shape's extent, crossed by the center's path before the best contact;
 * *entry is where the path enters it. */
static int sweep_box(const struct sweep_query *q, const float box_lo[3], const float box_hi[3], float *entry)
{
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = outward_lo(box_lo[a] - q->extent[a]);
        hi[a] = outward_hi(box_hi[a] + q->extent[a]);
    }
    /* A zero delta gives rcp = +inf on every axis: the slab test then
     * accepts exactly the boxes holding the center (NaNs are ignored). */
    const uint32_t o = q->octant;
    return cbvh_slab_test(o & 1u ? hi[0] : lo[0], o & 2u ? hi[1] : lo[1], o & 4u ? hi[2] : lo[2],
                          o & 1u ? lo[0] : hi[0], o & 2u ? lo[1] : hi[1], o & 4u ? lo[2] : hi[2], q->center, q->rcp,
                          0.0f, q->limit, entry);
}

/* A node box as sweep_box sees it: dequantized on the file's grid. */
static int sweep_enter(void *query, const uint32_t grid[6], float *entry)
{
    const struct sweep_query *q = query;
    const float *origin = q->f->grid_origin, *scale = q->f->grid_scale;
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = cbvh_dequantize(grid[a], origin[a], scale[a]);
        hi[a] = cbvh_dequantize(grid[3 + a], origin[a], scale[a]);
    }
    return sweep_box(q, lo, hi, entry);
}

/* Culling by the motion: the sign of delta . n, n the face normal as wound; parallel or no motion keeps it. */
static int culled(cbvh_cull cull, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const float delta[3])
{
    const double s = v3_dot(v3_cross(v3_sub(b, a), v3_sub(c, a)), v3_from_f(delta));
    return (cull == CBVH_CULL_BACK && s > 0.0) || (cull == CBVH_CULL_FRONT && s < 0.0);
}

/* The filter's verdict on cooked triangle k, whose contact would win: its record with the barycentrics of
 * the contact point (in the triangle's best-conditioned frame, as the hit records' normals). */
static int ask_filter(const struct sweep_query *q, uint32_t k, const cbvh_v3 v[3], const struct cbvh_sweep_contact *c)
{
    struct cbvh_triangle_frame fr;
    cbvh_triangle_frame_of(v, &fr);
    double w[3] = {1.0, 0.0, 0.0};
    if (fr.nn > 0.0) {
        double x, y;
        cbvh_triangle_frame_barycentrics(&fr, v3_sub(c->point, v[fr.base]), &x, &y);
        w[fr.base] = 1.0 - x - y;
        w[(fr.base + 1) % 3] = x;
        w[(fr.base + 2) % 3] = y;
    }
    cbvh_hit_record r;
    cbvh_hit_record_fill(q->f, k, 0.0, (float)c->t, (float)w[1], (float)w[2], q->delta, &r);
    if (q->rules->placement)
        v3_to_f(cbvh_rotate(q->rules->placement->rotation, v3_from_f(r.normal)), r.normal);
    return q->rules->filter(q->rules->user, &r);
}

static int sweep_leaf(void *query, uint32_t first, uint32_t count)
{
    struct sweep_query *q = query;
    const struct cbvh_sweep_rules *rules = q->rules;
    for (uint32_t k = first; k < first + count; k++) {
        float a[3], b[3], cc[3], lo[3], hi[3];
        cbvh_triangle_vertices(q->f, k, a, b, cc);
        cbvh_triangle_bounds(a, b, cc, lo, hi);
        float entry;
        if (!sweep_box(q, lo, hi, &entry))
            continue;
        const cbvh_v3 v[3] = {v3_from_f(a), v3_from_f(b), v3_from_f(cc)};
        if (rules && rules->cull != CBVH_CULL_NONE && culled(rules->cull, v[0], v[1], v[2], q->delta))
            continue;
        const enum cbvh_cull_verdict cull =
            cbvh_cull_triangle(q->bounds, v3_from_f(q->delta), q->best.t, v[0], v[1], v[2], 0);
        if (cull == CBVH_CULL_CLEAR)
            continue;
        struct cbvh_sweep_contact c = {0.0, {0, 0, 0}, {0, 0, 0}, 0.0};
        if (!q->sweep(q->shape, v[0], v[1], v[2], q->best.t, cull == CBVH_CULL_CLEAR_AT_START, &c) ||
            !(c.t < q->best.t || (c.t == q->best.t && k < q->best_tri)))
            continue;
        const int verdict = rules && rules->filter ? ask_filter(q, k, v, &c) : CBVH_FILTER_ACCEPT;
        if (verdict == CBVH_FILTER_REJECT)
            continue;
        q->best = c; /* c.depth stays 0 unless the kernel found an overlap at t = 0 */
        q->best_tri = k;
        q->limit = (float)c.t;
        if (verdict == CBVH_FILTER_STOP)
            return 1;
    }
    return 0;
}

int cbvh_sweep_walk(const struct cbvh_file *f, const struct cbvh_local_shape *bounds, const float delta[3],
                    cbvh_sweep_triangle_fn sweep, const void *shape, const struct cbvh_sweep_rules *rules,
                    struct cbvh_sweep_found *found)
{
    cbvh_v3 lo, hi;
    float center[3], extent[3];
    cbvh_shape_bounds(bounds, &lo, &hi);
    cbvh_sweep_bounds(lo, hi, center, extent);
    struct sweep_query q = {f, center, extent, delta, {1.0f / delta[0], 1.0f / delta[1], 1.0f / delta[2]}, 0, sweep,
                            shape, bounds, rules, {1.0, {0, 0, 0}, {0, 0, 0}, 0.0}, UINT32_MAX, 1.0f};
    q.octant = cbvh_octant_of(q.rcp);
    cbvh_shape_walk(f, f->layout, q.octant, sweep_enter, sweep_leaf, &q, &q.limit, NULL);
    found->tri = q.best_tri;
    found->contact = q.best;
    found->contact.normal = v3_normalize(q.best.normal);
    return q.best_tri != UINT32_MAX;
}

void cbvh_sweep_bounds(cbvh_v3 lo, cbvh_v3 hi, float center[3], float extent[3])
{
    for (int a = 0; a < 3; a++) {
        const double l = v3_get(lo, a), h = v3_get(hi, a);
        center[a] = (float)(0.5 * (l + h));
        const double above = h - center[a], below = center[a] - l, e = above > below ? above : below;
        float ef = (float)e;
        if ((double)ef < e)
            ef = nextafterf(ef, INFINITY);
        extent[a] = ef;
    }
}

int cbvh_all_finite(const float *v, int n)
{
    for (int k = 0; k < n; k++)
        if (!isfinite(v[k]))
            return 0;
    return 1;
}

int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3],
                      const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found)
{
    const cbvh_ray ray = {{center[0], center[1], center[2]}, 0.0f, {delta[0], delta[1], delta[2]}, 1.0f};
    struct cbvh_ray_ctx ctx;
    struct cbvh_hit_gate gate;
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    found->tri = UINT32_MAX;
    if (!cbvh_ray_prepare(&ctx, &ray, f))
        return 0;
    if (rules && (rules->cull != CBVH_CULL_NONE || rules->filter)) {
        cbvh_hit_gate_init(&gate, rules->cull, rules->filter, rules->user,
                           rules->placement ? rules->placement->rotation : NULL, delta, ctx.t_base);
        ctx.gate = &gate;
    }
    cbvh_closest(f, &ctx, CBVH_TRAVERSAL_SORTED, &best, NULL);
    if (best.tri == UINT32_MAX)
        return 0;
    float a[3], b[3], c[3];
    cbvh_triangle_vertices(f, best.tri, a, b, c);
    const cbvh_v3 va = v3_from_f(a), vb = v3_from_f(b), vc = v3_from_f(c);
    found->tri = best.tri;
    found->contact.t = (float)(ctx.t_base + best.t);
    found->contact.point =
        v3_madd(v3_madd(v3_scale(va, 1.0 - (double)best.u - (double)best.v), vb, best.u), vc, best.v);
    found->contact.normal = cbvh_fallback_normal(va, vb, vc, v3_from_f(delta));
    found->contact.depth = 0.0;
    return 1;
}
