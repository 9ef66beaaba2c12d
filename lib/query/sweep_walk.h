/* sweep_walk.h: the tree walk shared by the sphere, capsule and box sweeps. */
#ifndef CBVH_QUERY_SWEEP_WALK_H
#define CBVH_QUERY_SWEEP_WALK_H

#include "common/file.h"
#include "query/placement.h"
#include "query/sweep_features.h"

/* What a sweep with options leaves out (cbvh_sweep_with): culling by the motion, the caller's filter (its
 * records in the world of `placement` when not NULL). */
struct cbvh_sweep_rules {
    cbvh_cull cull;
    cbvh_hit_filter_fn filter;
    void *user;
    const struct cbvh_placement *placement;
};

/* A sweep's answer: cooked triangle (UINT32_MAX for none) and its contact, in the mesh's frame. */
struct cbvh_sweep_found {
    uint32_t tri;
    struct cbvh_sweep_contact contact;
};

/* Sweeps `shape` (a sphere, capsule or box of some size) by delta with its kind's exact test of each
 * triangle (sweep_sphere.h, sweep_capsule.h, sweep_box.h), walking the nodes whose box, grown by the extent
 * of a float box center +- extent holding the shape (cbvh_shape_bounds), is crossed by the point
 * center + t * delta for t in [0, 1] (this culls exactly what the swept shape cannot touch), nearest entry
 * first (cbvh_shape_sort_nearest), in the walk kernel chosen for the rays (cbvh_walk_kernel). Each
 * triangle reached (past rules->cull) is tested; the earliest contact wins, ties to the lower cooked
 * index, a contact that would win asks rules->filter. rules may be NULL. Returns 1 on contact; fills
 * *found either way. */
struct cbvh_local_shape;
int cbvh_sweep_walk(const struct cbvh_file *f, const struct cbvh_local_shape *shape, const float delta[3],
                    const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found);

#ifdef CBVH_HAVE_AVX2
/* cbvh_sweep_walk's AVX2 instance (sweep_walk_avx2.c), for CPUs that have it (the caller checks). */
int cbvh_sweep_walk_avx2(const struct cbvh_file *f, const struct cbvh_local_shape *shape,
                         const float delta[3], const struct cbvh_sweep_rules *rules,
                         struct cbvh_sweep_found *found);
#endif

/* A zero-size shape: the sweep is the ray center + t * delta, t in [0, 1],
 * answered by the ray kernel so that it agrees with cbvh_raycast exactly
 * (same triangle, same t), under the rules' culling and filter; the normal is
 * the face normal against delta. Returns 1 on contact; fills *found either way. */
int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3],
                      const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found);

#endif
