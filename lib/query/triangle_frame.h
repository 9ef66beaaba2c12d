/* triangle_frame.h: a triangle's best-conditioned frame (base vertex, edges, normal) and barycentrics in it,
 * in double. */
#ifndef CBVH_QUERY_TRIANGLE_FRAME_H
#define CBVH_QUERY_TRIANGLE_FRAME_H

#include "query/vec3d.h"

/* base: the vertex opposite the triangle's longest edge; e1, e2: the edges
 * from it to the next two vertices in cyclic order (which keeps the
 * winding); n = e1 x e2. */
struct cbvh_triangle_frame {
    int base;
    cbvh_v3 e1, e2, n;
    double nn; /* |n|^2: 0 for a degenerate triangle (or when it underflows) */
};

/* Vertex base + k (k = 1, 2) in cyclic order: (base + k) % 3 without a division. */
static inline int cbvh_frame_vertex(int base, int k)
{
    const int i = base + k;
    return i >= 3 ? i - 3 : i;
}

/* The triangle's edges in cyclic order, edge[i] = v[i + 2] - v[i + 1] (the edge opposite vertex i), and
 * their squared lengths: what the frame's choice of base computes, for callers that use them again. */
struct cbvh_triangle_edges {
    cbvh_v3 edge[3];
    double len2[3];
};

static inline void cbvh_triangle_edges_of(const cbvh_v3 v[3], struct cbvh_triangle_edges *e)
{
    e->edge[0] = v3_sub(v[2], v[1]);
    e->edge[1] = v3_sub(v[0], v[2]);
    e->edge[2] = v3_sub(v[1], v[0]);
    for (int i = 0; i < 3; i++)
        e->len2[i] = v3_len2(e->edge[i]);
}

/* The frame of triangle v from its edges e (cbvh_triangle_edges_of). The shorter edges give the accurate
 * normal: on a needle whose long edges differ by less than their rounding (findings F5 and F9: two vertices
 * 1e-16 apart, the third at distance 3), differences taken from the far
 * vertex lose the short edge, and n points anywhere. Ties (and NaN lengths
 * of overflowing edges) keep vertex 0. e1 is the edge opposite vertex base + 2, the same difference; e2 is
 * taken anew, as the negated opposite edge may differ from it in the sign of a zero. */
static inline void cbvh_triangle_frame_of_edges(const cbvh_v3 v[3], const struct cbvh_triangle_edges *e,
                                                struct cbvh_triangle_frame *f)
{
    const double len0 = e->len2[0], len1 = e->len2[1], len2 = e->len2[2];
    const int base = len1 > len0 ? (len2 > len1 ? 2 : 1) : (len2 > len0 ? 2 : 0);
    f->base = base;
    f->e1 = e->edge[cbvh_frame_vertex(base, 2)];
    f->e2 = v3_sub(v[cbvh_frame_vertex(base, 2)], v[base]);
    f->n = v3_cross(f->e1, f->e2);
    f->nn = v3_len2(f->n);
}

static inline void cbvh_triangle_frame_of(const cbvh_v3 v[3], struct cbvh_triangle_frame *f)
{
    struct cbvh_triangle_edges e;
    cbvh_triangle_edges_of(v, &e);
    cbvh_triangle_frame_of_edges(v, &e, f);
}

/* Barycentrics (x, y) of base + w projected onto the plane, with
 * w ~ x e1 + y e2: x = (w x e2).n / n.n, y = (e1 x w).n / n.n. Their errors
 * scale with the edge lengths, not with the area (a Gram-matrix solve or
 * sheared edge functions cancel on slivers: findings F4 and F6). Only for
 * nn > 0. */
static inline void cbvh_triangle_frame_barycentrics(const struct cbvh_triangle_frame *f, cbvh_v3 w, double *x,
                                                    double *y)
{
    *x = v3_dot(v3_cross(w, f->e2), f->n) / f->nn;
    *y = v3_dot(v3_cross(f->e1, w), f->n) / f->nn;
}

/* u and v (the weights of vertices 1 and 2) of the point with barycentrics x, y (the weights of vertices
 * base + 1 and base + 2) in a frame whose base vertex is `base`. */
static inline void cbvh_frame_uv(int base, double x, double y, float *u, float *v)
{
    double weight[3]; /* of vertices 0, 1, 2 */
    weight[cbvh_frame_vertex(base, 1)] = x;
    weight[cbvh_frame_vertex(base, 2)] = y;
    weight[base] = 1.0 - x - y;
    *u = (float)weight[1];
    *v = (float)weight[2];
}

#endif
