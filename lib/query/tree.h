/* tree.h: navigating the depth-first node array (children, escape links) of spec section 5. */
#ifndef CBVH_QUERY_TREE_H
#define CBVH_QUERY_TREE_H

#include "common/format.h"

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

#endif
