/* place_wide4.c: the cooker's side of the 4-wide layout: the build tree collapsed into 64-byte nodes, breadth
 * first. */
#include <string.h>

#include "common/alloc.h"
#include "common/endian.h"
#include "common/error.h"
#include "cook/cook_internal.h"
#include "layout/wide4.h"

/* The slot of kids[0 .. k) to open next: the first internal one whose two children are both leaves (left
 * as a node of its own, it would fill two of its four slots), else the internal one of largest quantized
 * area (ties: the first); CBVH_W4_WIDTH when none is internal. */
static uint32_t slot_to_open(const cook_tree *t, const double *area, const uint32_t *kids, uint32_t k)
{
    uint32_t largest = CBVH_W4_WIDTH;
    for (uint32_t s = 0; s < k; s++) {
        const cook_bnode *c = &t->nodes[kids[s]];
        if (c->count)
            continue;
        if (t->nodes[c->child].count && t->nodes[c->child + 1].count)
            return s;
        if (largest == CBVH_W4_WIDTH || area[kids[s]] > area[kids[largest]])
            largest = s;
    }
    return largest;
}

/* The children of build node b, as build node ids: its two children, then
 * slots opened into their two children (slot_to_open) until there are four or
 * none is internal. So nodes fill up before leaves are chosen (opening the
 * two-leaf slots first gives fewer nodes than opening by area alone, for
 * slightly more node visits per ray: docs/PERFORMANCE.md), and the children
 * keep the build's spatial grouping in slot order. Returns how many (1 for a
 * leaf root). */
static uint32_t collapse(const cook_tree *t, const double *area, uint32_t b, uint32_t kids[CBVH_W4_WIDTH])
{
    const cook_bnode *n = &t->nodes[b];
    if (n->count) {
        kids[0] = b;
        return 1;
    }
    uint32_t k = 2;
    kids[0] = n->child;
    kids[1] = n->child + 1;
    while (k < CBVH_W4_WIDTH) {
        const uint32_t open = slot_to_open(t, area, kids, k);
        if (open == CBVH_W4_WIDTH)
            break;
        const uint32_t c = t->nodes[kids[open]].child;
        memmove(kids + open + 2, kids + open + 1, (k - open - 1) * sizeof kids[0]);
        kids[open] = c;
        kids[open + 1] = c + 1;
        k++;
    }
    return k;
}

/* The index in cbvh_wide4_orders of the slot order nearest first for octant
 * k (spec section 5.2): used slots by increasing dot(center, octant
 * direction), computed in binary64 from the quantized boxes as
 * sum over x, y, z of +-(qmin + qmax) * grid_scale (exact terms, summed in
 * that order); ties keep the slot order; unused slots last. */
static uint32_t octant_order(const cook_grid *g, const uint16_t q[6][4], uint32_t used, uint32_t k)
{
    double key[4];
    uint8_t slots[4];
    uint32_t n = 0;
    for (uint32_t s = 0; s < 4; s++) {
        if (!(used >> s & 1u))
            continue;
        double dot = 0.0;
        for (uint32_t a = 0; a < 3; a++) {
            const double d = (double)((uint32_t)q[a][s] + q[3 + a][s]) * (double)g->scale[a];
            dot += k >> a & 1u ? -d : d;
        }
        uint32_t j = n++;
        for (; j > 0 && dot < key[j - 1]; j--) {
            key[j] = key[j - 1];
            slots[j] = slots[j - 1];
        }
        key[j] = dot;
        slots[j] = (uint8_t)s;
    }
    for (uint32_t s = 0; s < 4; s++)
        if (!(used >> s & 1u))
            slots[n++] = (uint8_t)s;
    for (uint32_t o = 0; o < CBVH_W4_ORDERS; o++)
        if (memcmp(cbvh_wide4_orders[o], slots, 4) == 0)
            return o;
    return 0; /* unreachable: the table holds every order of four slots */
}

/* The leaves' triangles in depth-first order (spec section 5.2, CBVH_INCOMPAT_W4_DEPTH_FIRST): node i's
 * leaf slots from its first_triangle on, in slot order, then its internal children's subtrees in slot
 * order. Breadth first, leaves of different levels that share vertices would lie far apart; depth first, a
 * subtree's triangles are consecutive, so their vertices get close ids (first-use numbering, layout.c)
 * and LOCAL8's 256-vertex windows need few copies. Writes each node's first_triangle and triangle_source. */
static cbvh_result tile_depth_first(const cook_tree *t, const double *area, const uint32_t *build_of,
                                    uint8_t *nodes, uint32_t depth, const cbvh_allocator *a,
                                    uint32_t *triangle_source)
{
    uint32_t *stack = cbvh_alloc_array(a, (size_t)(CBVH_W4_WIDTH - 1u) * depth + 1u, sizeof(uint32_t), 64);
    if (!stack)
        return CBVH_ERROR_OUT_OF_MEMORY;
    uint32_t sp = 0, next = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const uint32_t i = stack[--sp];
        uint8_t *node = nodes + (size_t)i * CBVH_W4_NODE_SIZE;
        uint32_t kids[CBVH_W4_WIDTH];
        const uint32_t k = collapse(t, area, build_of[i], kids); /* the slots, as the placement made them */
        cbvh_write_u32(node + CBVH_W4_FIRST_TRIANGLE, next);
        uint32_t internal = 0;
        for (uint32_t s = 0; s < k; s++) {
            const cook_bnode *c = &t->nodes[kids[s]];
            if (!c->count) {
                internal++;
                continue;
            }
            for (uint32_t j = 0; j < c->count; j++)
                triangle_source[next + j] = t->prims[c->child + j];
            next += c->count;
        }
        /* the internal children, pushed last first so the first is walked next */
        const uint32_t first_child = cbvh_read_u32(node + CBVH_W4_FIRST_CHILD);
        while (internal > 0)
            stack[sp++] = first_child + --internal;
    }
    cbvh_free(a, stack);
    return CBVH_OK;
}

cbvh_result cbvh_cook_place_wide4(const cook_tree *t, const cook_grid *g, float traversal_cost,
                                  float intersection_cost, const cbvh_allocator *a, cook_layout *out,
                                  cbvh_error *err)
{
    /* At most one wide node per internal build node. */
    const uint32_t capacity = t->node_count - t->leaf_count > 0 ? t->node_count - t->leaf_count : 1;
    uint16_t(*box)[6] = cbvh_alloc_array(a, t->node_count, sizeof *box, 64);
    double *area = cbvh_alloc_array(a, t->node_count, sizeof(double), 64);
    uint32_t *build_of = cbvh_alloc_array(a, capacity, sizeof(uint32_t), 64); /* wide node -> build node */
    uint8_t *nodes = cbvh_alloc_array(a, capacity, CBVH_W4_NODE_SIZE, 64);
    out->triangle_source = cbvh_alloc_array(a, out->triangle_count, sizeof(uint32_t), 64);
    if (!box || !area || !build_of || !nodes || !out->triangle_source) {
        cbvh_free(a, box);
        cbvh_free(a, area);
        cbvh_free(a, build_of);
        cbvh_free(a, nodes);
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while laying out %u wide nodes",
                         capacity);
    }
    for (uint32_t i = 0; i < t->node_count; i++) {
        cbvh_cook_quantize_box(g, t->nodes[i].lo, t->nodes[i].hi, box[i], box[i] + 3);
        area[i] = cbvh_cook_quantized_half_area(g, box[i], box[i] + 3);
    }
    /* Breadth first: node i's internal children take the next free node indices, in slot order, as the
     * spec's validation rule expects; the leaves' triangles are placed depth first afterwards. */
    uint32_t node_count = 1, depth = 1, level_end = 1, max_leaf = 0;
    double sah = traversal_cost * area[0];
    build_of[0] = 0;
    for (uint32_t i = 0; i < node_count; i++) {
        if (i == level_end) {
            depth++;
            level_end = node_count;
        }
        uint32_t kids[CBVH_W4_WIDTH], count[CBVH_W4_WIDTH] = {0, 0, 0, 0}, order[8], used = 0, internal = 0;
        uint16_t q[6][4];
        memset(q, 0, sizeof q);
        const uint32_t k = collapse(t, area, build_of[i], kids);
        uint8_t *node = nodes + (size_t)i * CBVH_W4_NODE_SIZE;
        cbvh_write_u32(node + CBVH_W4_FIRST_CHILD, node_count);
        for (uint32_t s = 0; s < k; s++) {
            const cook_bnode *c = &t->nodes[kids[s]];
            used |= 1u << s;
            for (uint32_t p = 0; p < 6; p++)
                q[p][s] = box[kids[s]][p];
            if (c->count) {
                count[s] = c->count;
                max_leaf = c->count > max_leaf ? c->count : max_leaf;
                sah += intersection_cost * c->count * area[kids[s]];
            } else {
                internal |= 1u << s;
                build_of[node_count++] = kids[s];
                sah += traversal_cost * area[kids[s]];
            }
        }
        for (uint32_t o = 0; o < 8; o++)
            order[o] = octant_order(g, q, used, o);
        for (uint32_t p = 0; p < 6; p++)
            for (uint32_t s = 0; s < 4; s++)
                cbvh_write_u16(node + cbvh_w4_plane_offset(p, s), q[p][s]);
        cbvh_write_u64(node + CBVH_W4_META, cbvh_w4_make_meta(count, used, internal, order));
    }
    const double root_area = area[0];
    const cbvh_result r = tile_depth_first(t, area, build_of, nodes, depth, a, out->triangle_source);
    cbvh_free(a, box);
    cbvh_free(a, area);
    cbvh_free(a, build_of);
    /* The capacity is a bound, well above what a tree uses: the nodes move to an array of their size. */
    uint8_t *fit = r == CBVH_OK ? cbvh_alloc_array(a, node_count, CBVH_W4_NODE_SIZE, 64) : NULL;
    if (fit)
        memcpy(fit, nodes, (size_t)node_count * CBVH_W4_NODE_SIZE);
    cbvh_free(a, nodes);
    out->nodes = fit;
    out->node_count = node_count;
    out->leaf_count = t->leaf_count;
    out->depth = depth;
    out->max_leaf_count = max_leaf;
    out->sah_cost = root_area > 0.0 ? sah / root_area : 0.0;
    if (!fit)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while ordering %u triangles",
                         out->triangle_count);
    return CBVH_OK;
}
