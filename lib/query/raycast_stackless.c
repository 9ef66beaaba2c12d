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
    const float origin[3] = {f->grid_origin[0], f->grid_origin[1], f->grid_origin[2]};
    const float scale[3] = {f->grid_scale[0], f->grid_scale[1], f->grid_scale[2]};
    const float org[3] = {ray->shear.org[0], ray->shear.org[1], ray->shear.org[2]};
    const float rcp[3] = {ray->rcp[0], ray->rcp[1], ray->rcp[2]};
    const struct cbvh_slab_select sel = cbvh_slab_select_of(ray->octant);
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
        if (!cbvh_ray_node(n, origin, scale, sel, org, rcp, tmin, tmax, &entry)) {
            i += cbvh_node_span(word);
            continue;
        }
        if (cbvh_node_is_leaf(word)) {
            if (any) {
                uint32_t count;
                int h = cbvh_leaf_any(f, word, &ray->shear, tmin, tmax, &count);
                if (counting)
                    tested += count;
                if (h) {
                    hit = 1;
                    break;
                }
            } else {
                uint32_t count = cbvh_leaf_closest(f, word, &ray->shear, tmin, &tmax, best);
                if (counting)
                    tested += count;
            }
        }
        i++;
    }
    if (counting) {
        stats->nodes_visited += visited;
        stats->triangles_tested += tested;
    }
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
