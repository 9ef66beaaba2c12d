/* placement.h: a query transform (cbvh_transform) as a rotation matrix, and points and vectors taken through
 * it. */
#ifndef CBVH_QUERY_PLACEMENT_H
#define CBVH_QUERY_PLACEMENT_H

#include "cbvh.h"
#include "query/vec3d.h"

/* world = translation + scale * rotation * local, in double. */
struct cbvh_placement {
    double rotation[3]
                   [3]; /* the normalized quaternion's matrix; its columns are the local axes in the world */
    cbvh_v3 translation;
    double scale;
};

/* The matrix of quaternion q (x, y, z, w), normalized in double. Returns 0 when q is not finite or zero. */
int cbvh_rotation_of_quaternion(const float q[4], double m[3][3]);

/* Checks transform t (finite, non-zero quaternion, scale > 0) and fills *p. Returns 0 when it is invalid. */
int cbvh_placement_of(const cbvh_transform *t, struct cbvh_placement *p);

/* The placement of a query's transform t: *out is NULL when t is NULL (the mesh's own frame), else
 * `storage` filled by cbvh_placement_of. Returns 0 for an invalid transform. */
static inline int cbvh_placement_of_option(const cbvh_transform *t, struct cbvh_placement *storage,
                                           const struct cbvh_placement **out)
{
    *out = t ? storage : NULL;
    return !t || cbvh_placement_of(t, storage);
}

/* A world point or displacement in the mesh's frame, and a mesh point back in the world. */
static inline cbvh_v3 cbvh_vector_to_mesh(const struct cbvh_placement *p, cbvh_v3 world)
{
    const cbvh_v3 r = cbvh_rotate_back(p->rotation, world);
    return v3(r.x / p->scale, r.y / p->scale, r.z / p->scale);
}
static inline cbvh_v3 cbvh_point_to_mesh(const struct cbvh_placement *p, cbvh_v3 world)
{
    return cbvh_vector_to_mesh(p, v3_sub(world, p->translation));
}
static inline cbvh_v3 cbvh_point_to_world(const struct cbvh_placement *p, cbvh_v3 mesh)
{
    return v3_add(p->translation, v3_scale(cbvh_rotate(p->rotation, mesh), p->scale));
}

#endif
