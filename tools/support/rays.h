/* rays.h: deterministic benchmark ray sets (incoherent, coherent camera tiles, shadow rays, short probes)
 * from a seed. */
#ifndef CBVH_RAYS_H
#define CBVH_RAYS_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

typedef enum ray_kind {
    RAYS_INCOHERENT = 0, /* origins uniform in the bounds, directions uniform on the sphere */
    RAYS_COHERENT = 1,   /* pinhole camera looking at the mesh, 8x8 pixel tiles in tile order */
    RAYS_SHADOW = 2,     /* from points on the triangles towards a point light, ending just before it */
    RAYS_SHORT = 3       /* game probes: 1% of the diagonal long, from just off a point of a triangle */
} ray_kind;
#define RAYS_KIND_COUNT 4

/* "incoherent", "coherent", "shadow", "short". */
const char *rays_kind_name(ray_kind kind);

/* The mesh the rays are aimed at: tightly packed xyz positions and 3 indices per triangle. */
typedef struct rays_mesh {
    const float *positions;
    size_t vertex_count;
    const uint32_t *indices;
    size_t triangle_count;
} rays_mesh;

/* Bounds of the vertices the triangles use; returns the length of the diagonal. */
double rays_mesh_bounds(const rays_mesh *mesh, float lo[3], float hi[3]);

/* Fills out[0..count) with rays of `kind` aimed at `mesh`, the same rays for the
 * same seed on every platform. Every ray has a finite tmax that reaches past
 * the mesh (peers such as Bullet cast segments, not infinite rays), but for
 * short rays, which are segments themselves. Incoherent and short directions
 * are unit length; coherent and shadow directions are not.
 * Precondition: mesh->triangle_count > 0. */
void rays_generate(ray_kind kind, const rays_mesh *mesh, uint64_t seed, cbvh_ray *out, size_t count);

/* The samplers the ray sets (and tools/support/shapes.c) draw from a generator state: a unit direction
 * uniform on the sphere; a point of a triangle picked uniformly by index, uniformly on that triangle, and
 * (when normal is not NULL) that triangle's unit normal as wound. */
void rays_unit_direction(uint64_t *state, float dir[3]);
void rays_surface_point(const rays_mesh *mesh, uint64_t *state, double p[3], double normal[3]);

#endif
