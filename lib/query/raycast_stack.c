/* raycast_stack.c: closest-hit and any-hit walks with a fixed stack, children ordered by the sort byte or not. */
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/tree.h"

/* One walk for every variant. mask is the ray's sort mask (sorted) or 0
 * (first child first): `word & mask` is the whole ordering decision. The
 * loader checked depth <= CBVH_MAX_DEPTH, and a walk pushes at most one
 * node per level, so the stack cannot overflow. */
CBVH_KERNEL int stack_walk(const struct cbvh_file *restrict f, const struct cbvh_ray_ctx *restrict ray, uint32_t mask,
                           const int any, const int counting, struct cbvh_best_hit *restrict best,
                           cbvh_query_stats *restrict stats)
{
    const cbvh_node *restrict nodes = f->nodes;
    struct cbvh_box_ray box;
    cbvh_box_ray_init(&box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint32_t stack[CBVH_MAX_DEPTH];
    uint32_t sp = 0, i = 0;
    uint64_t visited = 0, tested = 0;
    int hit = 0;

    for (;;) {
        const cbvh_node *n = &nodes[i];
        float entry;
        if (counting)
            visited++;
        if (cbvh_box_ray_test(&box, n, tmin, tmax, &entry)) {
            const uint32_t word = n->word;
            if (!cbvh_node_is_leaf(word)) {
                uint32_t near = i + 1u, far = cbvh_second_child(nodes, i);
                if (word & mask) {
                    uint32_t tmp = near;
                    near = far;
                    far = tmp;
                }
                stack[sp++] = far;
                i = near;
                continue;
            }
            if (cbvh_leaf_visit(f, word, ray, any, counting, &tmax, best, &tested)) {
                hit = 1;
                break;
            }
        }
        if (sp == 0)
            break;
        i = stack[--sp];
    }
    if (counting)
        cbvh_stats_add(stats, visited, tested);
    return hit;
}

void cbvh_closest_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted,
                        struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    const uint32_t mask = sorted ? ray->sort_mask : 0u;
    if (stats)
        stack_walk(f, ray, mask, 0, 1, best, stats);
    else
        stack_walk(f, ray, mask, 0, 0, best, NULL);
}

int cbvh_any_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted, cbvh_query_stats *stats)
{
    const uint32_t mask = sorted ? ray->sort_mask : 0u;
    if (stats)
        return stack_walk(f, ray, mask, 1, 1, NULL, stats);
    return stack_walk(f, ray, mask, 1, 0, NULL, NULL);
}
