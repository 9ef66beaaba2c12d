/* ray_triangle.h: the watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013), t from the plane in double. */
#ifndef CBVH_QUERY_RAY_TRIANGLE_H
#define CBVH_QUERY_RAY_TRIANGLE_H

#include "query/ray_setup.h"

#if defined(__GNUC__)
#define CBVH_LIKELY(x) __builtin_expect(!!(x), 1)
#define CBVH_COLD __attribute__((noinline, cold))
#else
#define CBVH_LIKELY(x) (x)
#define CBVH_COLD
#endif

/* Edge functions of the sheared triangle when float could not decide them:
 * one of them is 0, infinite or NaN (coordinates beyond about 1e12 relative
 * to the origin overflow coord^2 products), or their sum overflows. Returns
 * 0 on a miss, else 1 (the double edge functions are left in e[3]).
 *
 * Watertight across the two paths: rounding is monotonic, so a float edge
 * function that is finite and non-zero has the exact sign of the edge
 * function of the float sheared coordinates, and the double one below is
 * exact (a product of two floats is exact in double), so both paths decide
 * every edge the same way and two triangles sharing an edge agree whichever
 * path each takes. A vertex whose float sheared coordinates overflowed is
 * sheared in double instead; that choice depends on the vertex and the ray
 * only, and the two triangles' edge functions are then the same double
 * expression up to an exact negation, so they still agree. */
CBVH_COLD static int cbvh_ray_triangle_edges_double(const struct cbvh_ray_shear *s, const float *const v[3],
                                                    const float sheared[3][2], double e[3])
{
    double p[3][2];
    for (int k = 0; k < 3; k++) {
        if (isfinite(sheared[k][0]) && isfinite(sheared[k][1])) {
            p[k][0] = sheared[k][0];
            p[k][1] = sheared[k][1];
        } else {
            const double z = (double)v[k][s->kz] - s->org[s->kz];
            p[k][0] = ((double)v[k][s->kx] - s->org[s->kx]) - (double)s->sx * z;
            p[k][1] = ((double)v[k][s->ky] - s->org[s->ky]) - (double)s->sy * z;
        }
    }
    e[0] = p[2][0] * p[1][1] - p[2][1] * p[1][0]; /* u: edge b-c */
    e[1] = p[0][0] * p[2][1] - p[0][1] * p[2][0]; /* v: edge c-a */
    e[2] = p[1][0] * p[0][1] - p[1][1] * p[0][0]; /* w: edge a-b */
    if ((e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0) && (e[0] > 0.0 || e[1] > 0.0 || e[2] > 0.0))
        return 0;
    /* An edge function that is NaN here came from infinite double coordinates, which a
     * finite file and a finite ray cannot produce; reject it rather than guess. */
    return !isnan(e[0]) && !isnan(e[1]) && !isnan(e[2]) && e[0] + e[1] + e[2] != 0.0;
}

/* t where the ray crosses the plane of (a, b, c): dot(n, a - org) / dot(n, dir)
 * with n = (b - a) x (c - a), all in double. Well conditioned whatever the
 * triangle's shape (the interpolated t of the original test loses accuracy as
 * 1/area on slivers), and without overflow for any float coordinates. Only
 * triangles that passed the edge tests get here. Returns 0 when the ray lies
 * in the plane (t undefined). */
CBVH_KERNEL int cbvh_plane_t(const struct cbvh_ray_shear *restrict s, const float *restrict a,
                               const float *restrict b, const float *restrict c, double *t)
{
    const double e1x = (double)b[0] - a[0], e1y = (double)b[1] - a[1], e1z = (double)b[2] - a[2];
    const double e2x = (double)c[0] - a[0], e2y = (double)c[1] - a[1], e2z = (double)c[2] - a[2];
    const double nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
    const double den = nx * s->dir[0] + ny * s->dir[1] + nz * s->dir[2];
    const double num = nx * ((double)a[0] - s->org[0]) + ny * ((double)a[1] - s->org[1]) + nz * ((double)a[2] - s->org[2]);
    if (den == 0.0)
        return 0;
    /* Every point of the triangle projects onto the ray between its vertices'
     * projections, so a hit's t lies in that span. For a ray that grazes the
     * plane, num / den is ill conditioned and can land far outside it (even
     * behind the origin); clamping keeps t on the triangle the edge tests
     * accepted. */
    const double dd = (double)s->dir[0] * s->dir[0] + (double)s->dir[1] * s->dir[1] + (double)s->dir[2] * s->dir[2];
    double lo = INFINITY, hi = -INFINITY;
    const float *const v[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        const double proj = ((double)v[k][0] - s->org[0]) * s->dir[0] + ((double)v[k][1] - s->org[1]) * s->dir[1] +
                            ((double)v[k][2] - s->org[2]) * s->dir[2];
        lo = proj < lo ? proj : lo;
        hi = proj > hi ? proj : hi;
    }
    double tp = num / den;
    lo /= dd;
    hi /= dd;
    tp = tp < lo ? lo : tp;
    tp = tp > hi ? hi : tp;
    *t = tp;
    return 1;
}

/* The barycentrics of the boundary point nearest to a + w (w = u e1 + v e2
 * with (u, v) outside the triangle): the nearest of the three edges'
 * clamped projections, measured in space (a barycentric shift along a long
 * edge of a sliver would move the point far). */
CBVH_COLD static void cbvh_barycentrics_to_boundary(const double e1[3], const double e2[3], const double w[3],
                                                   double *u, double *v)
{
    /* edge k runs from p0 + s * d, s in [0, 1], with barycentrics (u0 + s du, v0 + s dv) */
    const double d[3][3] = {{e1[0], e1[1], e1[2]}, {e2[0], e2[1], e2[2]},
                            {e2[0] - e1[0], e2[1] - e1[1], e2[2] - e1[2]}};
    const double start[3][3] = {{0, 0, 0}, {0, 0, 0}, {e1[0], e1[1], e1[2]}};
    const double bary[3][4] = {{0, 0, 1, 0}, {0, 0, 0, 1}, {1, 0, -1, 1}}; /* u0, v0, du, dv */
    double best = INFINITY;
    for (int k = 0; k < 3; k++) {
        double dd = 0.0, dw = 0.0;
        for (int x = 0; x < 3; x++) {
            dd += d[k][x] * d[k][x];
            dw += d[k][x] * (w[x] - start[k][x]);
        }
        const double t = dd > 0.0 ? (dw / dd < 0.0 ? 0.0 : dw / dd > 1.0 ? 1.0 : dw / dd) : 0.0;
        double gap = 0.0;
        for (int x = 0; x < 3; x++) {
            const double g = w[x] - start[k][x] - t * d[k][x];
            gap += g * g;
        }
        if (gap < best) {
            best = gap;
            *u = bary[k][0] + t * bary[k][2];
            *v = bary[k][1] + t * bary[k][3];
        }
    }
}

/* Barycentrics (u: weight of b, v: weight of c) of the point at t on the
 * ray, which lies in the triangle's plane: w = p - a = u e1 + v e2 gives
 * u = (w x e2).n / n.n and v = (e1 x w).n / n.n with n = e1 x e2, in double.
 * Their errors scale with the edge lengths, not with the area: the sheared
 * edge functions (products of coordinates relative to the origin) cancel on
 * slivers and put the barycentric point far from the hit (finding F6). Only
 * for accepted hits. edge: the sheared edge functions (u, v, w scaled). */
CBVH_KERNEL void cbvh_plane_barycentrics(const struct cbvh_ray_shear *restrict s, const float *restrict a,
                                         const float *restrict b, const float *restrict c, double t,
                                         const double edge[3], float *u, float *v)
{
    double e1[3], e2[3], w[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)b[k] - a[k];
        e2[k] = (double)c[k] - a[k];
        w[k] = ((double)s->org[k] - a[k]) + t * s->dir[k];
    }
    const double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
                 nz = e1[0] * e2[1] - e1[1] * e2[0];
    const double nn = nx * nx + ny * ny + nz * nz;
    const double un = nx * (w[1] * e2[2] - w[2] * e2[1]) + ny * (w[2] * e2[0] - w[0] * e2[2]) +
                      nz * (w[0] * e2[1] - w[1] * e2[0]);
    const double vn = nx * (e1[1] * w[2] - e1[2] * w[1]) + ny * (e1[2] * w[0] - e1[0] * w[2]) +
                      nz * (e1[0] * w[1] - e1[1] * w[0]);
    double bu = un / nn, bv = vn / nn;
    /* n.n underflowed (denormal coordinates): the edge functions' barycentrics. */
    if (!(isfinite(bu) && isfinite(bv))) {
        const double sum = edge[0] + edge[1] + edge[2];
        bu = edge[1] / sum;
        bv = edge[2] / sum;
    }
    /* Into the closed triangle: the edge tests accept a ray up to float
     * precision outside it, where the exact point has a barycentric below 0;
     * then the nearest boundary point. */
    if (!(bu >= 0.0 && bv >= 0.0 && bu + bv <= 1.0))
        cbvh_barycentrics_to_boundary(e1, e2, w, &bu, &bv);
    *u = (float)bu;
    *v = (float)bv;
}

/* Tests the ray (sheared by s) against triangle (a, b, c). Returns 1 when it
 * hits at t in [tmin, tmax] and writes t and the barycentrics u (weight of b)
 * and v (weight of c). Watertight: a ray through a shared edge or vertex hits
 * at least one of the triangles sharing it, because each edge function's sign
 * is the exact sign for the float sheared coordinates, which both triangles
 * compute identically (see cbvh_ray_triangle_edges_double), and the sign test
 * accepts 0 on either side. A ray in the triangle's plane misses, as does a
 * degenerate triangle. Both windings are hit. The hit/miss decision is the
 * edge tests'; t comes from the plane (cbvh_plane_t), rounded to float, and
 * u, v from the hit point (cbvh_plane_barycentrics). */
CBVH_KERNEL int cbvh_ray_triangle(const struct cbvh_ray_shear *restrict s, const float *restrict a,
                                    const float *restrict b, const float *restrict c, float tmin, float tmax,
                                    float *t_out, float *u_out, float *v_out)
{
    const uint32_t kx = s->kx, ky = s->ky, kz = s->kz;
    const float sx = s->sx, sy = s->sy;
    const float ox = s->org[kx], oy = s->org[ky], oz = s->org[kz];

    /* Vertices relative to the origin, then sheared so the ray is the +z axis. */
    const float az = a[kz] - oz, bz = b[kz] - oz, cz = c[kz] - oz;
    const float ax = (a[kx] - ox) - sx * az, ay = (a[ky] - oy) - sy * az;
    const float bx = (b[kx] - ox) - sx * bz, by = (b[ky] - oy) - sy * bz;
    const float cx = (c[kx] - ox) - sx * cz, cy = (c[ky] - oy) - sy * cz;

    /* Scaled barycentrics: 2D edge functions of the sheared triangle at the origin. */
    const float u = cx * by - cy * bx;
    const float v = ax * cy - ay * cx;
    const float w = bx * ay - by * ax;
    /* Non-zero, non-NaN float edge functions have exact signs (see above):
     * two of opposite sign are a miss whatever the third is. */
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return 0;
    /* All non-zero and finite (so of one sign, with a finite sum): decided.
     * Otherwise (an edge through the origin, an overflow) decide in double. */
    double e[3] = {u, v, w};
    const double det = e[0] + e[1] + e[2];
    if (!CBVH_LIKELY(u != 0.0f && v != 0.0f && w != 0.0f && fabs(det) <= (double)FLT_MAX)) {
        const float *const vert[3] = {a, b, c};
        const float sheared[3][2] = {{ax, ay}, {bx, by}, {cx, cy}};
        if (!cbvh_ray_triangle_edges_double(s, vert, sheared, e))
            return 0;
    }
    double td;
    if (!cbvh_plane_t(s, a, b, c, &td))
        return 0;
    const float t = (float)td;
    /* Ordered compares: an overflowed t (inf) fails t <= tmax <= CBVH_T_LIMIT. */
    if (!(t >= tmin && t <= tmax))
        return 0;
    *t_out = t;
    cbvh_plane_barycentrics(s, a, b, c, td, e, u_out, v_out);
    return 1;
}

#endif
