/* shape_walk.h: the tree walk of sweeps and overlaps: boxes tested by the query's own rule, leaves handed to it. */
#ifndef CBVH_QUERY_SHAPE_WALK_H
#define CBVH_QUERY_SHAPE_WALK_H

#include "layout/tree.h"
#include "query/ray_setup.h"

/* 1 when the walk enters the box [lo, hi] (dequantized on the file's grid). */
typedef int (*cbvh_shape_enter_fn)(void *query, const float lo[3], const float hi[3]);
/* The leaf's cooked triangles [first, first + count). Returns 1 to end the walk. */
typedef int (*cbvh_shape_leaf_fn)(void *query, uint32_t first, uint32_t count);

/* Walks the subtrees whose boxes `enter` accepts, children in the
 * precomputed order of `octant` (CBVH_NO_OCTANT: stored order, which for the
 * binary layout is the file's depth-first order). A box is tested when its
 * reference is popped, so `enter` sees the query's state as the leaves before
 * left it (a sweep's shrinking distance). Force-inlined so each query's
 * callbacks are direct calls; `layout` is read at run time (a sweep's cost is
 * in its triangle tests). */
CBVH_KERNEL void cbvh_shape_walk(const struct cbvh_file *f, const uint32_t layout, uint32_t octant,
                                 cbvh_shape_enter_fn enter, cbvh_shape_leaf_fn leaf, void *query)
{
    struct cbvh_child stack[(CBVH_TREE_WIDTH - 1u) * CBVH_MAX_DEPTH + 1u];
    uint32_t sp = 0;
    struct cbvh_child at = {cbvh_tree_root_box(f, layout), cbvh_tree_root(f, layout)};
    for (;;) {
        int in = 1;
        if (at.box != CBVH_NO_BOX) {
            float lo[3], hi[3];
            cbvh_tree_box(f, layout, at.box, lo, hi);
            in = enter(query, lo, hi);
        }
        if (in && !cbvh_tree_is_leaf(f, layout, at.ref)) {
            struct cbvh_child children[CBVH_TREE_WIDTH];
            const uint32_t n = cbvh_tree_children(f, layout, at.ref, octant, children);
            for (uint32_t k = n; k-- > 1;)
                stack[sp++] = children[k];
            at = children[0];
            continue;
        }
        if (in) {
            uint32_t first, count;
            cbvh_tree_leaf(f, layout, at.ref, &first, &count);
            if (leaf(query, first, count))
                return;
        }
        if (sp == 0)
            return;
        at = stack[--sp];
    }
}

#endif
