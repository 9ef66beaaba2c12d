/* closest.h: closest points between a point, a segment and a triangle, in double precision. */
#ifndef CBVH_QUERY_CLOSEST_H
#define CBVH_QUERY_CLOSEST_H

#include "common/compiler.h"
#include "query/triangle_frame.h"
#include "query/vec3d.h"

static inline double cbvh_clamp01(double x)
{
    return x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
}

/* The projection of p onto the plane of triangle v (frame f, cbvh_triangle_frame_of) when its barycentrics
 * in the frame are in range: 1 and the point in *q; else 0 (a degenerate triangle has no inside). w is
 * p - v[f->base]. */
CBVH_FORCE_INLINE int cbvh_projection_inside(cbvh_v3 w, const cbvh_v3 v[3],
                                             const struct cbvh_triangle_frame *f, cbvh_v3 *q)
{
    if (!(f->nn > 0.0))
        return 0;
    double x, y;
    cbvh_triangle_frame_barycentrics(f, w, &x, &y);
    if (!(x >= 0.0 && y >= 0.0 && x + y <= 1.0))
        return 0;
    *q = v3_madd(v3_madd(v[f->base], f->e1, x), f->e2, y);
    return 1;
}

/* The point of segment a-b nearest to p: a clamped projection, well conditioned for any length; ab is
 * b - a, len2 its squared length and pa p - a. */
CBVH_FORCE_INLINE cbvh_v3 cbvh_closest_point_segment(cbvh_v3 a, cbvh_v3 ab, double len2, cbvh_v3 pa)
{
    return len2 > 0.0 ? v3_madd(a, ab, cbvh_clamp01(v3_dot(pa, ab) / len2)) : a;
}

/* cbvh_closest_point_triangle of triangle v, inlined into the overlap tests: the projection when it falls
 * inside (cbvh_projection_inside), else the nearest of the three edges' clamped projections: errors
 * relative to the lengths, not the area, so slivers and needles keep their precision (unlike Ericson's
 * Voronoi-region form). The frame's edges and their lengths serve the edges' projections too. */
CBVH_FORCE_INLINE cbvh_v3 cbvh_closest_point_in_triangle(cbvh_v3 p, const cbvh_v3 v[3])
{
    struct cbvh_triangle_edges e;
    struct cbvh_triangle_frame f;
    cbvh_triangle_edges_of(v, &e);
    cbvh_triangle_frame_of_edges(v, &e, &f);
    const cbvh_v3 pv[3] = {v3_sub(p, v[0]), v3_sub(p, v[1]), v3_sub(p, v[2])};
    cbvh_v3 inside;
    if (cbvh_projection_inside(pv[f.base], v, &f, &inside))
        return inside;
    /* edge v[i] to v[i + 1] is e.edge[i + 2] */
    cbvh_v3 best = cbvh_closest_point_segment(v[0], e.edge[2], e.len2[2], pv[0]);
    double d = v3_len2(v3_sub(p, best));
    const cbvh_v3 q1 = cbvh_closest_point_segment(v[1], e.edge[0], e.len2[0], pv[1]),
                  q2 = cbvh_closest_point_segment(v[2], e.edge[1], e.len2[1], pv[2]);
    const double d1 = v3_len2(v3_sub(p, q1)), d2 = v3_len2(v3_sub(p, q2));
    if (d1 < d) {
        best = q1;
        d = d1;
    }
    return d2 < d ? q2 : best;
}

/* The point of triangle (a, b, c) nearest to p: the projection onto the
 * plane when it falls inside, else the nearest point of the three edges.
 * Accurate on slivers of any aspect; works for degenerate triangles too
 * (then a point of an edge). */
cbvh_v3 cbvh_closest_point_triangle(cbvh_v3 p, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c);

/* Closest points of segments p0-p1 and q0-q1 (Ericson 5.1.9), degenerate
 * segments included; returns the squared distance, writes the points. */
double cbvh_closest_segments(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 q0, cbvh_v3 q1, cbvh_v3 *on_p, cbvh_v3 *on_q);

/* Closest points of segment p0-p1 and triangle (a, b, c): 0 when the segment
 * crosses the triangle, else the nearest of the pairs an endpoint makes with
 * its projection inside the triangle and of the segment-to-edge pairs (a
 * minimum with the triangle's point on no edge has an endpoint's projection
 * there, so one of them always attains it). Returns the squared distance. */
double cbvh_closest_segment_triangle(cbvh_v3 p0, cbvh_v3 p1, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 *on_seg,
                                     cbvh_v3 *on_tri);

/* cbvh_closest_segment_triangle of triangle v. */
double cbvh_closest_segment_triangle_of(cbvh_v3 p0, cbvh_v3 p1, const cbvh_v3 v[3], cbvh_v3 *on_seg,
                                        cbvh_v3 *on_tri);

#endif
