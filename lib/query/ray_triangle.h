/* ray_triangle.h: the watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013). */
#ifndef CBVH_QUERY_RAY_TRIANGLE_H
#define CBVH_QUERY_RAY_TRIANGLE_H

#include "query/ray_setup.h"

/* Tests the ray (sheared by s) against triangle (a, b, c). Returns 1 when it
 * hits at t in [tmin, tmax] and writes t and the barycentrics u (weight of b)
 * and v (weight of c). Watertight: a ray through a shared edge or vertex hits
 * at least one of the triangles sharing it, because the edge functions are
 * computed identically for both (in double when a float result is exactly 0)
 * and the sign test accepts 0 on either side. A ray in the triangle's plane
 * (det == 0) misses, as does a degenerate triangle. Both windings are hit. */
static inline int cbvh_ray_triangle(const struct cbvh_ray_shear *restrict s, const float *restrict a,
                                    const float *restrict b, const float *restrict c, float tmin, float tmax,
                                    float *t_out, float *u_out, float *v_out)
{
    const uint32_t kx = s->kx, ky = s->ky, kz = s->kz;
    const float sx = s->sx, sy = s->sy, sz = s->sz;
    const float ox = s->org[kx], oy = s->org[ky], oz = s->org[kz];

    /* Vertices relative to the origin, then sheared so the ray is the +z axis. */
    const float az = a[kz] - oz, bz = b[kz] - oz, cz = c[kz] - oz;
    const float ax = (a[kx] - ox) - sx * az, ay = (a[ky] - oy) - sy * az;
    const float bx = (b[kx] - ox) - sx * bz, by = (b[ky] - oy) - sy * bz;
    const float cx = (c[kx] - ox) - sx * cz, cy = (c[ky] - oy) - sy * cz;

    /* Scaled barycentrics: 2D edge functions of the sheared triangle at the origin. */
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if (u == 0.0f || v == 0.0f || w == 0.0f) {
        /* On an edge in float: products of floats are exact in double, so the
         * double difference has the exact sign; both neighbours agree on it. */
        u = (float)((double)cx * (double)by - (double)cy * (double)bx);
        v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
        w = (float)((double)bx * (double)ay - (double)by * (double)ax);
    }
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return 0;
    const float det = u + v + w;
    if (det == 0.0f)
        return 0;
    const float tz = u * (sz * az) + v * (sz * bz) + w * (sz * cz);
    const float inv = 1.0f / det;
    const float t = tz * inv;
    /* Ordered compares: t is never NaN here, but an overflowed t (inf) fails t <= tmax <= CBVH_T_LIMIT. */
    if (!(t >= tmin && t <= tmax))
        return 0;
    *t_out = t;
    *u_out = v * inv;
    *v_out = w * inv;
    return 1;
}

#endif
