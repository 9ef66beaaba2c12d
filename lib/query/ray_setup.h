/* ray_setup.h: per-ray validation and precomputation (reciprocal, octant, watertight shear), done once per ray. */
#ifndef CBVH_QUERY_RAY_SETUP_H
#define CBVH_QUERY_RAY_SETUP_H

#include <float.h>
#include <math.h>
#include <stdint.h>

#include "cbvh.h"
#include "common/compiler.h"
#include "common/format.h"

/* Kernels are written once with constant flags (any-hit, counting) and
 * instantiated per flag set; forcing inlining makes each instance lose the
 * code its flags switch off. */
#define CBVH_KERNEL CBVH_FORCE_INLINE

/* The largest t a ray reports: FLT_MAX / 2, so tmax * CBVH_BOX_PAD cannot overflow. */
#define CBVH_T_LIMIT 0x1.fffffep126f

/* What the triangle test needs from a ray: the origin and the shear of
 * Woop, Benthin & Wald 2013 ("Watertight ray/triangle intersection"). */
struct cbvh_ray_shear {
    float org[3];
    float dir[3];      /* for t from the triangle's plane (ray_triangle.h) */
    double dir_inv[3]; /* 1 / dir and |dir|^2 in double, for the plane t's clamps: once per ray, not per hit */
    double dir_len2;
    float sx, sy, sz;  /* dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz] */
    uint32_t kx, ky, kz; /* kz: dominant axis of dir; kx, ky keep the winding */
};

/* A validated ray, ready for traversal. */
struct cbvh_ray_ctx {
    struct cbvh_ray_shear shear;
    float rcp[3];         /* 1/dir: 0 and -0 give +inf and -inf, which the box test handles */
    float tmin, tmax;     /* tmax clamped to CBVH_T_LIMIT: an overflowed t never counts as a hit, and the
                           * box test's padded tmax stays finite, so a box at infinity is never entered */
    double t_base;        /* t of shear.org on the caller's ray: 0, or the distance a far origin was moved
                           * (ray_origin.c); the kernels' t and [tmin, tmax] are relative to it */
    uint32_t box_halve;   /* bit a: a plane - org difference on axis a can overflow (coordinates past
                           * FLT_MAX / 2), so the box test runs on that axis at half scale (ray_box.h) */
    uint32_t octant;      /* bit a set when rcp[a] has its sign bit set (so -0 counts as negative): selects
                           * the precomputed child order (layout/tree.h) */
    const struct cbvh_hit_gate *gate; /* NULL, or the culling and hit filter of a query with options
                                       * (raycast.c), asked about each candidate hit (leaf.h) */
};

/* The octant of a reciprocal direction, from its sign bits. Every kernel
 * takes the octant from here so the sort byte and the box test agree. */
static inline uint32_t cbvh_octant_of(const float rcp[3])
{
    return (uint32_t)(signbit(rcp[0]) != 0) | (uint32_t)(signbit(rcp[1]) != 0) << 1 |
           (uint32_t)(signbit(rcp[2]) != 0) << 2;
}

static inline void cbvh_shear_setup(struct cbvh_ray_shear *s, const float org[3], const float dir[3])
{
    float ax = fabsf(dir[0]), ay = fabsf(dir[1]), az = fabsf(dir[2]);
    /* kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2), kx and ky the next axes, swapped for a
     * negative dir[kz] (which keeps the winding, so the sign test stays the same); in integer arithmetic:
     * which way a ray points is as unpredictable as the ray, and branches on it mispredict */
    const uint32_t x_wins = 0u - (uint32_t)(ax > ay);
    const uint32_t kz = ((2u - 2u * (uint32_t)(ax > az)) & x_wins) | ((2u - (uint32_t)(ay > az)) & ~x_wins);
    uint32_t kx = (0x021u >> (4u * kz)) & 0xFu; /* (kz + 1) mod 3 */
    uint32_t ky = (0x021u >> (4u * kx)) & 0xFu;
    const uint32_t swap = (kx ^ ky) & (0u - (uint32_t)(dir[kz] < 0.0f));
    kx ^= swap;
    ky ^= swap;
    s->kx = kx;
    s->ky = ky;
    s->kz = kz;
    s->sx = dir[kx] / dir[kz];
    s->sy = dir[ky] / dir[kz];
    s->sz = 1.0f / dir[kz];
    for (int a = 0; a < 3; a++) {
        s->org[a] = org[a];
        s->dir[a] = dir[a];
        s->dir_inv[a] = 1.0 / (double)dir[a];
    }
    s->dir_len2 = (double)dir[0] * dir[0] + (double)dir[1] * dir[1] + (double)dir[2] * dir[2];
}

/* 1 when the ray is valid (cbvh.h: finite org and dir, dir not all zero,
 * 0 <= tmin <= tmax, tmax finite or +inf), else 0. */
static inline int cbvh_ray_valid(const cbvh_ray *ray)
{
    const float *o = ray->org, *d = ray->dir;
    if (!(isfinite(o[0]) && isfinite(o[1]) && isfinite(o[2]) && isfinite(d[0]) && isfinite(d[1]) &&
          isfinite(d[2]) && isfinite(ray->tmin)))
        return 0;
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
        return 0;
    /* Ordered compares: a NaN tmax fails them and is rejected. */
    return ray->tmin >= 0.0f && ray->tmin <= ray->tmax;
}

/* The octant of a valid ray (cbvh_octant_of its reciprocal) without computing the reciprocal: 1/d has
 * d's sign bit for every d that is not NaN, ±0 (±inf) included. */
static inline uint32_t cbvh_ray_octant(const cbvh_ray *ray)
{
    return (uint32_t)(signbit(ray->dir[0]) != 0) | (uint32_t)(signbit(ray->dir[1]) != 0) << 1 |
           (uint32_t)(signbit(ray->dir[2]) != 0) << 2;
}

/* Returns 1 and fills ctx when the ray is valid (cbvh_ray_valid), else 0. */
static inline int cbvh_ray_setup(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray)
{
    const float *o = ray->org, *d = ray->dir;
    if (!cbvh_ray_valid(ray))
        return 0;
    for (int a = 0; a < 3; a++)
        ctx->rcp[a] = 1.0f / d[a];
    ctx->t_base = 0.0;
    ctx->box_halve = 0;
    ctx->gate = NULL;
    ctx->tmin = ray->tmin;
    ctx->tmax = ray->tmax < CBVH_T_LIMIT ? ray->tmax : CBVH_T_LIMIT;
    ctx->octant = cbvh_octant_of(ctx->rcp);
    cbvh_shear_setup(&ctx->shear, o, d);
    return 1;
}

#endif
