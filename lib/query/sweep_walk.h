/* sweep_walk.h: the tree walk shared by the sphere, capsule and box sweeps. */
#ifndef CBVH_QUERY_SWEEP_WALK_H
#define CBVH_QUERY_SWEEP_WALK_H

#include "common/file.h"
#include "query/sweep_features.h"

/* Sweeps one triangle: first contact with t in [0, tmax] (t = 0 when the shape
 * already overlaps the triangle). Returns 1 and fills *out on contact. */
typedef int (*cbvh_sweep_triangle_fn)(const void *shape, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, double tmax,
                                      struct cbvh_sweep_contact *out);

/* Walks the nodes whose box, grown by `extent`, is crossed by the point
 * center + t * delta for t in [0, 1] (the shape lies in the box
 * center +- extent, so this culls exactly what the swept shape cannot touch),
 * nearer child first by the sort byte of delta's octant. Each triangle reached
 * goes to `sweep`; the earliest contact wins, ties to the lower cooked index.
 * Returns 1 and fills *hit (original id) on contact. */
int cbvh_sweep_walk(const struct cbvh_file *f, const float center[3], const float extent[3], const float delta[3],
                    cbvh_sweep_triangle_fn sweep, const void *shape, cbvh_sweep_hit *hit);

/* The float box center +- extent that surely holds the double box [lo, hi]. */
void cbvh_sweep_bounds(cbvh_v3 lo, cbvh_v3 hi, float center[3], float extent[3]);

/* Fills a miss. Returns 0. */
int cbvh_sweep_miss(cbvh_sweep_hit *hit);

/* 1 when all n floats are finite. */
int cbvh_all_finite(const float *v, int n);

/* A zero-size shape: the sweep is the ray center + t * delta, t in [0, 1],
 * answered by the ray kernel so that it agrees with cbvh_raycast exactly
 * (same triangle, same t); the normal is the face normal against delta. */
int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3], cbvh_sweep_hit *hit);

#endif
