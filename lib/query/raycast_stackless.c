/* raycast_stackless.c: closest-hit and any-hit walks over the escape links, no stack. */
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/tree.h"

/* i = hit ? i + 1 : escape(i), until the end of the array. A leaf's escape
 * is i + 1 as well, so after a leaf the walk just moves on. Every step goes
 * strictly forward (the loader checked the links), so each node is visited
 * at most once and the walk ends. The order is the fixed depth-first one:
 * a closest-hit walk cannot follow the sort byte. */
CBVH_KERNEL int stackless_walk(const struct cbvh_file *restrict f, const struct cbvh_ray_ctx *restrict ray,
                               const int any, const int counting, struct cbvh_best_hit *restrict best,
                               cbvh_query_stats *restrict stats)
{
    const cbvh_node *restrict nodes = f->nodes;
    const uint32_t end = f->info.node_count;
    struct cbvh_box_ray box;
    cbvh_box_ray_init(&box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint64_t visited = 0, tested = 0;
    int hit = 0;
    uint32_t i = 0;

    while (i < end) {
        const cbvh_node *n = &nodes[i];
        const uint32_t word = n->word;
        float entry;
        if (counting)
            visited++;
        if (!cbvh_box_ray_test(&box, n, tmin, tmax, &entry)) {
            i += cbvh_node_span(word);
            continue;
        }
        if (cbvh_node_is_leaf(word)) {
            if (cbvh_leaf_visit(f, word, ray, any, counting, &tmax, best, &tested)) {
                hit = 1;
                break;
            }
        }
        i++;
    }
    if (counting)
        cbvh_stats_add(stats, visited, tested);
    return hit;
}

void cbvh_closest_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, struct cbvh_best_hit *best,
                            cbvh_query_stats *stats)
{
    if (stats)
        stackless_walk(f, ray, 0, 1, best, stats);
    else
        stackless_walk(f, ray, 0, 0, best, NULL);
}

int cbvh_any_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats)
{
    if (stats)
        return stackless_walk(f, ray, 1, 1, NULL, stats);
    return stackless_walk(f, ray, 1, 0, NULL, NULL);
}
