/* sweep_walk.c: the sphere, capsule and box sweeps' tree walk with their exact triangle tests (its scalar
 * and SSE2 instances, and the choice of kernel), and the sweep of a point. */
#include "config.h"

#include <float.h>
#include <math.h>

#include "query/raycast.h"
#include "query/sweep_walk_kernel.h"

static int sweep_walk_scalar(const struct cbvh_file *f, const struct cbvh_local_shape *bounds,
                             const float delta[3], const struct cbvh_sweep_rules *rules,
                             struct cbvh_sweep_found *found)
{
    return sweep_walk_kernel(f, bounds, delta, rules, found, 0);
}

#ifdef CBVH_HAVE_SIMD
static int sweep_walk_sse2(const struct cbvh_file *f, const struct cbvh_local_shape *bounds,
                           const float delta[3], const struct cbvh_sweep_rules *rules,
                           struct cbvh_sweep_found *found)
{
    return sweep_walk_kernel(f, bounds, delta, rules, found, 1);
}
#endif

/* The instance of the walk kernel chosen for the rays (cbvh_walk_kernel), whatever the layout: the scalar
 * one takes triangles one at a time, the others CBVH_LANES at a time. */
int cbvh_sweep_walk(const struct cbvh_file *f, const struct cbvh_local_shape *shape, const float delta[3],
                    const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found)
{
    switch (cbvh_walk_kernel()) {
#ifdef CBVH_HAVE_AVX2
    case CBVH_WALK_KERNEL_AVX2:
        return cbvh_sweep_walk_avx2(f, shape, delta, rules, found);
#endif
#ifdef CBVH_HAVE_SIMD
    case CBVH_WALK_KERNEL_SSE2:
        return sweep_walk_sse2(f, shape, delta, rules, found);
#endif
    default:
        return sweep_walk_scalar(f, shape, delta, rules, found);
    }
}

int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3],
                      const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found)
{
    const cbvh_ray ray = {{center[0], center[1], center[2]}, 0.0f, {delta[0], delta[1], delta[2]}, 1.0f};
    struct cbvh_ray_ctx ctx;
    struct cbvh_hit_gate gate;
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    found->tri = UINT32_MAX;
    if (!cbvh_ray_prepare(&ctx, &ray, f, NULL))
        return 0;
    if (rules && (rules->cull != CBVH_CULL_NONE || rules->filter)) {
        cbvh_hit_gate_init(&gate, rules->cull, rules->filter, rules->user,
                           rules->placement ? rules->placement->rotation : NULL, delta, &ctx.t_frame);
        ctx.gate = &gate;
    }
    cbvh_closest(f, &ctx, CBVH_TRAVERSAL_SORTED, &best, NULL);
    if (best.tri == UINT32_MAX)
        return 0;
    float a[3], b[3], c[3];
    cbvh_triangle_vertices(f, best.tri, a, b, c);
    const cbvh_v3 va = v3_from_f(a), vb = v3_from_f(b), vc = v3_from_f(c);
    found->tri = best.tri;
    found->contact.t = cbvh_t_frame_out(&ctx.t_frame, best.t);
    found->contact.point =
        v3_madd(v3_madd(v3_scale(va, 1.0 - (double)best.u - (double)best.v), vb, best.u), vc, best.v);
    found->contact.normal = cbvh_fallback_normal(va, vb, vc, v3_from_f(delta));
    found->contact.depth = 0.0;
    return 1;
}
