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

/* A float box against the ray, with ray_box.h's slab test and octant plane choice. */
static inline int exact_box_test(const float *restrict box, struct cbvh_slab_select sel, const float org[3],
                                 const float rcp[3], float tmin, float tmax, float *entry)
{
    return cbvh_slab_test(box[sel.near_x], box[sel.near_y], box[sel.near_z], box[sel.far_x], box[sel.far_y],
                          box[sel.far_z], org, rcp, tmin, tmax, entry);
}

/* The sorted walk of lib/query/raycast_stack.c over float boxes: both children
 * tested at the parent, the nearer by the sort byte first, the farther pushed
 * with its entry distance and dropped on pop once beyond tmax; the same leaf
 * step and the same counters. Only the boxes differ. */
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
    float tmax = ray->tmax, entry0, entry1;
    struct {
        uint32_t node;
        float entry;
    } stack[CBVH_MAX_DEPTH];
    uint32_t sp = 0, i = 0;
    uint64_t visited = 1, tested = 0;
    int hit = 0;
    if (!exact_box_test(boxes, sel, org, rcp, tmin, tmax, &entry0))
        goto done;
    for (;;) {
        const uint32_t word = nodes[i].word;
        if (!cbvh_node_is_leaf(word)) {
            uint32_t near = i + 1u, far = cbvh_second_child(nodes, i);
            const int h0 = exact_box_test(boxes + 6 * (size_t)near, sel, org, rcp, tmin, tmax, &entry0);
            const int h1 = exact_box_test(boxes + 6 * (size_t)far, sel, org, rcp, tmin, tmax, &entry1);
            visited += 2;
            if (h0 && h1) {
                if (word & mask) {
                    uint32_t tmp = near;
                    near = far;
                    far = tmp;
                    entry1 = entry0;
                }
                stack[sp].node = far;
                stack[sp].entry = entry1;
                sp++;
                i = near;
                continue;
            }
            if (h0 || h1) {
                i = h0 ? near : far;
                continue;
            }
        } else if (cbvh_leaf_visit(f, word, ray, any, 1, &tmax, best, &tested)) {
            hit = 1;
            break;
        }
        do {
            if (sp == 0)
                goto done;
            sp--;
        } while (!(stack[sp].entry <= tmax * CBVH_BOX_PAD));
        i = stack[sp].node;
    }
done:
    if (stats)
        cbvh_stats_add(stats, visited, tested);
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
