/* triangle_box.h: the separating-axis test of a triangle and an axis-aligned box, static or moving. */
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
 * separated them last, or at t = 0 the axis of least penetration.
 * With delta = 0 and tmax = 0 this is the static overlap test. */
int cbvh_triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 delta, double tmax,
                            double *t, cbvh_v3 *normal);

#endif
