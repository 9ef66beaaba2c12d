/* shape_walk.h: the tree walk of sweeps and overlaps: boxes tested by the query's own rule, leaves handed to it. */
#ifndef CBVH_QUERY_SHAPE_WALK_H
#define CBVH_QUERY_SHAPE_WALK_H

#include "layout/tree.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"

/* 1 when the walk enters the box of grid coordinates q (cbvh_tree_box_coord's order: qmin x, y, z, qmax
 * x, y, z), with *entry its key for the walk's limit (below). */
typedef int (*cbvh_shape_enter_fn)(void *query, const uint32_t q[6], float *entry);
/* The leaf's cooked triangles [first, first + count). Returns 1 to end the walk. */
typedef int (*cbvh_shape_leaf_fn)(void *query, uint32_t first, uint32_t count);

/* The grid coordinates of box `box` in cbvh_tree_box_coord's order. */
static inline void cbvh_shape_box_coords(const struct cbvh_file *f, const uint32_t layout, uint32_t box,
                                         uint32_t q[6])
{
    q[0] = cbvh_tree_box_coord(f, layout, box, 0);
    q[1] = cbvh_tree_box_coord(f, layout, box, 1);
    q[2] = cbvh_tree_box_coord(f, layout, box, 2);
    q[3] = cbvh_tree_box_coord(f, layout, box, 3);
    q[4] = cbvh_tree_box_coord(f, layout, box, 4);
    q[5] = cbvh_tree_box_coord(f, layout, box, 5);
}

/* Walks the subtrees whose boxes `enter` accepts, children in the
 * precomputed order of `octant` (CBVH_NO_OCTANT: stored order, which for the
 * binary layout is the file's depth-first order). A node's children are
 * tested at the node, so a missed child is never pushed; the others wait on
 * the stack with their entry keys, and one popped once *limit times
 * CBVH_BOX_PAD has fallen below its key is dropped without a second test:
 * for a sweep, whose best contact so far is *limit and whose keys are slab
 * entry distances, that is its box test again with the shorter motion.
 * Force-inlined so each query's callbacks are direct calls; `layout` is read
 * at run time (a sweep's cost is in its triangle tests). The loader checked
 * depth <= CBVH_MAX_DEPTH, and a node pushes at most CBVH_TREE_WIDTH - 1
 * references, so the stack cannot overflow. */
CBVH_KERNEL void cbvh_shape_walk(const struct cbvh_file *f, const uint32_t layout, uint32_t octant,
                                 cbvh_shape_enter_fn enter, cbvh_shape_leaf_fn leaf, void *query,
                                 const float *limit)
{
    struct {
        cbvh_ref ref;
        float entry;
    } stack[(CBVH_TREE_WIDTH - 1u) * CBVH_MAX_DEPTH];
    uint32_t sp = 0, q[6];
    cbvh_ref r = cbvh_tree_root(f, layout);
    const uint32_t root_box = cbvh_tree_root_box(f, layout);
    float entry;
    if (root_box != CBVH_NO_BOX) {
        cbvh_shape_box_coords(f, layout, root_box, q);
        if (!enter(query, q, &entry))
            return;
    }
    for (;;) {
        if (!cbvh_tree_is_leaf(f, layout, r)) {
            struct cbvh_child children[CBVH_TREE_WIDTH];
            const uint32_t n = cbvh_tree_children(f, layout, r, octant, children);
            cbvh_ref in[CBVH_TREE_WIDTH];
            float in_entry[CBVH_TREE_WIDTH];
            uint32_t m = 0;
            for (uint32_t k = 0; k < n; k++) { /* no branch on the test: its outcome is hard to predict */
                cbvh_shape_box_coords(f, layout, children[k].box, q);
                in[m] = children[k].ref;
                m += enter(query, q, &in_entry[m]) != 0;
            }
            if (m > 0) {
                for (uint32_t k = m; k-- > 1;) {
                    stack[sp].ref = in[k];
                    stack[sp].entry = in_entry[k];
                    sp++;
                }
                r = in[0];
                continue;
            }
        } else {
            uint32_t first, count;
            cbvh_tree_leaf(f, layout, r, &first, &count);
            if (leaf(query, first, count))
                return;
        }
        do {
            if (sp == 0)
                return;
            sp--;
        } while (!(stack[sp].entry <= *limit * CBVH_BOX_PAD));
        r = stack[sp].ref;
    }
}

#endif
