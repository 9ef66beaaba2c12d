/* closest.h: closest points between a point, a segment and a triangle, in double precision. */
#ifndef CBVH_QUERY_CLOSEST_H
#define CBVH_QUERY_CLOSEST_H

#include "query/vec3d.h"

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

#endif
