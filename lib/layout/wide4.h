/* wide4.h: the 4-wide node layout (NODES encoding W4, spec section 5.2): every fact about its node bytes. */
#ifndef CBVH_LAYOUT_WIDE4_H
#define CBVH_LAYOUT_WIDE4_H

#include <stdint.h>
#include <string.h>

#include "cbvh.h"
#include "common/endian.h"

/* A node is 64 bytes, one cache line, and holds the boxes of its up to four
 * children (slots) in structure-of-arrays order, so one 8-byte load gives a
 * plane of all four:
 *   u16 q[6][4]   plane k (0..2 qmin x, y, z; 3..5 qmax x, y, z) of slot s at q[k][s]
 *   u32 first_child     node index of the first internal child; the internal
 *                       children are consecutive nodes, in slot order
 *   u32 first_triangle  cooked index of the first triangle of the first leaf
 *                       child; leaf children's triangles follow each other in
 *                       slot order
 *   u64 meta            bits 4s..4s+3: triangle count - 1 of slot s (a leaf)
 *                       bits 16..19: the slots in use (slot s: bit 16 + s)
 *                       bits 20..23: the internal slots
 *                       bits 24 + 5k .. 28 + 5k: for ray octant k (spec
 *                       section 5), the index (cbvh_wide4_orders) of the
 *                       slot order a sorted walk visits the children in.
 * A child is named on a walk's stack by a reference (layout/tree.h): an
 * internal child by its node index (bit 31 clear), a leaf by
 * CBVH_W4_LEAF_BIT | (count - 1) << 28 | first triangle. So a file holds up to
 * 2^28 triangles and 2^31 nodes, and a leaf up to 8 triangles. The box of
 * slot s of node n has the box id 4 n + s. */

#define CBVH_W4_NODE_SIZE 64u
#define CBVH_W4_WIDTH 4u
#define CBVH_W4_LEAF_BIT 0x80000000u
#define CBVH_W4_COUNT_SHIFT 28
#define CBVH_W4_FIRST_MASK 0x0FFFFFFFu
#define CBVH_W4_MAX_LEAF CBVH_WIDE4_MAX_LEAF
#define CBVH_W4_MAX_TRIANGLES 0x10000000u
#define CBVH_W4_MAX_NODES 0x7FFFFFFFu
#define CBVH_W4_ORDERS 24u

/* Byte offsets in a node. */
enum { CBVH_W4_Q = 0, CBVH_W4_FIRST_CHILD = 48, CBVH_W4_FIRST_TRIANGLE = 52, CBVH_W4_META = 56 };

/* The 24 orders of four slots, lexicographic: order o lists the slots in visit order. Listed once, as
 * X(a, b, c, d) for each order; the two tables below are made from it. */
/* clang-format off */
#define CBVH_W4_ORDER_LIST(X)                                                                              \
    X(0, 1, 2, 3) X(0, 1, 3, 2) X(0, 2, 1, 3) X(0, 2, 3, 1) X(0, 3, 1, 2) X(0, 3, 2, 1)                     \
    X(1, 0, 2, 3) X(1, 0, 3, 2) X(1, 2, 0, 3) X(1, 2, 3, 0) X(1, 3, 0, 2) X(1, 3, 2, 0)                     \
    X(2, 0, 1, 3) X(2, 0, 3, 1) X(2, 1, 0, 3) X(2, 1, 3, 0) X(2, 3, 0, 1) X(2, 3, 1, 0)                     \
    X(3, 0, 1, 2) X(3, 0, 2, 1) X(3, 1, 0, 2) X(3, 1, 2, 0) X(3, 2, 0, 1) X(3, 2, 1, 0)
/* clang-format on */

/* Entry o lists the slots of order o. */
#define CBVH_W4_ORDER_ROW(a, b, c, d) {a, b, c, d},
static const uint8_t cbvh_wide4_orders[CBVH_W4_ORDERS][4] = {CBVH_W4_ORDER_LIST(CBVH_W4_ORDER_ROW)};
#undef CBVH_W4_ORDER_ROW

/* Entry [o][hits] lists the slots of `hits` (a 4-bit mask) in order o, two bits each from the lowest:
 * what a walk visits of a node whose children `hits` the ray enters, with one load rather than a loop
 * that branches on each slot (which slots a ray enters is as unpredictable as the ray). */
/* clang-format off */
#define CBVH_W4_HIT(s, h) ((h) >> (s) & 1u)
#define CBVH_W4_BEFORE_C(a, b, h) (CBVH_W4_HIT(a, h) + CBVH_W4_HIT(b, h))
#define CBVH_W4_VISIT(a, b, c, d, h)                                                                       \
    (uint8_t)((CBVH_W4_HIT(a, h) * (a)) | (CBVH_W4_HIT(b, h) * (b)) << (2u * CBVH_W4_HIT(a, h)) |          \
              (CBVH_W4_HIT(c, h) * (c)) << (2u * CBVH_W4_BEFORE_C(a, b, h)) |                              \
              (CBVH_W4_HIT(d, h) * (d)) << (2u * (CBVH_W4_BEFORE_C(a, b, h) + CBVH_W4_HIT(c, h))))
#define CBVH_W4_VISIT_ROW(a, b, c, d)                                                                      \
    {CBVH_W4_VISIT(a, b, c, d, 0u),  CBVH_W4_VISIT(a, b, c, d, 1u),  CBVH_W4_VISIT(a, b, c, d, 2u),        \
     CBVH_W4_VISIT(a, b, c, d, 3u),  CBVH_W4_VISIT(a, b, c, d, 4u),  CBVH_W4_VISIT(a, b, c, d, 5u),        \
     CBVH_W4_VISIT(a, b, c, d, 6u),  CBVH_W4_VISIT(a, b, c, d, 7u),  CBVH_W4_VISIT(a, b, c, d, 8u),        \
     CBVH_W4_VISIT(a, b, c, d, 9u),  CBVH_W4_VISIT(a, b, c, d, 10u), CBVH_W4_VISIT(a, b, c, d, 11u),       \
     CBVH_W4_VISIT(a, b, c, d, 12u), CBVH_W4_VISIT(a, b, c, d, 13u), CBVH_W4_VISIT(a, b, c, d, 14u),       \
     CBVH_W4_VISIT(a, b, c, d, 15u)},
/* clang-format on */
static const uint8_t cbvh_wide4_visits[CBVH_W4_ORDERS][16] = {CBVH_W4_ORDER_LIST(CBVH_W4_VISIT_ROW)};
#undef CBVH_W4_VISIT_ROW

/* Entry [o][hits] says how a depth-first walk descends into the children `hits` in order o, a slot a
 * byte: byte 3 the first one in visit order (the walk goes on there), bytes 0, 1, 2 the ones it pushes
 * onto its stack, from the last in visit order (deepest) to the second; with fewer than four children
 * the bytes past them repeat slots (a walk stores those entries above its new top, dead). Made from the
 * visit table: slot i of the visit list v is field i, v >> 2 i & 3. */
/* clang-format off */
#define CBVH_W4_HITS(h) (((h) & 1u) + ((h) >> 1 & 1u) + ((h) >> 2 & 1u) + ((h) >> 3 & 1u))
#define CBVH_W4_FIELD(v, i) ((uint32_t)(v) >> (2u * ((i) & 3u)) & 3u)
#define CBVH_W4_DESCENT(v, h)                                                                              \
    (CBVH_W4_FIELD(v, CBVH_W4_HITS(h) - 1u) | CBVH_W4_FIELD(v, CBVH_W4_HITS(h) - 2u) << 8 |                  \
     CBVH_W4_FIELD(v, CBVH_W4_HITS(h) - 3u) << 16 | CBVH_W4_FIELD(v, 0u) << 24)
#define CBVH_W4_DESCENT_ROW(a, b, c, d)                                                                    \
    {CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 0u), 0u),   CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 1u), 1u),     \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 2u), 2u),   CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 3u), 3u),     \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 4u), 4u),   CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 5u), 5u),     \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 6u), 6u),   CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 7u), 7u),     \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 8u), 8u),   CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 9u), 9u),     \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 10u), 10u), CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 11u), 11u),   \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 12u), 12u), CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 13u), 13u),   \
     CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 14u), 14u), CBVH_W4_DESCENT(CBVH_W4_VISIT(a, b, c, d, 15u), 15u)},
/* clang-format on */
static const uint32_t cbvh_wide4_descents[CBVH_W4_ORDERS][16] = {CBVH_W4_ORDER_LIST(CBVH_W4_DESCENT_ROW)};
#undef CBVH_W4_DESCENT_ROW
#undef CBVH_W4_DESCENT
#undef CBVH_W4_FIELD
#undef CBVH_W4_HITS
#undef CBVH_W4_VISIT
#undef CBVH_W4_BEFORE_C
#undef CBVH_W4_HIT

static inline const uint8_t *cbvh_w4_node(const void *nodes, uint32_t n)
{
    return (const uint8_t *)nodes + (size_t)n * CBVH_W4_NODE_SIZE;
}

/* Where plane k of slot s lies in a node: the planes' one addressing, for readers and the cooker (the macro
 * for tables, which need a constant expression). Plane k of the four slots is one run of 8 bytes. */
#define CBVH_W4_PLANE_OFFSET(k, s) (CBVH_W4_Q + 8u * (k) + 2u * (s))
static inline uint32_t cbvh_w4_plane_offset(uint32_t k, uint32_t s)
{
    return CBVH_W4_PLANE_OFFSET(k, s);
}

/* Plane k of slot s. The file is little-endian, and so is every host the library builds for (configure
 * checks). */
static inline uint32_t cbvh_w4_plane(const uint8_t *node, uint32_t k, uint32_t s)
{
    uint16_t q;
    memcpy(&q, node + cbvh_w4_plane_offset(k, s), sizeof q);
    return q;
}

/* Set bits of a 4-bit mask, from a table of nibbles (no popcount instruction in the x86-64 baseline). */
static inline uint32_t cbvh_w4_popcount(uint32_t mask4)
{
    return (uint32_t)(0x4332322132212110ull >> (4u * mask4)) & 0xFu;
}

static inline uint64_t cbvh_w4_meta(const uint8_t *node)
{
    return cbvh_read_u64(node + CBVH_W4_META);
}
static inline uint32_t cbvh_w4_first_child(const uint8_t *node)
{
    return cbvh_read_u32(node + CBVH_W4_FIRST_CHILD);
}
static inline uint32_t cbvh_w4_first_triangle(const uint8_t *node)
{
    return cbvh_read_u32(node + CBVH_W4_FIRST_TRIANGLE);
}
static inline uint32_t cbvh_w4_used(uint64_t meta)
{
    return (uint32_t)(meta >> 16) & 0xFu;
}
static inline uint32_t cbvh_w4_internal(uint64_t meta)
{
    return (uint32_t)(meta >> 20) & 0xFu;
}
static inline uint32_t cbvh_w4_count(uint64_t meta, uint32_t s)
{
    return ((uint32_t)(meta >> (4u * s)) & 0xFu) + 1u;
}
static inline uint32_t cbvh_w4_order(uint64_t meta, uint32_t octant)
{
    return (uint32_t)(meta >> (24u + 5u * octant)) & 0x1Fu;
}

static inline uint64_t cbvh_w4_make_meta(const uint32_t count[4], uint32_t used, uint32_t internal,
                                         const uint32_t order[8])
{
    uint64_t m = (uint64_t)used << 16 | (uint64_t)internal << 20;
    for (uint32_t s = 0; s < 4; s++)
        if ((used & ~internal) >> s & 1u)
            m |= (uint64_t)(count[s] - 1u) << (4u * s);
    for (uint32_t k = 0; k < 8; k++)
        m |= (uint64_t)order[k] << (24u + 5u * k);
    return m;
}

/* The reference of slot s of a node (used, meta as read): an internal child's
 * node index, or a leaf's packed triangle range. A leaf's first triangle is
 * the node's first plus the counts of the leaf slots before it: their number
 * plus the sum of their count nibbles (the nibbles of other slots are 0, as
 * the loader checked; each is at most 7, so two fit a byte). */
static inline uint32_t cbvh_w4_child_ref(const uint8_t *node, uint64_t meta, uint32_t s)
{
    const uint32_t below = (1u << s) - 1u, internal = cbvh_w4_internal(meta);
    if (internal >> s & 1u)
        return cbvh_w4_first_child(node) + cbvh_w4_popcount(internal & below);
    const uint32_t nibbles = (uint32_t)meta & ((1u << (4u * s)) - 1u);
    const uint32_t pairs = (nibbles & 0x0F0Fu) + (nibbles >> 4 & 0x0F0Fu);
    const uint32_t leaves = cbvh_w4_used(meta) & ~internal & below;
    const uint32_t first =
        cbvh_w4_first_triangle(node) + cbvh_w4_popcount(leaves) + (pairs & 0xFFu) + (pairs >> 8);
    return CBVH_W4_LEAF_BIT | (cbvh_w4_count(meta, s) - 1u) << CBVH_W4_COUNT_SHIFT | first;
}

static inline int cbvh_w4_ref_is_leaf(uint32_t ref)
{
    return (ref & CBVH_W4_LEAF_BIT) != 0;
}
static inline uint32_t cbvh_w4_ref_first(uint32_t ref)
{
    return ref & CBVH_W4_FIRST_MASK;
}
static inline uint32_t cbvh_w4_ref_count(uint32_t ref)
{
    return ((ref >> CBVH_W4_COUNT_SHIFT) & 7u) + 1u;
}

#endif
