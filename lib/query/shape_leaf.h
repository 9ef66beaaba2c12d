/* shape_leaf.h: the shape queries' leaf loop, CBVH_LANES triangles a group for their float tests. */
#ifndef CBVH_QUERY_SHAPE_LEAF_H
#define CBVH_QUERY_SHAPE_LEAF_H

#ifdef CBVH_HAVE_SIMD
#include "common/file.h"
#include "query/lanes.h"
#include "query/leaf.h"

/* A query's test of the CBVH_LANES triangles of group g: cooked triangles k + j for the lanes j of g->mask
 * (the other lanes hold other triangles, which the test must ignore). Returns 1 to end the walk. */
typedef int (*cbvh_shape_group_fn)(void *query, uint32_t k, const struct leaf_group *g);

/* The leaf's triangles [first, end) to `test`, a group at a time (leaf_group_lanes), the encodings given as
 * constants or run-time values (cbvh_shape_leaf_groups). Returns 1 when `test` ended the walk. */
CBVH_FORCE_INLINE int shape_leaf_groups_as(const struct cbvh_file *f, uint32_t first, uint32_t end,
                                           cbvh_shape_group_fn test, void *query, const int tri_enc,
                                           const int vert_enc)
{
    const struct leaf_quad *quads = (const struct leaf_quad *)f->quads;
    for (uint32_t k = leaf_groups_begin(quads, first); k < end; k += CBVH_LANES) {
        struct leaf_quad scratch[CBVH_LEAF_QUADS];
        struct leaf_group g;
        leaf_group_lanes(f, quads, tri_enc, vert_enc, f->grid_origin, f->grid_scale, first, end, k, scratch,
                         &g);
        if (test(query, k, &g))
            return 1;
    }
    return 0;
}

/* The leaf's triangles [first, first + count) to `test` a group at a time: the encodings the cooker writes
 * for lossless files (LOCAL8 or U16 indices, float vertices) get loops of their own, as the ray leaves do
 * (cbvh_leaf_visit). Returns 1 when `test` ended the walk. */
CBVH_FORCE_INLINE int cbvh_shape_leaf_groups(const struct cbvh_file *f, uint32_t first, uint32_t count,
                                             cbvh_shape_group_fn test, void *query)
{
    const uint32_t end = first + count;
    switch (f->triangle_encoding << 1 | f->vertex_encoding) {
    case CBVH_TRIS_LOCAL8 << 1 | CBVH_VERTS_F32:
        return shape_leaf_groups_as(f, first, end, test, query, CBVH_TRIS_LOCAL8, CBVH_VERTS_F32);
    case CBVH_TRIS_U16 << 1 | CBVH_VERTS_F32:
        return shape_leaf_groups_as(f, first, end, test, query, CBVH_TRIS_U16, CBVH_VERTS_F32);
    default:
        return shape_leaf_groups_as(f, first, end, test, query, (int)f->triangle_encoding,
                                    (int)f->vertex_encoding);
    }
}

/* Group g's corners as the float tests read them: c[v][axis], lane j for triangle k + j. */
CBVH_FORCE_INLINE void cbvh_group_corners(const struct leaf_group *g, cbvh_lanes c[3][3])
{
    const struct leaf_quad *lo = g->quad[0], *hi = g->quad[CBVH_LEAF_QUADS - 1u];
    (void)hi;
    for (int v = 0; v < 3; v++)
        for (int a = 0; a < 3; a++)
            c[v][a] = lanes_load_halves(lo->c[v][a], hi->c[v][a]);
}

/* The float vertices of lane j's triangle in group g. */
CBVH_FORCE_INLINE void cbvh_group_triangle(const struct leaf_group *g, uint32_t j, float a[3], float b[3],
                                           float c[3])
{
    const struct leaf_quad *t = g->quad[j / 4u];
    const uint32_t i = j % 4u;
    for (int x = 0; x < 3; x++) {
        a[x] = t->c[0][x][i];
        b[x] = t->c[1][x][i];
        c[x] = t->c[2][x][i];
    }
}
#endif

#endif
