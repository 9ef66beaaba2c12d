/* sweep_walk.c: the tree walk shared by the sphere, capsule and box sweeps, and their common helpers. */
#include <float.h>
#include <math.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/sweep_walk.h"
#include "query/shape_walk.h"

/* x moved away from zero by 2^-22 of itself: more than the half ulp a float
 * addition may have rounded it inwards by. */
static float outward_lo(float x) { return x - fabsf(x) * 0x1p-22f - FLT_MIN; }
static float outward_hi(float x) { return x + fabsf(x) * 0x1p-22f + FLT_MIN; }

/* A sweep as the shape walk sees it. */
struct sweep_query {
    const struct cbvh_file *f;
    const float *center, *extent;
    float rcp[3];
    uint32_t octant;
    cbvh_sweep_triangle_fn sweep;
    const void *shape;
    struct cbvh_sweep_contact best;
    uint32_t best_tri;
};

/* The box grown by the shape's extent, crossed by the center's path before the best contact. */
static int sweep_enter(void *query, const float box_lo[3], const float box_hi[3])
{
    const struct sweep_query *q = query;
    float lo[3], hi[3], entry;
    for (int a = 0; a < 3; a++) {
        lo[a] = outward_lo(box_lo[a] - q->extent[a]);
        hi[a] = outward_hi(box_hi[a] + q->extent[a]);
    }
    /* A zero delta gives rcp = +inf on every axis: the slab test then
     * accepts exactly the boxes holding the center (NaNs are ignored). */
    const uint32_t o = q->octant;
    return cbvh_slab_test(o & 1u ? hi[0] : lo[0], o & 2u ? hi[1] : lo[1], o & 4u ? hi[2] : lo[2],
                          o & 1u ? lo[0] : hi[0], o & 2u ? lo[1] : hi[1], o & 4u ? lo[2] : hi[2], q->center, q->rcp,
                          0.0f, (float)q->best.t, &entry);
}

static int sweep_leaf(void *query, uint32_t first, uint32_t count)
{
    struct sweep_query *q = query;
    struct cbvh_sweep_contact c;
    for (uint32_t k = first; k < first + count; k++) {
        float a[3], b[3], cc[3];
        cbvh_triangle_vertices(q->f, k, a, b, cc);
        if (q->sweep(q->shape, v3_from_f(a), v3_from_f(b), v3_from_f(cc), q->best.t, &c) &&
            (c.t < q->best.t || (c.t == q->best.t && k < q->best_tri))) {
            q->best = c;
            q->best_tri = k;
        }
    }
    return 0;
}

int cbvh_sweep_walk(const struct cbvh_file *f, const float center[3], const float extent[3], const float delta[3],
                    cbvh_sweep_triangle_fn sweep, const void *shape, cbvh_sweep_hit *hit)
{
    struct sweep_query q = {f, center, extent, {1.0f / delta[0], 1.0f / delta[1], 1.0f / delta[2]}, 0, sweep, shape,
                            {1.0, {0, 0, 0}, {0, 0, 0}}, UINT32_MAX};
    q.octant = cbvh_octant_of(q.rcp);
    cbvh_shape_walk(f, f->layout, q.octant, sweep_enter, sweep_leaf, &q);
    if (q.best_tri == UINT32_MAX)
        return cbvh_sweep_miss(hit);
    if (hit) {
        hit->tri = cbvh_original_id(f, q.best_tri);
        hit->t = (float)q.best.t;
        v3_to_f(q.best.point, hit->point);
        v3_to_f(v3_normalize(q.best.normal), hit->normal);
    }
    return 1;
}

void cbvh_sweep_bounds(cbvh_v3 lo, cbvh_v3 hi, float center[3], float extent[3])
{
    for (int a = 0; a < 3; a++) {
        const double l = v3_get(lo, a), h = v3_get(hi, a);
        center[a] = (float)(0.5 * (l + h));
        const double e = fmax(h - center[a], center[a] - l);
        float ef = (float)e;
        if ((double)ef < e)
            ef = nextafterf(ef, INFINITY);
        extent[a] = ef;
    }
}

int cbvh_sweep_miss(cbvh_sweep_hit *hit)
{
    if (hit)
        hit->tri = CBVH_NO_HIT;
    return 0;
}

int cbvh_all_finite(const float *v, int n)
{
    for (int k = 0; k < n; k++)
        if (!isfinite(v[k]))
            return 0;
    return 1;
}

int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3], cbvh_sweep_hit *hit)
{
    const cbvh_ray ray = {{center[0], center[1], center[2]}, 0.0f, {delta[0], delta[1], delta[2]}, 1.0f};
    struct cbvh_ray_ctx ctx;
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    if (!cbvh_ray_prepare(&ctx, &ray, f))
        return cbvh_sweep_miss(hit);
    cbvh_closest(f, &ctx, CBVH_TRAVERSAL_SORTED, &best, NULL);
    if (best.tri == UINT32_MAX)
        return cbvh_sweep_miss(hit);
    if (hit) {
        float a[3], b[3], c[3];
        cbvh_triangle_vertices(f, best.tri, a, b, c);
        const cbvh_v3 va = v3_from_f(a), vb = v3_from_f(b), vc = v3_from_f(c);
        const cbvh_v3 p = v3_madd(v3_madd(v3_scale(va, 1.0 - (double)best.u - (double)best.v), vb, best.u), vc, best.v);
        hit->tri = cbvh_original_id(f, best.tri);
        hit->t = (float)(ctx.t_base + best.t);
        v3_to_f(p, hit->point);
        v3_to_f(cbvh_fallback_normal(va, vb, vc, v3_from_f(delta)), hit->normal);
    }
    return 1;
}
