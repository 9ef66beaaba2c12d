/* raycast.c: the public single-ray entry points, cbvh_raycast and cbvh_occluded. */
#include "query/raycast.h"

int cbvh_hit_output(const struct cbvh_file *f, const struct cbvh_best_hit *best, double t_base, cbvh_hit *hit)
{
    if (best->tri == UINT32_MAX) {
        if (hit)
            hit->tri = CBVH_NO_HIT;
        return 0;
    }
    if (hit) {
        hit->tri = cbvh_original_id(f, best->tri);
        hit->t = t_base == 0.0 ? best->t : (float)(t_base + best->t);
        hit->u = best->u;
        hit->v = best->v;
    }
    return 1;
}

/* Named traversals; an unknown one is a miss. */
static int known_traversal(cbvh_traversal traversal)
{
    return traversal == CBVH_TRAVERSAL_SORTED || traversal == CBVH_TRAVERSAL_UNSORTED ||
           traversal == CBVH_TRAVERSAL_STACKLESS || traversal == CBVH_TRAVERSAL_DISTANCE;
}

/* A NULL file or ray, an unknown traversal and an invalid ray are all misses. */
CBVH_API int cbvh_raycast(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal, cbvh_hit *hit,
                          cbvh_query_stats *stats)
{
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    struct cbvh_ray_ctx ctx;
    ctx.t_base = 0.0;
    if (file && ray && known_traversal(traversal) && cbvh_ray_prepare(&ctx, ray, file))
        cbvh_closest(file, &ctx, traversal, &best, stats);
    return cbvh_hit_output(file, &best, ctx.t_base, hit);
}

CBVH_API int cbvh_occluded(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal,
                           cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    if (!file || !ray || !known_traversal(traversal) || !cbvh_ray_prepare(&ctx, ray, file))
        return 0;
    return cbvh_any(file, &ctx, traversal, stats);
}
