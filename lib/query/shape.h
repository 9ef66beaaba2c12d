/* shape.h: a query shape (ball, capsule, oriented box) in the mesh's frame, as cbvh_shape and a query
 * transform make it. */
#ifndef CBVH_QUERY_SHAPE_H
#define CBVH_QUERY_SHAPE_H

#include "query/placement.h"

/* Every value is a float (rounded once from the caller's frame), held in double for the exact tests. */
struct cbvh_local_shape {
    cbvh_shape_kind kind;
    cbvh_v3 p0, p1;    /* sphere and box: p0 is the center (p1 = p0); capsule: the segment */
    double radius;     /* sphere, capsule */
    cbvh_v3 half;      /* box */
    int rotated;       /* box: 0 when its axes are the mesh's */
    double axes[3][3]; /* box: columns are its unit axes in the mesh's frame (the identity unless rotated) */
};

/* The shape `in` (in the world of placement p, or in the mesh's frame when p is NULL) in the mesh's frame.
 * Returns 0 for an invalid shape (unknown kind, a value not finite, a negative size, a zero quaternion that
 * is not all zero) or one that does not fit in float there. */
int cbvh_shape_to_mesh(const cbvh_shape *in, const struct cbvh_placement *p, struct cbvh_local_shape *out);

/* The box [lo, hi] (double) that holds the shape. */
void cbvh_shape_bounds(const struct cbvh_local_shape *s, cbvh_v3 *lo, cbvh_v3 *hi);

/* 1 when the shape has no size (a point): a sweep of it is a ray. */
int cbvh_shape_is_point(const struct cbvh_local_shape *s);

#endif
