/* exact_walk.c: the library's sorted walk on exact float node boxes, the reference of box quantization. */
#include "config.h" /* CBVH_HAVE_SIMD: the walk's leaves as the library runs them, so its time compares */

#include <stdlib.h>

#include "cbvh_internal.h"
#include "inspect/inspect.h"
#include "query/walk.h"

int cbvh_exact_tree_build(cbvh_exact_tree *tree, const cbvh_file *file)
{
    const uint32_t n = cbvh_tree_box_count(file, file->layout);
    float *boxes = malloc((size_t)n * 6 * sizeof(float)), root[6];
    if (!boxes)
        return 0;
    cbvh_exact_boxes(file, boxes, root);
    tree->file = file;
    tree->boxes = boxes;
    tree->box_count = n;
    return 1;
}

void cbvh_exact_tree_free(cbvh_exact_tree *tree)
{
    free(tree->boxes);
    tree->boxes = NULL;
}

static const struct cbvh_walk_mode exact_closest = {.order = CBVH_WALK_SORTED};
static const struct cbvh_walk_mode exact_any = {.order = CBVH_WALK_SORTED, .any = 1};

/* The sorted walk on the exact float boxes: same tree, same order, same triangle test. */
static int exact_walk(const cbvh_exact_tree *tree, const struct cbvh_ray_ctx *ctx,
                      const struct cbvh_walk_mode mode, struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    const struct cbvh_file *f = tree->file;
    return cbvh_walk(f, f->layout, ctx, cbvh_tree_root(f, f->layout), cbvh_tree_root_box(f, f->layout), mode,
                     tree->boxes, best, stats);
}

int cbvh_exact_raycast(const cbvh_exact_tree *tree, const cbvh_ray *ray, cbvh_hit *hit,
                       cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    hit->tri = CBVH_NO_HIT;
    if (!cbvh_ray_setup(&ctx, ray))
        return 0;
    exact_walk(tree, &ctx, exact_closest, &best, stats);
    if (best.tri == UINT32_MAX)
        return 0;
    hit->tri = cbvh_original_id(tree->file, best.tri);
    hit->t = cbvh_t_frame_out(&ctx.t_frame, best.t);
    hit->u = best.u;
    hit->v = best.v;
    return 1;
}

int cbvh_exact_occluded(const cbvh_exact_tree *tree, const cbvh_ray *ray, cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    if (!cbvh_ray_setup(&ctx, ray))
        return 0;
    return exact_walk(tree, &ctx, exact_any, NULL, stats);
}
