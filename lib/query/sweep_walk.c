/* sweep_walk.c: the tree walk shared by the sphere, capsule and box sweeps, and their common helpers. */
#include <float.h>
#include <math.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/sweep_walk.h"
#include "query/tree.h"

/* x moved away from zero by 2^-22 of itself: more than the half ulp a float
 * addition may have rounded it inwards by. */
static float outward_lo(float x) { return x - fabsf(x) * 0x1p-22f - FLT_MIN; }
static float outward_hi(float x) { return x + fabsf(x) * 0x1p-22f + FLT_MIN; }

int cbvh_sweep_walk(const struct cbvh_file *f, const float center[3], const float extent[3], const float delta[3],
                    cbvh_sweep_triangle_fn sweep, const void *shape, cbvh_sweep_hit *hit)
{
    const cbvh_node *nodes = f->nodes;
    const float rcp[3] = {1.0f / delta[0], 1.0f / delta[1], 1.0f / delta[2]};
    const uint32_t octant = cbvh_octant_of(rcp);
    const uint32_t mask = (1u << octant) << CBVH_NODE_SORT_SHIFT;
    uint32_t stack[CBVH_MAX_DEPTH];
    uint32_t sp = 0, i = 0;
    struct cbvh_contact best = {1.0, {0, 0, 0}, {0, 0, 0}}, c;
    uint32_t best_tri = UINT32_MAX;

    for (;;) {
        float lo[3], hi[3], entry;
        cbvh_node_box(f, &nodes[i], lo, hi);
        for (int a = 0; a < 3; a++) {
            lo[a] = outward_lo(lo[a] - extent[a]);
            hi[a] = outward_hi(hi[a] + extent[a]);
        }
        /* A zero delta gives rcp = +inf on every axis: the slab test then
         * accepts exactly the boxes holding the center (NaNs are ignored). */
        if (cbvh_slab_test(octant & 1u ? hi[0] : lo[0], octant & 2u ? hi[1] : lo[1], octant & 4u ? hi[2] : lo[2],
                           octant & 1u ? lo[0] : hi[0], octant & 2u ? lo[1] : hi[1], octant & 4u ? lo[2] : hi[2],
                           center, rcp, 0.0f, (float)best.t, &entry)) {
            const uint32_t word = nodes[i].word;
            if (!cbvh_node_is_leaf(word)) {
                uint32_t first = i + 1u, second = cbvh_second_child(nodes, i);
                if (word & mask) {
                    uint32_t tmp = first;
                    first = second;
                    second = tmp;
                }
                stack[sp++] = second;
                i = first;
                continue;
            }
            const uint32_t tri0 = cbvh_leaf_first(word), tri_end = tri0 + cbvh_leaf_count(word);
            for (uint32_t k = tri0; k < tri_end; k++) {
                float a[3], b[3], cc[3];
                cbvh_triangle_vertices(f, k, a, b, cc);
                if (sweep(shape, v3_from_f(a), v3_from_f(b), v3_from_f(cc), best.t, &c) &&
                    (c.t < best.t || (c.t == best.t && k < best_tri))) {
                    best = c;
                    best_tri = k;
                }
            }
        }
        if (sp == 0)
            break;
        i = stack[--sp];
    }
    if (best_tri == UINT32_MAX)
        return cbvh_sweep_miss(hit);
    if (hit) {
        hit->tri = cbvh_original_id(f, best_tri);
        hit->t = (float)best.t;
        v3_to_f(best.point, hit->point);
        v3_to_f(v3_normalize(best.normal), hit->normal);
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
    if (ctx.box_halve)
        cbvh_closest_halved(f, &ctx, &best, NULL);
    else
        cbvh_closest_stack(f, &ctx, 1, &best, NULL);
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
