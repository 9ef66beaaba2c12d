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

/* The switches below treat an unknown traversal as a miss; the halved walk asks first. */
static int known_traversal(cbvh_traversal traversal)
{
    return traversal == CBVH_TRAVERSAL_SORTED || traversal == CBVH_TRAVERSAL_UNSORTED ||
           traversal == CBVH_TRAVERSAL_STACKLESS || traversal == CBVH_TRAVERSAL_DISTANCE;
}

/* A NULL file or ray, an unknown traversal and an invalid ray are all misses.
 * A ray whose box test needs half scale takes the halved walk whatever the
 * traversal (raycast.h): the answer is the same. */
CBVH_API int cbvh_raycast(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal, cbvh_hit *hit,
                          cbvh_query_stats *stats)
{
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    struct cbvh_ray_ctx ctx;
    ctx.t_base = 0.0;
    if (file && ray && cbvh_ray_prepare(&ctx, ray, file)) {
        if (ctx.box_halve) {
            if (known_traversal(traversal))
                cbvh_closest_halved(file, &ctx, &best, stats);
        } else switch (traversal) {
        case CBVH_TRAVERSAL_SORTED:
            cbvh_closest_stack(file, &ctx, 1, &best, stats);
            break;
        case CBVH_TRAVERSAL_UNSORTED:
            cbvh_closest_stack(file, &ctx, 0, &best, stats);
            break;
        case CBVH_TRAVERSAL_STACKLESS:
            cbvh_closest_stackless(file, &ctx, &best, stats);
            break;
        case CBVH_TRAVERSAL_DISTANCE:
            cbvh_closest_distance(file, &ctx, &best, stats);
            break;
        }
    }
    return cbvh_hit_output(file, &best, ctx.t_base, hit);
}

CBVH_API int cbvh_occluded(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal,
                           cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    if (!file || !ray || !cbvh_ray_prepare(&ctx, ray, file))
        return 0;
    if (ctx.box_halve)
        return known_traversal(traversal) ? cbvh_any_halved(file, &ctx, stats) : 0;
    switch (traversal) {
    case CBVH_TRAVERSAL_SORTED:
        return cbvh_any_stack(file, &ctx, 1, stats);
    case CBVH_TRAVERSAL_UNSORTED:
        return cbvh_any_stack(file, &ctx, 0, stats);
    case CBVH_TRAVERSAL_STACKLESS:
        return cbvh_any_stackless(file, &ctx, stats);
    case CBVH_TRAVERSAL_DISTANCE:
        return cbvh_any_distance(file, &ctx, stats);
    }
    return 0;
}
