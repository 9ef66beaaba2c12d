/* raycast.h: the single-ray traversal kernels behind cbvh_raycast and cbvh_occluded. */
#ifndef CBVH_QUERY_RAYCAST_H
#define CBVH_QUERY_RAYCAST_H

#include "common/file.h"
#include "query/leaf.h"
#include "query/ray_setup.h"

/* Each kernel takes a validated ray; closest-hit kernels fill *best (cooked
 * index, UINT32_MAX for none). stats may be NULL: the counting variants are
 * separate instances, so the uncounted path does no bookkeeping. */

/* Stack walk; sorted = 1 orders children by the node's sort byte, 0 takes the first child first. */
void cbvh_closest_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted,
                        struct cbvh_best_hit *best, cbvh_query_stats *stats);
int cbvh_any_stack(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, int sorted, cbvh_query_stats *stats);

/* Stack walk ordering children by their box entry distance, computed at run time. */
void cbvh_closest_distance(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, struct cbvh_best_hit *best,
                           cbvh_query_stats *stats);
int cbvh_any_distance(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats);

/* Stackless walk over escape links. */
void cbvh_closest_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, struct cbvh_best_hit *best,
                            cbvh_query_stats *stats);
int cbvh_any_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats);

/* cbvh_ray_setup for a ray cast into file f: also moves an origin far from
 * the file's bounds next to them (ray_origin.c), so the triangle test keeps
 * its precision; ctx->t_base is then the distance moved. Returns 0 for an
 * invalid ray. */
int cbvh_ray_prepare(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray, const struct cbvh_file *f);

/* Converts a kernel's best hit into the public form (original id, t on the
 * caller's ray: t_base + the kernel's t). Returns 1 on a hit. */
int cbvh_hit_output(const struct cbvh_file *f, const struct cbvh_best_hit *best, double t_base, cbvh_hit *hit);

#endif
