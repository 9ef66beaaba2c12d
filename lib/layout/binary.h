/* binary.h: the binary node layout (NODES encoding Q16, spec section 5): every fact about its node bytes. */
#ifndef CBVH_LAYOUT_BINARY_H
#define CBVH_LAYOUT_BINARY_H

#include <stdint.h>

#include "common/format.h"

/* A node: a conservative 16-bit box on the file's grid plus one word.
 *   internal: bit 31 = 0, bits 30..23 = sort byte, bits 22..0 = subtree size
 *             in nodes (the escape link is index + size; the first child is
 *             index + 1, the second child is the first child's escape).
 *   leaf:     bit 31 = 1, bits 30..27 = triangle count - 1, bits 26..0 =
 *             first triangle (in cooked order); its escape is index + 1.
 * Sort byte bit k, for ray octant k (bit 0: dir.x < 0, bit 1: dir.y < 0,
 * bit 2: dir.z < 0, signs taken from the reciprocal direction): set when the
 * second child is nearer and is visited first. A node's box id (layout/tree.h)
 * is its index: every node carries its own box. */
typedef struct cbvh_node {
    uint16_t qmin[3];
    uint16_t qmax[3];
    uint32_t word;
} cbvh_node;

#define CBVH_NODE_SIZE 16u
#define CBVH_NODE_LEAF_BIT 0x80000000u
#define CBVH_NODE_SIZE_MASK 0x7FFFFFu
#define CBVH_NODE_SORT_SHIFT 23
#define CBVH_NODE_COUNT_SHIFT 27
#define CBVH_NODE_FIRST_MASK 0x7FFFFFFu

/* Limits of this layout: 23 bits of subtree size in an internal node's word,
 * 27 bits of first-triangle index and 4 of count in a leaf's word. */
#define CBVH_BINARY_MAX_NODES 0x7FFFFFu
#define CBVH_BINARY_MAX_TRIANGLES 0x7FFFFFFu

static inline int cbvh_node_is_leaf(uint32_t word)
{
    return (word & CBVH_NODE_LEAF_BIT) != 0;
}
static inline uint32_t cbvh_node_subtree_size(uint32_t word)
{
    return word & CBVH_NODE_SIZE_MASK;
}
static inline uint32_t cbvh_node_sort_byte(uint32_t word)
{
    return (word >> CBVH_NODE_SORT_SHIFT) & 0xFFu;
}
static inline uint32_t cbvh_leaf_first(uint32_t word)
{
    return word & CBVH_NODE_FIRST_MASK;
}
static inline uint32_t cbvh_leaf_count(uint32_t word)
{
    return ((word >> CBVH_NODE_COUNT_SHIFT) & 0xFu) + 1u;
}

static inline uint32_t cbvh_make_internal(uint32_t subtree_size, uint32_t sort_byte)
{
    return (sort_byte << CBVH_NODE_SORT_SHIFT) | subtree_size;
}
static inline uint32_t cbvh_make_leaf(uint32_t first, uint32_t count)
{
    return CBVH_NODE_LEAF_BIT | ((count - 1u) << CBVH_NODE_COUNT_SHIFT) | first;
}

/* Nodes in the subtree of a node with this word: 1 for a leaf. */
static inline uint32_t cbvh_node_span(uint32_t word)
{
    return cbvh_node_is_leaf(word) ? 1u : cbvh_node_subtree_size(word);
}

/* The second child of internal node i: the escape link of its first child i + 1. */
static inline uint32_t cbvh_second_child(const cbvh_node *nodes, uint32_t i)
{
    return i + 1u + cbvh_node_span(nodes[i + 1u].word);
}

/* The node's six grid coordinates as one array: qmin x,y,z then qmax x,y,z. */
static inline const uint16_t *cbvh_node_q(const cbvh_node *n)
{
    /* qmin and qmax are adjacent uint16_t[3] arrays at offsets 0 and 6 (spec section 5) */
    return (const uint16_t *)(const void *)n;
}

#endif
