/* report_exact.c: the report's reference layout: a cooked tree with float node boxes recomputed exactly from its triangles. */
#include <stdlib.h>

#include "common/file.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"
#include "query/tree.h"
#include "report_exact.h"
#include "tree_stats.h"

int exact_tree_build(exact_tree *tree, const cbvh_file *file)
{
    uint32_t n = file->info.node_count;
    float *boxes = malloc((size_t)n * 6 * sizeof(float));
    if (!boxes)
        return 0;
    tree_exact_boxes(file, boxes);
    tree->file = file;
    tree->boxes = boxes;
    tree->node_count = n;
    return 1;
}

void exact_tree_free(exact_tree *tree)
{
    free(tree->boxes);
    tree->boxes = NULL;
}

/* The stack walk of lib/query/raycast_stack.c over float boxes: same visit
 * order (sort byte), same slab and triangle tests, same counters. */
static int exact_walk(const exact_tree *tree, const struct cbvh_ray_ctx *ray, int any, struct cbvh_best_hit *best,
                      cbvh_query_stats *stats)
{
    const struct cbvh_file *f = tree->file;
    const cbvh_node *restrict nodes = f->nodes;
    const float *restrict boxes = tree->boxes;
    const float org[3] = { ray->shear.org[0], ray->shear.org[1], ray->shear.org[2] };
    const float rcp[3] = { ray->rcp[0], ray->rcp[1], ray->rcp[2] };
    const struct cbvh_slab_select sel = cbvh_slab_select_of(ray->octant);
    const uint32_t mask = ray->sort_mask;
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint32_t stack[CBVH_MAX_DEPTH];
    uint32_t sp = 0, i = 0;
    uint64_t visited = 0, tested = 0;
    int hit = 0;
    for (;;) {
        const float *b = boxes + 6 * (size_t)i;
        float entry;
        visited++;
        if (cbvh_slab_test(b[sel.near_x], b[sel.near_y], b[sel.near_z], b[sel.far_x], b[sel.far_y], b[sel.far_z], org,
                           rcp, tmin, tmax, &entry)) {
            const uint32_t word = nodes[i].word;
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
                hit = cbvh_leaf_any(f, word, &ray->shear, tmin, tmax, &count);
                tested += count;
                if (hit)
                    break;
            } else {
                tested += cbvh_leaf_closest(f, word, &ray->shear, tmin, &tmax, best);
            }
        }
        if (sp == 0)
            break;
        i = stack[--sp];
    }
    if (stats) {
        stats->nodes_visited += visited;
        stats->triangles_tested += tested;
    }
    return hit;
}

int exact_raycast(const exact_tree *tree, const cbvh_ray *ray, cbvh_hit *hit, cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    struct cbvh_best_hit best = { UINT32_MAX, 0.0f, 0.0f, 0.0f };
    hit->tri = CBVH_NO_HIT;
    if (!cbvh_ray_setup(&ctx, ray))
        return 0;
    exact_walk(tree, &ctx, 0, &best, stats);
    if (best.tri == UINT32_MAX)
        return 0;
    hit->tri = cbvh_original_id(tree->file, best.tri);
    hit->t = best.t;
    hit->u = best.u;
    hit->v = best.v;
    return 1;
}

int exact_occluded(const exact_tree *tree, const cbvh_ray *ray, cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    if (!cbvh_ray_setup(&ctx, ray))
        return 0;
    return exact_walk(tree, &ctx, 1, NULL, stats);
}
