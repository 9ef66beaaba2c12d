/* sweep_features.h: first entry of a moving point into a ball, a finite cylinder side, or a thickened face.
 */
#ifndef CBVH_QUERY_SWEEP_FEATURES_H
#define CBVH_QUERY_SWEEP_FEATURES_H

#include "query/vec3d.h"

/* A first contact: time, point on the triangle, unit normal from the triangle towards the shape, and at
 * t = 0 how far the shape reaches into the triangle along the normal (0 otherwise). */
struct cbvh_sweep_contact {
    double t;
    cbvh_v3 point;
    cbvh_v3 normal;
    double depth;
};

/* The moving point is o + t*d for t in [0, tmax]. Each test below reports the
 * first time the point enters one convex piece of a Minkowski sum (the shape
 * dilated by radius r) from outside; a point already inside reports nothing,
 * the caller checks overlap at t = 0 first. The pieces are those of a
 * sphere-swept triangle (or parallelogram): the thickened face, the edge
 * cylinders and the vertex balls. The first entry into their union is the
 * earliest entry into any of them, so each can be tested on its own. */

/* Ball of radius r around c. Writes t and the unit outward normal at entry. */
int cbvh_enter_ball(cbvh_v3 o, cbvh_v3 d, cbvh_v3 c, double r, double tmax, double *t, cbvh_v3 *normal);

/* Side of the cylinder of radius r around segment p-q (caps excluded: the
 * end balls cover them). Writes t, the radial unit normal and the axis
 * parameter in [0, 1] of the entry point. */
int cbvh_enter_cylinder(cbvh_v3 o, cbvh_v3 d, cbvh_v3 p, cbvh_v3 q, double r, double tmax, double *t,
                        cbvh_v3 *normal, double *axis);

/* One of the two faces at distance r of the flat piece base + a*e1 + b*e2
 * (triangle: a, b >= 0, a + b <= 1; parallelogram: a, b in [0, 1]). Writes t,
 * the unit face normal on the side of o, and (a, b) of the entry point. */
int cbvh_enter_face(cbvh_v3 o, cbvh_v3 d, cbvh_v3 base, cbvh_v3 e1, cbvh_v3 e2, int parallelogram, double r,
                    double tmax, double *t, cbvh_v3 *normal, double *a, double *b);

/* A ball of radius r >= 0 centred at o moving by d, which does not overlap
 * triangle (a, b, c) at t = 0: first contact with t <= tmax over face, edges
 * and vertices (the face only when r = 0). Returns 1 and fills *out (point
 * on the triangle). */
int cbvh_sweep_ball_triangle(cbvh_v3 o, cbvh_v3 d, double r, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                             struct cbvh_sweep_contact *out);

/* The normal used when shape and triangle touch with no separating
 * direction (a zero-distance contact): the face normal turned against the
 * motion d (as wound when d is parallel to the face or zero); -d or +z for
 * a degenerate triangle. */
cbvh_v3 cbvh_fallback_normal(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 d);

#endif
