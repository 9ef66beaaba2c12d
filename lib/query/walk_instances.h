/* walk_instances.h: the walk modes the library instantiates, one list for every instruction set's instances.
 */
#ifndef CBVH_QUERY_WALK_INSTANCES_H
#define CBVH_QUERY_WALK_INSTANCES_H

#include "common/file.h"
#include "layout/tree.h"
#include "query/leaf.h"
#include "query/ray_setup.h"

/* X(name, order, any) for each instance: the walk's order (enum cbvh_walk_order) and whether it stops at
 * the first hit. */
#define CBVH_WALK_INSTANCES(X)                                                                               \
    X(closest_sorted, CBVH_WALK_SORTED, 0)                                                                   \
    X(closest_unsorted, CBVH_WALK_UNSORTED, 0)                                                               \
    X(closest_distance, CBVH_WALK_DISTANCE, 0)                                                               \
    X(any_sorted, CBVH_WALK_SORTED, 1)                                                                       \
    X(any_unsorted, CBVH_WALK_UNSORTED, 1)                                                                   \
    X(any_distance, CBVH_WALK_DISTANCE, 1)

#ifdef CBVH_HAVE_AVX2
/* The wide layout's instances compiled for AVX2 (raycast_walks_avx2.c), for CPUs that have it (the
 * caller checks, raycast_walks.c): cbvh_walk on the subtree `start`, whose box the caller tested. */
#define CBVH_WALK_AVX2_DECLARE(name, order, any)                                                             \
    int cbvh_walk_##name##_wide4_avx2(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,             \
                                      cbvh_ref start, struct cbvh_best_hit *best, cbvh_query_stats *stats);
CBVH_WALK_INSTANCES(CBVH_WALK_AVX2_DECLARE)
#undef CBVH_WALK_AVX2_DECLARE
#endif

#endif
