/* tree.h: the node-layout interface: subtrees, children, boxes and leaves, whatever the node layout. */
#ifndef CBVH_LAYOUT_TREE_H
#define CBVH_LAYOUT_TREE_H

#include <stdint.h>

#include "common/file.h"
#include "layout/binary.h"
#include "layout/wide4.h"

/* Every walk, the tools and the tests see a tree through these functions
 * only; the layout module (layout/binary.h) alone knows the node bytes.
 *
 * - A subtree is named by a reference (cbvh_ref): the walks push references.
 *   Binary layout: the node index. Wide layout: the child reference of
 *   layout/wide4.h (a node index, or a leaf's packed triangle range).
 * - A box is named by a box id (< cbvh_tree_box_count). Binary layout: the
 *   node index, since every node carries its own box. Wide layout: 4 x the
 *   node + the slot, since a node carries its children's boxes.
 * - A node's children come as (box, ref) pairs, nearest first for a ray
 *   octant when asked. A reference is a leaf or has children, never both.
 * - The root's box may be absent (CBVH_NO_BOX): then every query enters it.
 *
 * `layout` is the file's f->layout, passed separately so a kernel instance
 * can make it a compile-time constant. */

typedef uint32_t cbvh_ref;

/* The most children a node has in any layout. */
#define CBVH_TREE_WIDTH 4u
#define CBVH_NO_BOX UINT32_MAX
/* Ask cbvh_tree_children for the stored (depth-first) order. */
#define CBVH_NO_OCTANT 8u

struct cbvh_child {
    uint32_t box;
    cbvh_ref ref;
};

static inline const cbvh_node *cbvh_binary_nodes(const struct cbvh_file *f)
{
    return (const cbvh_node *)f->nodes;
}

static inline cbvh_ref cbvh_tree_root(const struct cbvh_file *f, const uint32_t layout)
{
    (void)f;
    (void)layout;
    return 0;
}

static inline uint32_t cbvh_tree_root_box(const struct cbvh_file *f, const uint32_t layout)
{
    (void)f;
    return layout == CBVH_LAYOUT_WIDE4 ? CBVH_NO_BOX : 0;
}

/* Box ids are below this. */
static inline uint32_t cbvh_tree_box_count(const struct cbvh_file *f, const uint32_t layout)
{
    return layout == CBVH_LAYOUT_WIDE4 ? CBVH_W4_WIDTH * f->info.node_count : f->info.node_count;
}

static inline int cbvh_tree_is_leaf(const struct cbvh_file *f, const uint32_t layout, cbvh_ref r)
{
    if (layout == CBVH_LAYOUT_WIDE4)
        return cbvh_w4_ref_is_leaf(r);
    return cbvh_node_is_leaf(cbvh_binary_nodes(f)[r].word);
}

/* A leaf's cooked triangles [*first, *first + *count). */
static inline void cbvh_tree_leaf(const struct cbvh_file *f, const uint32_t layout, cbvh_ref r,
                                  uint32_t *first, uint32_t *count)
{
    if (layout == CBVH_LAYOUT_WIDE4) {
        *first = cbvh_w4_ref_first(r);
        *count = cbvh_w4_ref_count(r);
        return;
    }
    const uint32_t word = cbvh_binary_nodes(f)[r].word;
    *first = cbvh_leaf_first(word);
    *count = cbvh_leaf_count(word);
}

/* For a non-leaf r of the binary layout: 1 when a ray of `octant` should
 * visit its second stored child first (the sort byte's bit). */
static inline int cbvh_tree_second_first(const struct cbvh_file *f, const uint32_t layout, cbvh_ref r,
                                         uint32_t octant)
{
    (void)layout;
    return (int)(cbvh_binary_nodes(f)[r].word >> (CBVH_NODE_SORT_SHIFT + octant) & 1u);
}

/* The children of non-leaf r, in the order a ray of `octant` should visit
 * them (the precomputed sort), or in stored order for CBVH_NO_OCTANT.
 * Returns how many (at most CBVH_TREE_WIDTH). */
static inline uint32_t cbvh_tree_children(const struct cbvh_file *f, const uint32_t layout, cbvh_ref r,
                                          uint32_t octant, struct cbvh_child out[CBVH_TREE_WIDTH])
{
    if (layout == CBVH_LAYOUT_WIDE4) {
        const uint8_t *node = cbvh_w4_node(f->nodes, r);
        const uint64_t meta = cbvh_w4_meta(node);
        const uint32_t used = cbvh_w4_used(meta);
        const uint8_t *order = cbvh_wide4_orders[octant < CBVH_NO_OCTANT ? cbvh_w4_order(meta, octant) : 0];
        uint32_t n = 0;
        for (uint32_t k = 0; k < CBVH_W4_WIDTH; k++) {
            const uint32_t s = order[k];
            if (used >> s & 1u) {
                out[n].box = CBVH_W4_WIDTH * r + s;
                out[n].ref = cbvh_w4_child_ref(node, meta, s);
                n++;
            }
        }
        return n;
    }
    const cbvh_node *nodes = cbvh_binary_nodes(f);
    uint32_t first = r + 1u, second = cbvh_second_child(nodes, r);
    if (octant < CBVH_NO_OCTANT && cbvh_tree_second_first(f, layout, r, octant)) {
        uint32_t tmp = first;
        first = second;
        second = tmp;
    }
    out[0].box = out[0].ref = first;
    out[1].box = out[1].ref = second;
    return 2;
}

/* Grid coordinate k of box `box`: k = 0, 1, 2 its qmin x, y, z; 3, 4, 5 its qmax x, y, z. */
static inline uint32_t cbvh_tree_box_coord(const struct cbvh_file *f, const uint32_t layout, uint32_t box,
                                           uint32_t k)
{
    if (layout == CBVH_LAYOUT_WIDE4)
        return cbvh_w4_plane(cbvh_w4_node(f->nodes, box / CBVH_W4_WIDTH), k, box % CBVH_W4_WIDTH);
    return cbvh_node_q(&cbvh_binary_nodes(f)[box])[k];
}

/* The grid coordinates (as cbvh_tree_box_coord's) of the smallest box holding every box a walk tests
 * first: the root box (binary layout) or the root node's children's boxes (wide layout). Returns 0 when
 * there is no such box (a tree without nodes, or a root without children). */
static inline int cbvh_tree_top_box(const struct cbvh_file *f, const uint32_t layout, uint32_t q[6])
{
    struct cbvh_child c[CBVH_TREE_WIDTH];
    uint32_t n = 0;
    const uint32_t root_box = cbvh_tree_root_box(f, layout);
    if (f->info.node_count == 0)
        return 0;
    if (root_box != CBVH_NO_BOX) {
        c[0].box = root_box;
        n = 1;
    } else {
        n = cbvh_tree_children(f, layout, cbvh_tree_root(f, layout), CBVH_NO_OCTANT, c);
    }
    if (n == 0)
        return 0;
    for (uint32_t k = 0; k < 6; k++) {
        q[k] = cbvh_tree_box_coord(f, layout, c[0].box, k);
        for (uint32_t j = 1; j < n; j++) {
            const uint32_t v = cbvh_tree_box_coord(f, layout, c[j].box, k);
            q[k] = k < 3 ? (v < q[k] ? v : q[k]) : (v > q[k] ? v : q[k]);
        }
    }
    return 1;
}

/* Box `box` dequantized on the file's grid. */
static inline void cbvh_tree_box(const struct cbvh_file *f, const uint32_t layout, uint32_t box, float lo[3],
                                 float hi[3])
{
    for (uint32_t a = 0; a < 3; a++) {
        lo[a] = cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, a), f->grid_origin[a], f->grid_scale[a]);
        hi[a] =
            cbvh_dequantize(cbvh_tree_box_coord(f, layout, box, 3 + a), f->grid_origin[a], f->grid_scale[a]);
    }
}

#endif
