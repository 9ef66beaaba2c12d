/* raycast_stackless.c: closest-hit and any-hit walks over the binary layout's escape links, no stack. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "layout/binary.h"
#include "query/ray_box.h"
#include "query/raycast.h"

/* The leaf step, out of line: inlined, its register pressure made the node loop reload the box test's
 * ray from the stack at every node. */
CBVH_NOINLINE int stackless_leaf(const struct cbvh_file *f, uint32_t word, const struct cbvh_ray_ctx *ray,
                                 const int any, const int near, float *tmax, struct cbvh_best_hit *best)
{
    return cbvh_leaf_visit(f, cbvh_leaf_first(word), cbvh_leaf_count(word), ray, any, 0, near, tmax, best);
}

/* i = hit ? i + 1 : escape(i), until the end of the array. A leaf's escape
 * is i + 1 as well, so after a leaf the walk just moves on. Every step goes
 * strictly forward (the loader checked the links), so each node is visited
 * at most once and the walk ends. The order is the fixed depth-first one:
 * a closest-hit walk cannot follow the sort byte. Escape links are a fact of
 * the binary layout (layout/binary.h): a wide node's other children live in
 * its parent, so the wide layouts take the stack walk instead. */
CBVH_KERNEL int stackless_walk(const struct cbvh_file *restrict f, const struct cbvh_ray_ctx *restrict ray,
                               const int any, struct cbvh_best_hit *restrict best,
                               cbvh_query_stats *restrict stats)
{
    const cbvh_node *restrict nodes = cbvh_binary_nodes(f);
    const uint32_t end = f->info.node_count;
    struct cbvh_box_ray box;
    cbvh_box_ray_init(&box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint64_t visited = 0, tested = 0;
    int hit = 0;
    uint32_t i = 0;

    while (i < end) {
        const uint32_t word = nodes[i].word;
        float entry;
        visited++;
        if (!cbvh_box_ray_test(&box, f, CBVH_LAYOUT_BINARY, i, tmin, tmax, &entry)) {
            i += cbvh_node_span(word);
            continue;
        }
        if (cbvh_node_is_leaf(word)) {
            tested += cbvh_leaf_count(word);
            if (stackless_leaf(f, word, ray, any, entry <= tmin, &tmax, best)) {
                hit = 1;
                break;
            }
        }
        i++;
    }
    if (stats)
        cbvh_stats_add(stats, visited, tested);
    return hit;
}

void cbvh_closest_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,
                            struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    stackless_walk(f, ray, 0, best, stats);
}

int cbvh_any_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats)
{
    return stackless_walk(f, ray, 1, NULL, stats);
}
