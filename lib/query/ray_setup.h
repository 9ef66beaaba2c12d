/* ray_setup.h: per-ray validation and precomputation (reciprocal, octant, watertight shear), done once per
 * ray. */
#ifndef CBVH_QUERY_RAY_SETUP_H
#define CBVH_QUERY_RAY_SETUP_H

#ifdef CBVH_HAVE_SIMD
#include <emmintrin.h>
#endif
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "cbvh.h"
#include "common/compiler.h"
#include "common/format.h"

/* Kernels take constant flags and are force-inlined into each instance, which loses what they switch off. */
#define CBVH_KERNEL CBVH_FORCE_INLINE

/* The largest t a ray reports: FLT_MAX / 2, so tmax * CBVH_BOX_PAD cannot overflow. */
#define CBVH_T_LIMIT 0x1.fffffep126f

/* The query side of the exact range (docs/EXACTNESS.md): the kernels walk a ray whose direction's largest
 * component lies in [2^-20, 2^20] or, scaled by a power of two, in [2^CBVH_DIR_EXPONENT,
 * 2^(CBVH_DIR_EXPONENT + 1)), whose other components are 0 or at least CBVH_DIR_FLUSH times it, and whose
 * origin coordinates are 0 or at least CBVH_ORIGIN_FLUSH: with the cooker's range no step of a box or
 * triangle test then rounds in the subnormal range, and no t that could be a hit overflows. */
#define CBVH_DIR_EXPONENT 8
#define CBVH_DIR_FLUSH 0x1p-60f
#define CBVH_ORIGIN_FLUSH 0x1p-64f

/* Where a kernel's t lies on the caller's ray: (base + t) * scale. base: the distance a far origin was moved
 * (ray_origin.c), in the kernels' t; scale: the power of two the direction was divided by. */
struct cbvh_t_frame {
    double base, scale;
};

/* A kernel's t on the caller's ray. */
static inline float cbvh_t_frame_out(const struct cbvh_t_frame *frame, float t)
{
    if (CBVH_LIKELY(frame->base == 0.0 && frame->scale == 1.0))
        return t;
    return (float)((frame->base + (double)t) * frame->scale);
}

/* x rounded to float towards +inf (up = 1) or -inf (up = 0). */
static inline float cbvh_float_rounded(double x, int up)
{
    float f = (float)x;
    if (up && (double)f < x)
        f = nextafterf(f, INFINITY);
    if (!up && (double)f > x)
        f = nextafterf(f, -INFINITY);
    return f;
}

/* Origin coordinates below CBVH_ORIGIN_FLUSH in magnitude become 0. */
static inline void cbvh_origin_flush(float org[3])
{
    for (int a = 0; a < 3; a++)
        org[a] = fabsf(org[a]) < CBVH_ORIGIN_FLUSH ? 0.0f : org[a];
}

/* What the triangle test needs from a ray: the origin and the shear of
 * Woop, Benthin & Wald 2013 ("Watertight ray/triangle intersection"). */
struct cbvh_ray_shear {
    float org[3];
    float dir[3];        /* for t from the triangle's plane (ray_triangle.h) */
    float sx, sy, sz;    /* dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz] */
    uint32_t kx, ky, kz; /* kz: dominant axis of dir; kx, ky keep the winding */
};

/* A validated ray, ready for traversal. */
struct cbvh_ray_ctx {
    struct cbvh_ray_shear shear;
    float rcp[3];                /* 1/dir: 0 and -0 give +inf and -inf, which the box test handles */
    float tmin, tmax;            /* tmax clamped to CBVH_T_LIMIT, so a padded tmax stays finite */
    struct cbvh_t_frame t_frame; /* the kernels' t and [tmin, tmax] on the caller's ray */
    uint32_t box_halve;          /* bit a: the box test runs at half scale on axis a (ray_box.h) */
    uint32_t octant;             /* bit a: rcp[a]'s sign bit (-0 counts as negative) */
    uint32_t any_flip; /* 7 when the origin lies inside the mesh's bounds (cbvh_ray_prepare), else 0: an
                        * any-hit walk takes the child order of octant ^ any_flip (walk.h) */
    const struct cbvh_hit_gate *gate; /* NULL, or a query's culling and hit filter (leaf.h) */
};

/* The octant of a reciprocal direction (or of a direction: 1/d has d's sign bit), from its sign bits. */
static inline uint32_t cbvh_octant_of(const float rcp[3])
{
    return (uint32_t)(signbit(rcp[0]) != 0) | (uint32_t)(signbit(rcp[1]) != 0) << 1 |
           (uint32_t)(signbit(rcp[2]) != 0) << 2;
}

#ifdef CBVH_HAVE_SIMD
/* p[0..2] into lanes 0-2 and 0 into lane 3: two loads, none past p[2]. */
static inline __m128 cbvh_load3(const float *p)
{
    return _mm_movelh_ps(_mm_loadl_pi(_mm_setzero_ps(), (const __m64 *)(const void *)p), _mm_load_ss(p + 2));
}

/* Lanes 0-2 of v into p[0..2], nothing past them. */
static inline void cbvh_store3(float *p, __m128 v)
{
    _mm_storel_pi((__m64 *)(void *)p, v);
    _mm_store_ss(p + 2, _mm_movehl_ps(v, v));
}
#endif

static inline void cbvh_shear_setup(struct cbvh_ray_shear *s, const float org[3], const float dir[3])
{
    /* kz: the largest |dir| axis, kx and ky the next in cyclic order, swapped for a negative dir[kz] (which
     * keeps the winding), from tables rather than branches. KZ: 2 bits for each outcome of (ax > ay) |
     * (ax > az) << 1 | (ay > az) << 2; KXY: kx | ky << 2 in 4 bits at 2 * kz + (dir[kz] < 0). */
    enum { KZ = 0x192A, KXY = 0x148269 };
#ifdef CBVH_HAVE_SIMD
    /* the three compares at once: |dir| against itself rotated to (ay, az, ax) and to (az, ax, ay) */
    const __m128 d = cbvh_load3(dir), mag = _mm_andnot_ps(_mm_set1_ps(-0.0f), d);
    const uint32_t next = (uint32_t)_mm_movemask_ps(
        _mm_cmpgt_ps(mag, _mm_shuffle_ps(mag, mag, _MM_SHUFFLE(3, 0, 2, 1)))); /* ax > ay, ay > az */
    const uint32_t prev = (uint32_t)_mm_movemask_ps(
        _mm_cmpgt_ps(mag, _mm_shuffle_ps(mag, mag, _MM_SHUFFLE(3, 1, 0, 2)))); /* ax > az */
    const uint32_t outcome = (next & 1u) | (prev & 1u) << 1 | (next & 2u) << 1;
    const uint32_t kz = (uint32_t)KZ >> (2u * outcome) & 3u;
    const uint32_t negative = (uint32_t)_mm_movemask_ps(d) >> kz & 1u;
#else
    const float ax = fabsf(dir[0]), ay = fabsf(dir[1]), az = fabsf(dir[2]);
    const uint32_t outcome = (uint32_t)(ax > ay) | (uint32_t)(ax > az) << 1 | (uint32_t)(ay > az) << 2;
    const uint32_t kz = (uint32_t)KZ >> (2u * outcome) & 3u;
    const uint32_t negative = (uint32_t)(dir[kz] < 0.0f);
#endif
    const uint32_t kxy = (uint32_t)KXY >> (4u * (2u * kz + negative));
    const uint32_t kx = kxy & 3u, ky = kxy >> 2 & 3u;
    s->kx = kx;
    s->ky = ky;
    s->kz = kz;
#ifdef CBVH_HAVE_SIMD
    /* the same quotients as below, three to an instruction */
    cbvh_store3(&s->sx, _mm_div_ps(_mm_setr_ps(dir[kx], dir[ky], 1.0f, 1.0f), _mm_set1_ps(dir[kz])));
    cbvh_store3(s->org, cbvh_load3(org));
    cbvh_store3(s->dir, d);
#else
    s->sx = dir[kx] / dir[kz];
    s->sy = dir[ky] / dir[kz];
    s->sz = 1.0f / dir[kz];
    for (int a = 0; a < 3; a++) {
        s->org[a] = org[a];
        s->dir[a] = dir[a];
    }
#endif
}

/* 1 when all n floats are finite: the check of a query's points and vectors (rays, sweeps, boxes). */
static inline int cbvh_all_finite(const float *v, int n)
{
    for (int k = 0; k < n; k++)
        if (!isfinite(v[k]))
            return 0;
    return 1;
}

/* 1 when the ray is valid (finite org and dir, dir not zero, 0 <= tmin <= tmax, tmax finite or +inf). */
static inline int cbvh_ray_valid(const cbvh_ray *ray)
{
#ifdef CBVH_HAVE_SIMD
    /* org and tmin, dir and tmax are four consecutive floats each (cbvh.h): finite in the first seven
     * lanes (|x| <= FLT_MAX fails for inf and NaN), dir not zero in all three */
    _Static_assert(offsetof(cbvh_ray, tmin) == 3 * sizeof(float) &&
                       offsetof(cbvh_ray, tmax) == 7 * sizeof(float),
                   "cbvh_ray is org, tmin, dir, tmax");
    const __m128 org_tmin = _mm_loadu_ps(ray->org), dir_tmax = _mm_loadu_ps(ray->dir);
    const __m128 sign = _mm_set1_ps(-0.0f), largest = _mm_set1_ps(FLT_MAX);
    const int finite = _mm_movemask_ps(_mm_cmple_ps(_mm_andnot_ps(sign, org_tmin), largest)) |
                       _mm_movemask_ps(_mm_cmple_ps(_mm_andnot_ps(sign, dir_tmax), largest)) << 4;
    const int zero = _mm_movemask_ps(_mm_cmpeq_ps(dir_tmax, _mm_setzero_ps()));
    if ((finite & 0x7F) != 0x7F || (zero & 7) == 7)
        return 0;
#else
    const float *o = ray->org, *d = ray->dir;
    if (!(isfinite(o[0]) && isfinite(o[1]) && isfinite(o[2]) && isfinite(d[0]) && isfinite(d[1]) &&
          isfinite(d[2]) && isfinite(ray->tmin)))
        return 0;
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f)
        return 0;
#endif
    /* Ordered compares: a NaN tmax fails them and is rejected. */
    return ray->tmin >= 0.0f && ray->tmin <= ray->tmax;
}

/* The octant of a valid ray, without its reciprocal. */
static inline uint32_t cbvh_ray_octant(const cbvh_ray *ray)
{
    return cbvh_octant_of(ray->dir);
}

/* The ray the kernels walk (see CBVH_DIR_EXPONENT) from a valid ray: the caller's own when sanitizing
 * changes nothing, else *clean; clean's [tmin, tmax] is always set: the caller's range in the kernels' t,
 * rounded inwards and clamped to CBVH_T_LIMIT. The caller's t is the kernels' times *scale. A direction
 * whose largest component lies in [2^-CBVH_DIR_KEEP, 2^CBVH_DIR_KEEP] keeps its scale. */
#define CBVH_DIR_KEEP 20
static inline const cbvh_ray *cbvh_ray_sanitize(const cbvh_ray *ray, cbvh_ray *clean, double *scale)
{
    const float *d = ray->dir;
    clean->tmin = ray->tmin;
    clean->tmax = ray->tmax < CBVH_T_LIMIT ? ray->tmax : CBVH_T_LIMIT;
    *scale = 1.0;
    /* a component below big * CBVH_DIR_FLUSH becomes 0 of its sign */
#ifdef CBVH_HAVE_SIMD
    const __m128 sign = _mm_set1_ps(-0.0f), dv = cbvh_load3(d), mag = _mm_andnot_ps(sign, dv);
    const __m128 most = _mm_max_ps(_mm_max_ps(mag, _mm_shuffle_ps(mag, mag, _MM_SHUFFLE(3, 0, 2, 1))),
                                   _mm_shuffle_ps(mag, mag, _MM_SHUFFLE(3, 1, 0, 2)));
    const float big = _mm_cvtss_f32(most);
    const __m128 keep = _mm_cmpge_ps(mag, _mm_mul_ps(most, _mm_set1_ps(CBVH_DIR_FLUSH)));
    const __m128 ov = cbvh_load3(ray->org);
    const __m128 org_keep = _mm_cmpge_ps(_mm_andnot_ps(sign, ov), _mm_set1_ps(CBVH_ORIGIN_FLUSH));
    /* unchanged: every direction component kept or zero, every origin coordinate kept or +0 */
    const __m128 zero = _mm_setzero_ps();
    const int dir_same = _mm_movemask_ps(_mm_or_ps(keep, _mm_cmpeq_ps(mag, zero))) & 7;
    const int org_same =
        _mm_movemask_ps(_mm_or_ps(
            org_keep, _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_castps_si128(ov), _mm_setzero_si128())))) &
        7;
    if (CBVH_LIKELY((dir_same & org_same) == 7 && big >= 0x1p-20f && big <= 0x1p20f))
        return ray;
    cbvh_store3(clean->dir, _mm_or_ps(_mm_and_ps(dv, keep), _mm_and_ps(dv, sign)));
    cbvh_store3(clean->org, _mm_and_ps(ov, org_keep));
#else
    float big = fabsf(d[0]);
    big = fabsf(d[1]) > big ? fabsf(d[1]) : big;
    big = fabsf(d[2]) > big ? fabsf(d[2]) : big;
    const float flush = big * CBVH_DIR_FLUSH;
    for (int a = 0; a < 3; a++) {
        clean->dir[a] = fabsf(d[a]) < flush ? copysignf(0.0f, d[a]) : d[a];
        clean->org[a] = ray->org[a];
    }
    cbvh_origin_flush(clean->org);
#endif
    if (CBVH_LIKELY(big >= 0x1p-20f && big <= 0x1p20f))
        return clean;
    /* 2^(CBVH_DIR_EXPONENT - floor(log2 big)) and its inverse from the exponent of big as a double */
    const double wide = (double)big;
    uint64_t bits, up_bits, down_bits;
    memcpy(&bits, &wide, sizeof bits);
    bits = bits >> 52 & 0x7FFu;
    up_bits = (uint64_t)(2046u + CBVH_DIR_EXPONENT - bits) << 52;
    down_bits = (uint64_t)(bits - CBVH_DIR_EXPONENT) << 52;
    double up, down;
    memcpy(&up, &up_bits, sizeof up);
    memcpy(&down, &down_bits, sizeof down);
    for (int a = 0; a < 3; a++) /* exact: the flushed components are 0, the others at least 2^-60 big */
        clean->dir[a] = (float)((double)clean->dir[a] * up);
    const double tmax = ray->tmax < CBVH_T_LIMIT ? (double)ray->tmax : (double)CBVH_T_LIMIT;
    clean->tmin = cbvh_float_rounded((double)ray->tmin * down, 1);
    clean->tmax = cbvh_float_rounded(tmax * down < CBVH_T_LIMIT ? tmax * down : CBVH_T_LIMIT, 0);
    *scale = up;
    return clean;
}

/* For a valid ray, returns the ray the kernels walk (cbvh_ray_sanitize) and fills ctx but for its shear. */
static inline const cbvh_ray *cbvh_ray_setup_boxes(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray,
                                                   cbvh_ray *clean)
{
    if (!cbvh_ray_valid(ray))
        return NULL;
    const cbvh_ray *walked = cbvh_ray_sanitize(ray, clean, &ctx->t_frame.scale);
    const float *d = walked->dir;
#ifdef CBVH_HAVE_SIMD
    cbvh_store3(ctx->rcp, _mm_div_ps(_mm_set1_ps(1.0f), cbvh_load3(d)));
#else
    for (int a = 0; a < 3; a++)
        ctx->rcp[a] = 1.0f / d[a];
#endif
    ctx->octant = cbvh_ray_octant(walked);
    ctx->any_flip = 0;
    ctx->t_frame.base = 0.0;
    ctx->box_halve = 0;
    ctx->gate = NULL;
    ctx->tmin = clean->tmin;
    ctx->tmax = clean->tmax;
    return walked;
}

/* Returns 1 and fills ctx when the ray is valid (cbvh_ray_valid), else 0. */
static inline int cbvh_ray_setup(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray)
{
    cbvh_ray clean;
    const cbvh_ray *walked = cbvh_ray_setup_boxes(ctx, ray, &clean);
    if (!walked)
        return 0;
    cbvh_shear_setup(&ctx->shear, walked->org, walked->dir);
    return 1;
}

#endif
