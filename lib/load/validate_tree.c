/* validate_tree.c: checks every node in one linear pass (format spec section 5): boxes, subtree links, depth, leaf ranges. */
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

static uint32_t subtree_size(uint32_t word)
{
    return cbvh_node_is_leaf(word) ? 1u : cbvh_node_subtree_size(word);
}

/* The node at fault when some box has qmin > qmax (only a failing file pays for this second pass). */
static cbvh_result find_bad_box(const cbvh_node *nodes, uint32_t n, cbvh_error *err)
{
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            if (nodes[i].qmin[a] > nodes[i].qmax[a])
                return CORRUPT("node %u: qmin %u > qmax %u on axis %d", i, nodes[i].qmin[a], nodes[i].qmax[a], a);
    return CBVH_OK;
}

static cbvh_result check_leaf(uint32_t i, uint32_t word, uint32_t next_triangle, uint32_t triangle_count,
                              uint32_t max_leaf, cbvh_error *err)
{
    const uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
    if (first != next_triangle)
        return CORRUPT("node %u: leaf starts at triangle %u, the previous leaf ended at %u", i, first, next_triangle);
    if (count > max_leaf)
        return CORRUPT("node %u: leaf holds %u triangles, more than max_leaf_size %u", i, count, max_leaf);
    if (count > triangle_count - first)
        return CORRUPT("node %u: leaf triangles [%u, %u) run past triangle_count %u", i, first, first + count,
                       triangle_count);
    return CBVH_OK;
}

/* Internal node i of subtree size s: first child i + 1, second child c = its escape, which must lie
 * inside [i, i + s) and end exactly at i + s. With the root's size equal to node_count, these local
 * checks make every subtree range nest in its parent's, so the children's ranges tile their parent's,
 * every node belongs to the tree and every escape link points strictly forward. */
static cbvh_result check_internal(const cbvh_node *nodes, uint32_t i, uint32_t s, cbvh_error *err)
{
    if (s < 3)
        return CORRUPT("node %u: internal node with subtree size %u (at least 3)", i, s);
    const uint32_t first_size = subtree_size(nodes[i + 1].word);
    if (first_size < 1 || first_size > s - 2)
        return CORRUPT("node %u: first child %u has subtree size %u, leaving no room for a second child within %u", i,
                       i + 1, first_size, s);
    const uint32_t c = i + 1 + first_size;
    if (subtree_size(nodes[c].word) != i + s - c)
        return CORRUPT("node %u: subtree size %u, but its parent leaves it nodes [%u, %u)", c,
                       subtree_size(nodes[c].word), c, i + s);
    return CBVH_OK;
}

/* One pass in node order, which is depth-first order. A node's parent comes before it, so when node i
 * is reached its range [i, i + s) is already known to lie inside its parent's: reading nodes[i + 1] and
 * the second child is in bounds. Depth comes from a stack of the ends of the enclosing subtrees, which
 * the tiling makes end exactly where a later node starts. The loop only raises flags; the functions
 * above say what is wrong, so the hot path carries no message formatting. */
cbvh_result cbvh_validate_tree(const struct cbvh_file *f, cbvh_error *err)
{
    const cbvh_node *restrict nodes = f->nodes;
    const uint32_t node_count = f->info.node_count;
    const uint32_t triangle_count = f->info.triangle_count;
    const uint32_t max_leaf = f->info.max_leaf_size;
    const uint32_t header_depth = f->info.depth;
    if (subtree_size(nodes[0].word) != node_count)
        return CORRUPT("node 0: subtree size %u, but its parent leaves it nodes [0, %u)", subtree_size(nodes[0].word),
                       node_count);
    /* ends[0] is a sentinel no node index reaches, so the depth of a node is `top` */
    uint32_t ends[CBVH_MAX_DEPTH + 1];
    ends[0] = UINT32_MAX;
    uint32_t top = 1, next_triangle = 0, depth = 0, bad_box = 0;
    for (uint32_t i = 0; i < node_count; i++) {
        const cbvh_node n = nodes[i];
        bad_box |= (uint32_t)(n.qmin[0] > n.qmax[0]) | (uint32_t)(n.qmin[1] > n.qmax[1]) |
                   (uint32_t)(n.qmin[2] > n.qmax[2]);
        while (ends[top - 1] == i)
            top--;
        if (top > depth) {
            depth = top;
            if (depth > header_depth)
                return CORRUPT("node %u: at depth %u, deeper than the header's depth %u", i, depth, header_depth);
        }
        const uint32_t w = n.word;
        if (cbvh_node_is_leaf(w)) {
            const uint32_t first = cbvh_leaf_first(w), count = cbvh_leaf_count(w);
            if ((first != next_triangle) | (count > max_leaf) | (count > triangle_count - first))
                return check_leaf(i, w, next_triangle, triangle_count, max_leaf, err);
            next_triangle += count;
        } else {
            const uint32_t s = cbvh_node_subtree_size(w);
            if (s < 3)
                return check_internal(nodes, i, s, err);
            const uint32_t first_size = subtree_size(nodes[i + 1].word);
            const uint32_t c = i + 1 + first_size;
            if (first_size > s - 2 || subtree_size(nodes[c].word) != i + s - c)
                return check_internal(nodes, i, s, err);
            ends[top++] = i + s;
        }
    }
    if (bad_box)
        return find_bad_box(nodes, node_count, err);
    if (depth != header_depth)
        return CORRUPT("the tree's depth is %u, the header says %u", depth, header_depth);
    if (next_triangle != triangle_count)
        return CORRUPT("leaves cover triangles [0, %u), triangle_count is %u", next_triangle, triangle_count);
    return CBVH_OK;
}
