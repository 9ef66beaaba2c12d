/* validate_tree.c: checks every node in one linear, resumable pass (format spec section 5): boxes, links,
 * depth, leaves. */
#include "common/error.h"
#include "layout/binary.h"
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
                return CORRUPT("node %u: qmin %u > qmax %u on axis %d", i, nodes[i].qmin[a], nodes[i].qmax[a],
                               a);
    return CBVH_OK;
}

static cbvh_result check_leaf(uint32_t i, uint32_t word, uint32_t next_triangle, uint32_t triangle_count,
                              uint32_t max_leaf, cbvh_error *err)
{
    const uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
    if (first != next_triangle)
        return CORRUPT("node %u: leaf starts at triangle %u, the previous leaf ended at %u", i, first,
                       next_triangle);
    if (count > max_leaf)
        return CORRUPT("node %u: leaf holds %u triangles, more than max_leaf_size %u", i, count, max_leaf);
    if (count > triangle_count - first)
        return CORRUPT("node %u: leaf triangles [%u, %u) run past triangle_count %u", i, first, first + count,
                       triangle_count);
    return CBVH_OK;
}

/* One pass in node order, which is depth-first order, reading only node i and node i + 1.
 * An internal node i of subtree size s >= 3 has its first child at i + 1, of size s1 with
 * 1 <= s1 <= s - 2, and its second child at c = i + 1 + s1, which must end exactly at i + s: c is
 * pushed and checked when the walk reaches it, right after the first child's subtree, that is right
 * after a leaf. With the root's size equal to node_count, these checks make the children's ranges tile
 * their parent's, every node belong to the tree and every escape link point strictly forward. The
 * stack holds one pending second child per level, so the depth limit bounds it. The walk's state lives
 * in `walk_state` (a cbvh_tree_walk) between ranges; the loop keeps it in locals. */
cbvh_result cbvh_tree_check(const struct cbvh_file *f, void *walk_state, uint32_t begin, uint32_t end,
                            cbvh_error *err)
{
    cbvh_tree_walk *restrict w = walk_state;
    const cbvh_node *restrict nodes = (const cbvh_node *)f->nodes;
    const uint32_t node_count = f->info.node_count;
    const uint32_t triangle_count = f->info.triangle_count;
    const uint32_t max_leaf = f->info.max_leaf_size;
    const uint32_t header_depth = f->info.depth;
    if (begin == 0 && (f->info.incompat_flags & CBVH_INCOMPAT_W4_DEPTH_FIRST))
        return CORRUPT("incompat_flags 0x%x: the wide4 depth-first flag is set on a binary-layout file",
                       CBVH_INCOMPAT_W4_DEPTH_FIRST);
    if (begin == 0 && node_count > CBVH_BINARY_MAX_NODES)
        return CORRUPT("node_count %u is more than a binary-layout file holds (%u)", node_count,
                       CBVH_BINARY_MAX_NODES);
    if (begin == 0 && triangle_count > CBVH_BINARY_MAX_TRIANGLES)
        return CORRUPT("triangle_count %u is more than a binary-layout file holds (%u)", triangle_count,
                       CBVH_BINARY_MAX_TRIANGLES);
    if (begin == 0 && subtree_size(nodes[0].word) != node_count)
        return CORRUPT("node 0: subtree size %u, but its parent leaves it nodes [0, %u)",
                       subtree_size(nodes[0].word), node_count);
    uint32_t top = w->top, next_triangle = w->next_triangle, max_depth = w->max_depth;
    uint32_t depth = w->current_depth, after_leaf = w->after_leaf, bad_box = w->bad_box;
    cbvh_result r = CBVH_OK;
    for (uint32_t i = begin; i < end; i++) {
        const cbvh_node n = nodes[i];
        bad_box |= (uint32_t)(n.qmin[0] > n.qmax[0]) | (uint32_t)(n.qmin[1] > n.qmax[1]) |
                   (uint32_t)(n.qmin[2] > n.qmax[2]);
        const uint32_t word = n.word;
        if (after_leaf) { /* node i is the second child of the innermost pending internal node */
            if (top == 0 || w->begin[top - 1] != i) {
                r = CORRUPT("node %u: the walk reaches it where no subtree starts", i);
                break;
            }
            top--;
            if (subtree_size(word) != w->end[top] - i) {
                r = CORRUPT("node %u: subtree size %u, but its parent leaves it nodes [%u, %u)", i,
                            subtree_size(word), i, w->end[top]);
                break;
            }
            depth = w->depth[top];
        } else {
            depth++; /* the root, or the first child of node i - 1 */
        }
        if (depth > max_depth) {
            max_depth = depth;
            if (depth > header_depth) {
                r = CORRUPT("node %u: at depth %u, deeper than the header's depth %u", i, depth,
                            header_depth);
                break;
            }
        }
        after_leaf = cbvh_node_is_leaf(word);
        if (after_leaf) {
            const uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
            if ((first != next_triangle) | (count > max_leaf) | (count > triangle_count - first)) {
                r = check_leaf(i, word, next_triangle, triangle_count, max_leaf, err);
                break;
            }
            next_triangle += count;
            continue;
        }
        const uint32_t s = cbvh_node_subtree_size(word);
        if (s < 3) {
            r = CORRUPT("node %u: internal node with subtree size %u (at least 3)", i, s);
            break;
        }
        /* i + s lies inside the parent's range, so node i + 1 exists */
        const uint32_t first_size = subtree_size(nodes[i + 1].word);
        if (first_size < 1 || first_size > s - 2) {
            r = CORRUPT(
                "node %u: first child %u has subtree size %u, leaving no room for a second child within %u",
                i, i + 1, first_size, s);
            break;
        }
        /* top < depth <= 64 before this push */
        w->begin[top] = i + 1 + first_size;
        w->end[top] = i + s;
        w->depth[top] = depth + 1;
        top++;
    }
    w->top = top;
    w->next_triangle = next_triangle;
    w->max_depth = max_depth;
    w->current_depth = depth;
    w->after_leaf = after_leaf;
    w->bad_box = bad_box;
    return r;
}

cbvh_result cbvh_tree_finish(const struct cbvh_file *f, const cbvh_tree_walk *w, cbvh_error *err)
{
    if (w->bad_box)
        return find_bad_box((const cbvh_node *)f->nodes, f->info.node_count, err);
    if (w->max_depth != f->info.depth)
        return CORRUPT("the tree's depth is %u, the header says %u", w->max_depth, f->info.depth);
    if (w->next_triangle != f->info.triangle_count)
        return CORRUPT("leaves cover triangles [0, %u), triangle_count is %u", w->next_triangle,
                       f->info.triangle_count);
    return CBVH_OK;
}
