/* validate_tree.c: checks every node once, iteratively (format spec section 5): boxes, subtree links, depth, leaf ranges. */
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

/* A subtree still to visit: the node range [begin, end) it must fill exactly, and its depth. */
typedef struct pending {
    uint32_t begin, end, depth;
} pending;

static uint32_t subtree_size(uint32_t word)
{
    return cbvh_node_is_leaf(word) ? 1u : cbvh_node_subtree_size(word);
}

/* Walks the ranges depth-first. Ranges are popped in increasing node order (the first child's range is
 * pushed last), so each node is visited exactly once, leaves come in file order, and the stack never
 * holds more than one pending range per level. */
cbvh_result cbvh_validate_tree(const struct cbvh_file *f, cbvh_error *err)
{
    const cbvh_node *restrict nodes = f->nodes;
    const uint32_t node_count = f->info.node_count;
    const uint32_t triangle_count = f->info.triangle_count;
    const uint32_t max_leaf = f->info.max_leaf_size;
    const uint32_t header_depth = f->info.depth;
    pending stack[CBVH_MAX_DEPTH + 1];
    uint32_t top = 0, next_triangle = 0, depth = 0;
    stack[top++] = (pending){ 0, node_count, 1 };
    while (top > 0) {
        const pending p = stack[--top];
        const uint32_t i = p.begin;
        const cbvh_node n = nodes[i];
        for (int a = 0; a < 3; a++)
            if (n.qmin[a] > n.qmax[a])
                return CORRUPT("node %u: qmin %u > qmax %u on axis %d", i, n.qmin[a], n.qmax[a], a);
        if (p.depth > depth)
            depth = p.depth;
        if (depth > header_depth)
            return CORRUPT("node %u: at depth %u, deeper than the header's depth %u", i, p.depth, header_depth);
        if (subtree_size(n.word) != p.end - p.begin)
            return CORRUPT("node %u: subtree size %u, but its parent leaves it nodes [%u, %u)", i,
                           subtree_size(n.word), p.begin, p.end);
        if (cbvh_node_is_leaf(n.word)) {
            uint32_t first = cbvh_leaf_first(n.word), count = cbvh_leaf_count(n.word);
            if (first != next_triangle)
                return CORRUPT("node %u: leaf starts at triangle %u, the previous leaf ended at %u", i, first,
                               next_triangle);
            if (count > max_leaf)
                return CORRUPT("node %u: leaf holds %u triangles, more than max_leaf_size %u", i, count, max_leaf);
            if (count > triangle_count - first)
                return CORRUPT("node %u: leaf triangles [%u, %u) run past triangle_count %u", i, first, first + count,
                               triangle_count);
            next_triangle = first + count;
            continue;
        }
        const uint32_t s = p.end - p.begin;
        if (s < 3)
            return CORRUPT("node %u: internal node with subtree size %u (at least 3)", i, s);
        /* first child [i+1, c), second child [c, i+s): c must leave room for the second child */
        const uint32_t first_size = subtree_size(nodes[i + 1].word);
        if (first_size < 1 || first_size > s - 2)
            return CORRUPT("node %u: first child %u has subtree size %u, leaving no room for a second child within %u",
                           i, i + 1, first_size, s);
        const uint32_t c = i + 1 + first_size;
        stack[top++] = (pending){ c, p.end, p.depth + 1 };
        stack[top++] = (pending){ i + 1, c, p.depth + 1 };
    }
    if (depth != header_depth)
        return CORRUPT("the tree's depth is %u, the header says %u", depth, header_depth);
    if (next_triangle != triangle_count)
        return CORRUPT("leaves cover triangles [0, %u), triangle_count is %u", next_triangle, triangle_count);
    return CBVH_OK;
}
