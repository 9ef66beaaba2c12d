/* validate_wide4.c: checks every wide4 node in one linear, resumable pass (format spec section 5.2): slots,
 * links, levels, leaves. */
#include "common/error.h"
#include "layout/wide4.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

/* One node's own bytes: used slots, their boxes and leaf sizes, unused slots all zero, orders in range. */
static cbvh_result check_slots(const uint8_t *node, uint32_t i, uint64_t meta, uint32_t max_leaf,
                               cbvh_error *err)
{
    const uint32_t used = cbvh_w4_used(meta), internal = cbvh_w4_internal(meta);
    if (used == 0)
        return CORRUPT("node %u: no slot in use", i);
    if (internal & ~used)
        return CORRUPT("node %u: slots 0x%x are internal but not in use (in use: 0x%x)", i, internal & ~used,
                       used);
    for (uint32_t s = 0; s < CBVH_W4_WIDTH; s++) {
        const uint32_t nibble = (uint32_t)(meta >> (4u * s)) & 0xFu;
        if (!(used >> s & 1u) || (internal >> s & 1u)) {
            if (nibble != 0)
                return CORRUPT("node %u: slot %u is %s but has a triangle count field of %u (must be 0)", i,
                               s, used >> s & 1u ? "internal" : "unused", nibble);
        } else if (nibble + 1u > max_leaf) {
            return CORRUPT("node %u: slot %u is a leaf of %u triangles, more than max_leaf_size %u", i, s,
                           nibble + 1u, max_leaf);
        }
        for (uint32_t k = 0; k < 3; k++) {
            const uint32_t lo = cbvh_w4_plane(node, k, s), hi = cbvh_w4_plane(node, 3 + k, s);
            if (!(used >> s & 1u) && (lo | hi) != 0)
                return CORRUPT("node %u: unused slot %u has a nonzero box", i, s);
            if (lo > hi)
                return CORRUPT("node %u: slot %u: qmin %u > qmax %u on axis %u", i, s, lo, hi, k);
        }
    }
    for (uint32_t k = 0; k < 8; k++)
        if (cbvh_w4_order(meta, k) >= CBVH_W4_ORDERS)
            return CORRUPT("node %u: order index %u for octant %u is not below %u", i, cbvh_w4_order(meta, k),
                           k, CBVH_W4_ORDERS);
    return CBVH_OK;
}

/* With CBVH_INCOMPAT_W4_DEPTH_FIRST the leaves hold the triangles in depth-first order (spec section 5.2):
 * node i's leaf slots from first_triangle on, then its internal children's subtrees in slot order. Run
 * once the linear pass has proved the nodes a tree of the header's depth whose leaves hold triangle_count
 * triangles in all, so the walk ends and its stack (CBVH_W4_WIDTH - 1 per level) cannot overflow. */
static cbvh_result check_depth_first_triangles(const struct cbvh_file *f, cbvh_error *err)
{
    uint32_t stack[(CBVH_W4_WIDTH - 1u) * CBVH_MAX_DEPTH + 1u], sp = 0, next = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const uint32_t i = stack[--sp];
        const uint8_t *node = cbvh_w4_node(f->nodes, i);
        const uint64_t meta = cbvh_w4_meta(node);
        const uint32_t used = cbvh_w4_used(meta), internal = cbvh_w4_internal(meta);
        if (cbvh_w4_first_triangle(node) != next)
            return CORRUPT("node %u: first_triangle %u, but the leaves before it in depth-first order end at "
                           "triangle %u",
                           i, cbvh_w4_first_triangle(node), next);
        for (uint32_t s = 0; s < CBVH_W4_WIDTH; s++)
            if ((used & ~internal) >> s & 1u)
                next += cbvh_w4_count(meta, s);
        /* the internal children, pushed last first so the first is walked next */
        for (uint32_t k = cbvh_w4_popcount(internal); k-- > 0;)
            stack[sp++] = cbvh_w4_first_child(node) + k;
    }
    return CBVH_OK;
}

/* Breadth-first allocation makes the tree checkable in one pass: node i's
 * internal children MUST be the next unallocated node indices (first_child =
 * 1 + the internal children of nodes 0..i-1) and lie after i, and its leaves
 * the next cooked triangles (or, with CBVH_INCOMPAT_W4_DEPTH_FIRST, the ones
 * check_depth_first_triangles expects, checked at the end). So every node but the root is the child of
 * exactly one node with a smaller index (no cycle, no sharing, every walk
 * ends), and the leaves tile the triangles. The nodes of one level are
 * consecutive, and the next level is what they allocated: `level_end` tracks
 * the depth without a stack. */
cbvh_result cbvh_w4_tree_check(const struct cbvh_file *f, void *walk_state, uint32_t begin, uint32_t end,
                               cbvh_error *err)
{
    cbvh_w4_walk *restrict w = walk_state;
    const uint32_t node_count = f->info.node_count, triangle_count = f->info.triangle_count;
    const uint32_t max_leaf = f->info.max_leaf_size, header_depth = f->info.depth;
    if (begin == 0) {
        if (triangle_count > CBVH_W4_MAX_TRIANGLES)
            return CORRUPT("triangle_count %u is more than a wide4 file holds (%u)", triangle_count,
                           CBVH_W4_MAX_TRIANGLES);
        if (max_leaf > CBVH_W4_MAX_LEAF)
            return CORRUPT("max_leaf_size %u is more than a wide4 leaf holds (%u)", max_leaf,
                           CBVH_W4_MAX_LEAF);
        w->next_child = 1;
        w->level_end = 1;
        w->depth = 1;
    }
    for (uint32_t i = begin; i < end; i++) {
        const uint8_t *node = cbvh_w4_node(f->nodes, i);
        const uint64_t meta = cbvh_w4_meta(node);
        cbvh_result r = check_slots(node, i, meta, max_leaf, err);
        if (r != CBVH_OK)
            return r;
        if (i == w->level_end) {
            if (w->next_child == i)
                return CORRUPT("node %u: no node before it has it as a child", i);
            w->depth++;
            w->level_end = w->next_child;
            if (w->depth > header_depth)
                return CORRUPT("node %u: at depth %u, deeper than the header's depth %u", i, w->depth,
                               header_depth);
        }
        const uint32_t first_child = cbvh_w4_first_child(node), first_triangle = cbvh_w4_first_triangle(node);
        if (first_child != w->next_child)
            return CORRUPT("node %u: first_child %u, but the nodes before it leave the next child at %u", i,
                           first_child, w->next_child);
        if (first_triangle != w->next_triangle && !(f->info.incompat_flags & CBVH_INCOMPAT_W4_DEPTH_FIRST))
            return CORRUPT("node %u: first_triangle %u, but the leaves before it end at triangle %u", i,
                           first_triangle, w->next_triangle);
        const uint32_t used = cbvh_w4_used(meta), internal = cbvh_w4_internal(meta);
        const uint32_t children = cbvh_w4_popcount(internal);
        if (children > node_count - first_child)
            return CORRUPT("node %u: children [%u, %u) run past node_count %u", i, first_child,
                           first_child + children, node_count);
        w->next_child += children;
        for (uint32_t s = 0; s < CBVH_W4_WIDTH; s++) {
            if (!((used & ~internal) >> s & 1u))
                continue;
            const uint32_t count = cbvh_w4_count(meta, s);
            if (count > triangle_count - w->next_triangle)
                return CORRUPT("node %u: slot %u's triangles [%u, %u) run past triangle_count %u", i, s,
                               w->next_triangle, w->next_triangle + count, triangle_count);
            w->next_triangle += count;
        }
    }
    return CBVH_OK;
}

cbvh_result cbvh_w4_tree_finish(const struct cbvh_file *f, const cbvh_w4_walk *w, cbvh_error *err)
{
    if (w->next_child != f->info.node_count)
        return CORRUPT("the nodes' children cover nodes [1, %u), node_count is %u", w->next_child,
                       f->info.node_count);
    if (w->depth != f->info.depth)
        return CORRUPT("the tree's depth is %u, the header says %u", w->depth, f->info.depth);
    if (w->next_triangle != f->info.triangle_count)
        return CORRUPT("leaves cover triangles [0, %u), triangle_count is %u", w->next_triangle,
                       f->info.triangle_count);
    if (f->info.incompat_flags & CBVH_INCOMPAT_W4_DEPTH_FIRST)
        return check_depth_first_triangles(f, err);
    return CBVH_OK;
}
