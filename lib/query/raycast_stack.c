/* raycast_stack.c: the library's instances of the stack walk (stack_walk.h): sorted, unsorted, by distance, from a subtree, halved. */
#include "query/stack_walk.h"

void cbvh_closest_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted,
                        struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    const uint32_t mask = sorted ? ray->sort_mask : 0u;
    if (stats)
        cbvh_stack_walk(f, ray, 0, mask, 0, 0, 1, 0, NULL, best, stats);
    else
        cbvh_stack_walk(f, ray, 0, mask, 0, 0, 0, 0, NULL, best, NULL);
}

int cbvh_any_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted, cbvh_query_stats *stats)
{
    const uint32_t mask = sorted ? ray->sort_mask : 0u;
    if (stats)
        return cbvh_stack_walk(f, ray, 0, mask, 0, 1, 1, 0, NULL, NULL, stats);
    return cbvh_stack_walk(f, ray, 0, mask, 0, 1, 0, 0, NULL, NULL, NULL);
}

void cbvh_closest_distance(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, struct cbvh_best_hit *best,
                           cbvh_query_stats *stats)
{
    if (stats)
        cbvh_stack_walk(f, ray, 0, 0, 1, 0, 1, 0, NULL, best, stats);
    else
        cbvh_stack_walk(f, ray, 0, 0, 1, 0, 0, 0, NULL, best, NULL);
}

int cbvh_any_distance(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats)
{
    if (stats)
        return cbvh_stack_walk(f, ray, 0, 0, 1, 1, 1, 0, NULL, NULL, stats);
    return cbvh_stack_walk(f, ray, 0, 0, 1, 1, 0, 0, NULL, NULL, NULL);
}

void cbvh_closest_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, uint32_t root,
                          struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    if (stats)
        cbvh_stack_walk(f, ray, root, ray->sort_mask, 0, 0, 1, 0, NULL, best, stats);
    else
        cbvh_stack_walk(f, ray, root, ray->sort_mask, 0, 0, 0, 0, NULL, best, NULL);
}

int cbvh_any_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, uint32_t root, cbvh_query_stats *stats)
{
    if (stats)
        return cbvh_stack_walk(f, ray, root, ray->sort_mask, 0, 1, 1, 0, NULL, NULL, stats);
    return cbvh_stack_walk(f, ray, root, ray->sort_mask, 0, 1, 0, 0, NULL, NULL, NULL);
}

void cbvh_closest_halved(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, struct cbvh_best_hit *best,
                         cbvh_query_stats *stats)
{
    if (stats)
        cbvh_stack_walk(f, ray, 0, ray->sort_mask, 0, 0, 1, 1, NULL, best, stats);
    else
        cbvh_stack_walk(f, ray, 0, ray->sort_mask, 0, 0, 0, 1, NULL, best, NULL);
}

int cbvh_any_halved(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats)
{
    if (stats)
        return cbvh_stack_walk(f, ray, 0, ray->sort_mask, 0, 1, 1, 1, NULL, NULL, stats);
    return cbvh_stack_walk(f, ray, 0, ray->sort_mask, 0, 1, 0, 1, NULL, NULL, NULL);
}
