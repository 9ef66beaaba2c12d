/* report_exact.c: the report's reference layout: a cooked tree with float node boxes recomputed exactly from its triangles. */
#include <stdlib.h>

#include "common/file.h"
#include "query/stack_walk.h"
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

int exact_raycast(const exact_tree *tree, const cbvh_ray *ray, cbvh_hit *hit, cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    struct cbvh_best_hit best = { UINT32_MAX, 0.0f, 0.0f, 0.0f };
    hit->tri = CBVH_NO_HIT;
    if (!cbvh_ray_setup(&ctx, ray))
        return 0;
    /* counting is a constant in each instance, as in the library's walks */
    if (stats)
        cbvh_stack_walk(tree->file, &ctx, 0, ctx.sort_mask, 0, 0, 1, 0, tree->boxes, &best, stats);
    else
        cbvh_stack_walk(tree->file, &ctx, 0, ctx.sort_mask, 0, 0, 0, 0, tree->boxes, &best, NULL);
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
    if (stats)
        return cbvh_stack_walk(tree->file, &ctx, 0, ctx.sort_mask, 0, 1, 1, 0, tree->boxes, NULL, stats);
    return cbvh_stack_walk(tree->file, &ctx, 0, ctx.sort_mask, 0, 1, 0, 0, tree->boxes, NULL, NULL);
}
