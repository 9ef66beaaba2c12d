/* triangle_box.h: the separating-axis test of a triangle and a box (axis-aligned or oriented), static or
 * moving. */
#ifndef CBVH_QUERY_TRIANGLE_BOX_H
#define CBVH_QUERY_TRIANGLE_BOX_H

#include "query/vec3d.h"

/* Box (center, half extents) moving by center + t * delta, t in [0, tmax],
 * against triangle (a, b, c), on the 13 axes (3 box axes, the triangle's
 * normal, the 9 crosses of box axes and triangle edges), whose set of face
 * normals of the configuration obstacle triangle - box is complete, so the
 * test is exact up to rounding in double. Touching counts (closed sets).
 * Returns 1 when they touch; *t is the first time (0 when they overlap at the
 * start) and *normal the unit axis (from the triangle towards the box) that
 * separated them last, or at t = 0 the axis of least penetration, with
 * *depth (when depth is not NULL) how far the box reaches along it: the exact
 * penetration depth, since those axes hold every face normal of the
 * obstacle. With delta = 0 and tmax = 0 this is the static overlap test. normal may be NULL (then depth is
 * not written either): the yes or no alone. */
int cbvh_triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 delta,
                            double tmax, double *t, cbvh_v3 *normal, double *depth);

/* A box whose axes may be turned: the columns of `axes` are its unit axes (the identity unless rotated). */
struct cbvh_box {
    cbvh_v3 center, half;
    int rotated;
    double axes[3][3];
};

/* cbvh_triangle_box_sweep for any box: an oriented one is tested in its own frame (triangle and motion
 * rotated into it, the normal rotated back), the same 13 axes. */
int cbvh_triangle_oriented_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box,
                                     cbvh_v3 delta, double tmax, double *t, cbvh_v3 *normal, double *depth);

/* A point of triangle (a, b, c) where it touches the box moved to `center`: the mean of the corners of the
 * triangle clipped to the box grown by tol (the contact set is a point, segment or polygon; the mean of a
 * convex polygon's corners lies in it). When rounding leaves nothing, the triangle's vertex farthest along
 * `normal` (the contact normal, from the triangle towards the box). */
cbvh_v3 cbvh_box_contact_point(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box, cbvh_v3 center,
                               cbvh_v3 normal, double tol);

#endif
