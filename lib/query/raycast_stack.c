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
    const float origin[3] = {f->grid_origin[0], f->grid_origin[1], f->grid_origin[2]};
    const float scale[3] = {f->grid_scale[0], f->grid_scale[1], f->grid_scale[2]};
    const float org[3] = {ray->shear.org[0], ray->shear.org[1], ray->shear.org[2]};
    const float rcp[3] = {ray->rcp[0], ray->rcp[1], ray->rcp[2]};
    const struct cbvh_slab_select sel = cbvh_slab_select_of(ray->octant);
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
        if (cbvh_ray_node(n, origin, scale, sel, org, rcp, tmin, tmax, &entry)) {
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
        if (sp == 0)
            break;
        i = stack[--sp];
    }
    if (counting) {
        stats->nodes_visited += visited;
        stats->triangles_tested += tested;
    }
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
