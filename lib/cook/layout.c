/* layout.c: the file order of the built tree: the binary layout's depth-first placement (quantized boxes,
 * subtree sizes, sort bytes), the wide one's by place_wide4.c, then triangle and vertex order. */
#include <string.h>

#include "common/alloc.h"
#include "layout/encodings.h"
#include "layout/triangle_encodings.h"
#include "common/error.h"
#include "common/format.h"
#include "cook/cook_internal.h"

#define UNSET UINT32_MAX

/* Per build node, what the depth-first placement needs. */
typedef struct node_info {
    uint16_t qmin[3], qmax[3];
    uint32_t size;  /* nodes in the subtree */
    uint32_t tris;  /* triangles in the subtree */
    uint32_t first; /* build index of the child placed first (larger area) */
    uint32_t out;   /* index in the file */
    uint32_t start; /* first cooked triangle of the subtree */
    uint32_t depth; /* nodes from the root, root = 1 */
} node_info;

/* Spec section 5: bit k set when dot(center(first) - center(second), octant_direction(k)) > 0,
 * with d[a] = (qmin + qmax of first - qmin - qmax of second) x grid_scale[a] in double (exact:
 * 18-bit integer times binary32) and the sum taken x, y, z in that order. */
static uint32_t sort_byte(const cook_grid *g, const node_info *first, const node_info *second)
{
    double d[3];
    for (int a = 0; a < 3; a++) {
        int32_t diff = (int32_t)first->qmin[a] + first->qmax[a] - (int32_t)second->qmin[a] - second->qmax[a];
        d[a] = (double)diff * (double)g->scale[a];
    }
    uint32_t byte = 0;
    for (uint32_t k = 0; k < 8; k++) {
        double dot = (k & 1 ? -d[0] : d[0]) + (k & 2 ? -d[1] : d[1]);
        dot += k & 4 ? -d[2] : d[2];
        if (dot > 0.0)
            byte |= 1u << k;
    }
    return byte;
}

/* Children always come after their parent in build order, so one backward pass sums subtrees. */
static void measure_subtrees(const cook_tree *t, const cook_grid *g, node_info *restrict info)
{
    for (uint32_t i = 0; i < t->node_count; i++)
        cbvh_cook_quantize_box(g, t->nodes[i].lo, t->nodes[i].hi, info[i].qmin, info[i].qmax);
    for (uint32_t i = t->node_count; i-- > 0;) {
        const cook_bnode *n = &t->nodes[i];
        if (n->count) {
            info[i].size = 1;
            info[i].tris = n->count;
            continue;
        }
        const node_info *l = &info[n->child], *r = &info[n->child + 1];
        info[i].size = 1 + l->size + r->size;
        info[i].tris = l->tris + r->tris;
        /* Larger surface area first: more rays enter it, and ties keep the build order. */
        info[i].first = cbvh_cook_quantized_half_area(g, r->qmin, r->qmax) >
                                cbvh_cook_quantized_half_area(g, l->qmin, l->qmax)
                            ? n->child + 1
                            : n->child;
    }
}

/* One forward pass places every node: a first child right after its parent, the second after
 * the first's subtree; leaves take consecutive cooked triangles in that order. */
static void place(const cook_tree *t, const cook_grid *g, node_info *restrict info, cook_layout *l)
{
    info[0].out = 0;
    info[0].start = 0;
    info[0].depth = 1;
    uint32_t depth = 0, max_leaf = 0;
    for (uint32_t i = 0; i < t->node_count; i++) {
        const cook_bnode *n = &t->nodes[i];
        const node_info *me = &info[i];
        cbvh_node *out = (cbvh_node *)l->nodes + me->out;
        memcpy(out->qmin, me->qmin, sizeof out->qmin);
        memcpy(out->qmax, me->qmax, sizeof out->qmax);
        depth = me->depth > depth ? me->depth : depth;
        if (n->count) {
            out->word = cbvh_make_leaf(me->start, n->count);
            for (uint32_t k = 0; k < n->count; k++)
                l->triangle_source[me->start + k] = t->prims[n->child + k];
            max_leaf = n->count > max_leaf ? n->count : max_leaf;
            continue;
        }
        node_info *f = &info[me->first], *s = &info[me->first == n->child ? n->child + 1 : n->child];
        f->out = me->out + 1;
        s->out = me->out + 1 + f->size;
        f->start = me->start;
        s->start = me->start + f->tris;
        f->depth = s->depth = me->depth + 1;
        out->word = cbvh_make_internal(me->size, sort_byte(g, f, s));
    }
    l->depth = depth;
    l->max_leaf_count = max_leaf;
}

/* Which rule makes copies of vertices in order_vertices. */
enum vertex_copies {
    COPIES_NONE,    /* u16 or u32 indices: every vertex once */
    COPIES_DELTA16, /* a triangle whose deltas would not fit in i16 copies its stale vertices */
    COPIES_LOCAL8   /* a block of CBVH_LOCAL8_BLOCK triangles copies the vertices first used before its window
                     */
};

/* Vertices numbered by first use in cooked order, the leaves' depth-first order in both layouts:
 * neighbouring triangles get neighbouring indices, which keeps DELTA16 deltas and LOCAL8 windows small
 * and compresses well. A copy is a fresh id for a vertex already numbered, with a bit-identical position:
 * - DELTA16: a triangle that reuses a vertex first used long before (as across the root's split plane)
 *   gets copies of its stale vertices, so every triangle fits DELTA16 (8 bytes instead of 12 for u32);
 * - LOCAL8: a block's new ids are the next at most 3 x CBVH_LOCAL8_BLOCK, so a vertex whose id lies more
 *   than CBVH_LOCAL8_WINDOW - 3 x CBVH_LOCAL8_BLOCK below the block's first new id gets a copy, and every
 *   id of the block lies within CBVH_LOCAL8_WINDOW of its smallest. */
static cbvh_result order_vertices(const cook_mesh *m, cook_layout *l, enum vertex_copies copies,
                                  const cbvh_allocator *a)
{
    uint32_t *latest = cbvh_alloc_array(a, m->vertex_count, sizeof(uint32_t), 64);
    if (!latest)
        return CBVH_ERROR_OUT_OF_MEMORY;
    memset(latest, 0xFF, (size_t)m->vertex_count * sizeof(uint32_t));
    const uint32_t *restrict idx = m->indices;
    const uint32_t *restrict src = l->triangle_source;
    uint32_t *restrict tris = l->triangles;
    const uint32_t reach = CBVH_LOCAL8_WINDOW - 3u * CBVH_LOCAL8_BLOCK;
    uint32_t count = 0, window = 0; /* LOCAL8: the smallest id the current block may use */
    for (uint32_t t = 0; t < l->triangle_count; t++) {
        if (copies == COPIES_LOCAL8 && t % CBVH_LOCAL8_BLOCK == 0)
            window = count > reach ? count - reach : 0;
        uint32_t v[3], id[3];
        for (int c = 0; c < 3; c++) {
            v[c] = idx[3 * (size_t)src[t] + (size_t)c];
            if (latest[v[c]] == UNSET || (copies == COPIES_LOCAL8 && latest[v[c]] < window))
                latest[v[c]] = count++;
            id[c] = latest[v[c]];
        }
        if (copies == COPIES_DELTA16 &&
            (!cbvh_delta16_fits(id[0], id[1]) || !cbvh_delta16_fits(id[0], id[2]))) {
            /* Afterwards every id lies in [count - 32000, count + 3): deltas fit. */
            for (int c = 0; c < 3; c++)
                if (id[c] + 32000 < count)
                    latest[v[c]] = id[c] = count++;
        }
        for (int c = 0; c < 3; c++)
            tris[3 * (size_t)t + (size_t)c] = id[c];
    }
    cbvh_free(a, latest);
    /* Known only now, the count sizes vertex_source exactly (copies could make it up to 3 a triangle):
     * every id was given at a corner of its vertex. */
    uint32_t *vsrc = cbvh_alloc_array(a, count, sizeof(uint32_t), 64);
    if (!vsrc)
        return CBVH_ERROR_OUT_OF_MEMORY;
    for (size_t c = 0; c < 3 * (size_t)l->triangle_count; c++)
        vsrc[tris[c]] = idx[3 * (size_t)src[c / 3] + c % 3];
    cbvh_free(a, l->vertex_source);
    l->vertex_source = vsrc;
    l->vertex_count = count;
    return CBVH_OK;
}

/* The index encoding of the numbered triangles without LOCAL8: u16 when every index fits, else DELTA16
 * when every triangle's deltas fit in i16, else u32. */
static uint32_t wide_index_encoding(const cook_layout *l)
{
    if (l->vertex_count <= (uint64_t)cbvh_encoding_of(CBVH_SECTION_TRIANGLES, CBVH_TRIS_U16)->max_value + 1)
        return CBVH_TRIS_U16;
    const uint32_t *t = l->triangles;
    for (size_t i = 0; i < (size_t)l->triangle_count; i++, t += 3)
        if (!cbvh_delta16_fits(t[0], t[1]) || !cbvh_delta16_fits(t[0], t[2]))
            return CBVH_TRIS_U32;
    return CBVH_TRIS_DELTA16;
}

/* Bytes of the TRIANGLES and VERTICES sections for l's numbering in index encoding `enc`. */
static uint64_t mesh_bytes(const cook_layout *l, uint32_t enc, uint32_t vertex_size)
{
    const cbvh_encoding *e = cbvh_encoding_of(CBVH_SECTION_TRIANGLES, enc);
    return cbvh_elements_for(e, l->triangle_count) * e->element_size +
           (uint64_t)l->vertex_count * vertex_size;
}

/* Numbers the vertices and picks the index encoding whose triangles and vertices take the fewest bytes
 * (spec section 4): LOCAL8 with its copies, or the narrowest other encoding (u16, DELTA16 with its
 * copies, u32); ties go to LOCAL8. */
static cbvh_result number_vertices(const cook_mesh *m, cook_layout *l, uint32_t vertex_size,
                                   const cbvh_allocator *a)
{
    cbvh_result r = order_vertices(m, l, COPIES_LOCAL8, a);
    if (r != CBVH_OK)
        return r;
    const uint64_t local8 = mesh_bytes(l, CBVH_TRIS_LOCAL8, vertex_size);
    l->triangle_encoding = CBVH_TRIS_LOCAL8;
    /* The other encodings take at least this (each vertex once, the narrowest index that fits): most
     * meshes need no second numbering. */
    const uint32_t narrowest = m->vertex_count > 65536 ? CBVH_TRIS_DELTA16 : CBVH_TRIS_U16;
    const cbvh_encoding *n = cbvh_encoding_of(CBVH_SECTION_TRIANGLES, narrowest);
    if ((uint64_t)l->triangle_count * n->element_size + (uint64_t)m->vertex_count * vertex_size >= local8)
        return CBVH_OK;
    /* Copies are made only where a delta would not fit, so with few vertices (u16 indices) or a mesh whose
     * deltas all fit there are none. */
    cook_layout other = *l;
    other.triangles = cbvh_alloc_array(a, l->triangle_count, 3 * sizeof(uint32_t), 64);
    other.vertex_source = NULL;
    if (!other.triangles)
        return CBVH_ERROR_OUT_OF_MEMORY;
    r = order_vertices(m, &other, m->vertex_count > 65536 ? COPIES_DELTA16 : COPIES_NONE, a);
    if (r == CBVH_OK) {
        other.triangle_encoding = wide_index_encoding(&other);
        if (mesh_bytes(&other, other.triangle_encoding, vertex_size) < local8) {
            uint32_t *tris = l->triangles, *vsrc = l->vertex_source;
            *l = other;
            other.triangles = tris;
            other.vertex_source = vsrc;
        }
    }
    cbvh_free(a, other.triangles);
    cbvh_free(a, other.vertex_source);
    return r;
}

/* Ct x internal areas + Ci x leaf areas x triangles, over the root's area, on the decoded boxes. */
static double sah_cost(const cbvh_node *nodes, uint32_t count, const cook_grid *g, double ct, double ci)
{
    double sum = 0.0;
    for (uint32_t i = 0; i < count; i++) {
        double area = cbvh_cook_quantized_half_area(g, nodes[i].qmin, nodes[i].qmax);
        sum += cbvh_node_is_leaf(nodes[i].word) ? ci * cbvh_leaf_count(nodes[i].word) * area : ct * area;
    }
    double root = cbvh_cook_quantized_half_area(g, nodes[0].qmin, nodes[0].qmax);
    return root > 0.0 ? sum / root : 0.0;
}

void cbvh_cook_layout_free(const cbvh_allocator *a, cook_layout *l)
{
    cbvh_free(a, l->nodes);
    cbvh_free(a, l->triangles);
    cbvh_free(a, l->triangle_source);
    cbvh_free(a, l->vertex_source);
    memset(l, 0, sizeof *l);
}

/* A binary-layout limit the mesh exceeds: what, how many, the limit, and what to do instead. */
static cbvh_result binary_limit(cbvh_error *err, const char *what, uint32_t count, const char *unit,
                                uint32_t max, const char *also)
{
    return cbvh_fail(
        err, CBVH_ERROR_LIMIT,
        "the %s has %u %s; a binary-layout file holds at most %u (use the wide4 layout%s or split the "
        "mesh)",
        what, count, unit, max, also);
}

/* The binary layout: every build node becomes a file node. */
static cbvh_result place_binary(const cook_tree *t, const cook_grid *g, float traversal_cost,
                                float intersection_cost, const cbvh_allocator *a, cook_layout *out,
                                cbvh_error *err)
{
    if (out->triangle_count > CBVH_BINARY_MAX_TRIANGLES)
        return binary_limit(err, "mesh", out->triangle_count, "triangles", CBVH_BINARY_MAX_TRIANGLES, "");
    if (t->node_count > CBVH_BINARY_MAX_NODES)
        return binary_limit(err, "tree", t->node_count, "nodes", CBVH_BINARY_MAX_NODES,
                            ", raise max_leaf_size");
    node_info *info = cbvh_alloc_array(a, t->node_count, sizeof(node_info), 64);
    out->nodes = cbvh_alloc_array(a, t->node_count, sizeof(cbvh_node), 64);
    out->triangle_source = cbvh_alloc_array(a, out->triangle_count, sizeof(uint32_t), 64);
    if (!info || !out->nodes || !out->triangle_source) {
        cbvh_free(a, info);
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while laying out %u nodes",
                         t->node_count);
    }
    out->node_count = t->node_count;
    out->leaf_count = t->leaf_count;
    measure_subtrees(t, g, info);
    place(t, g, info, out);
    cbvh_free(a, info);
    out->sah_cost = sah_cost(out->nodes, out->node_count, g, traversal_cost, intersection_cost);
    return CBVH_OK;
}

cbvh_result cbvh_cook_layout_place(const cook_tree *t, uint32_t triangle_count, const cook_grid *g,
                                   cbvh_layout layout, float traversal_cost, float intersection_cost,
                                   const cbvh_allocator *a, cook_layout *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    out->layout = layout;
    out->triangle_count = triangle_count;
    cbvh_result r = layout == CBVH_LAYOUT_WIDE4
                        ? cbvh_cook_place_wide4(t, g, traversal_cost, intersection_cost, a, out, err)
                        : place_binary(t, g, traversal_cost, intersection_cost, a, out, err);
    if (r != CBVH_OK) {
        cbvh_cook_layout_free(a, out);
        return r;
    }
    if (out->depth > CBVH_MAX_DEPTH) {
        uint32_t depth = out->depth;
        cbvh_cook_layout_free(a, out);
        return cbvh_fail(err, CBVH_ERROR_LIMIT, "the tree is %u nodes deep; a file allows at most %u", depth,
                         CBVH_MAX_DEPTH);
    }
    return CBVH_OK;
}

cbvh_result cbvh_cook_layout_number(const cook_mesh *m, uint32_t vertex_size, const cbvh_allocator *a,
                                    cook_layout *l, cbvh_error *err)
{
    l->triangles = cbvh_alloc_array(a, l->triangle_count, 3 * sizeof(uint32_t), 64);
    if (!l->triangles || number_vertices(m, l, vertex_size, a) != CBVH_OK)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while ordering %u vertices",
                         m->vertex_count);
    return CBVH_OK;
}
