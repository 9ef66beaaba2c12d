/* ray_triangle.h: the watertight ray/triangle test of Woop, Benthin and Wald (JCGT 2013), t from the plane in
 * double. */
#ifndef CBVH_QUERY_RAY_TRIANGLE_H
#define CBVH_QUERY_RAY_TRIANGLE_H

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "query/ray_setup.h"
#include "query/triangle_frame.h"

/* Edge functions of the sheared triangle when float could not decide them (one is 0, infinite or NaN, or
 * their sum overflows). Returns 0 on a miss, else 1 with the double edge functions in e[3]. Watertight
 * across the two paths: a finite non-zero float edge function has the exact sign of the edge function of
 * the float sheared coordinates, which the double one here computes exactly; a vertex whose float sheared
 * coordinates overflowed is sheared in double, a choice that depends on the vertex and the ray only, so
 * two triangles sharing an edge still agree. */
CBVH_COLD static int cbvh_ray_triangle_edges_double(const struct cbvh_ray_shear *s, const cbvh_v3 vert[3],
                                                    double e[3])
{
    const uint32_t kx = s->kx, ky = s->ky, kz = s->kz;
    double p[3][2];
    for (int k = 0; k < 3; k++) {
        float v[3];
        v3_to_f(vert[k], v); /* exact: the vertices are floats */
        /* the float sheared coordinates, as cbvh_ray_triangle computes them */
        const float zf = v[kz] - s->org[kz];
        const float sheared[2] = {(v[kx] - s->org[kx]) - s->sx * zf, (v[ky] - s->org[ky]) - s->sy * zf};
        if (isfinite(sheared[0]) && isfinite(sheared[1])) {
            p[k][0] = sheared[0];
            p[k][1] = sheared[1];
        } else {
            const double z = (double)v[kz] - s->org[kz];
            p[k][0] = ((double)v[kx] - s->org[kx]) - (double)s->sx * z;
            p[k][1] = ((double)v[ky] - s->org[ky]) - (double)s->sy * z;
        }
    }
    e[0] = p[2][0] * p[1][1] - p[2][1] * p[1][0]; /* u: edge b-c */
    e[1] = p[0][0] * p[2][1] - p[0][1] * p[2][0]; /* v: edge c-a */
    e[2] = p[1][0] * p[0][1] - p[1][1] * p[0][0]; /* w: edge a-b */
    if ((e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0) && (e[0] > 0.0 || e[1] > 0.0 || e[2] > 0.0))
        return 0;
    /* NaN needs infinite double coordinates, which a finite file and ray cannot give: rejected */
    return !isnan(e[0]) && !isnan(e[1]) && !isnan(e[2]) && e[0] + e[1] + e[2] != 0.0;
}

/* The plane's t clamped into the span of the vertices' projections onto the ray (proj[k] = (vertex k -
 * org) . dir), where every hit's t lies: for a grazing ray num / den is ill conditioned. */
static inline double cbvh_plane_t_in_span(double t, const double proj[3], double dir_len2)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 3; k++) {
        lo = proj[k] < lo ? proj[k] : lo;
        hi = proj[k] > hi ? proj[k] : hi;
    }
    lo /= dir_len2;
    hi /= dir_len2;
    t = t < lo ? lo : t;
    return t > hi ? hi : t;
}

/* t where the ray crosses the plane of the triangle v: dot(n, base - org) / dot(n, dir) in the triangle's
 * frame (triangle_frame.h, left in *f), in double: well conditioned on slivers, no overflow. Returns 0 when
 * the ray lies in the plane. */
CBVH_KERNEL int cbvh_plane_t(const struct cbvh_ray_shear *restrict s, const cbvh_v3 v[3],
                             struct cbvh_triangle_frame *restrict f, double *t)
{
    const cbvh_v3 org = v3_from_f(s->org), dir = v3_from_f(s->dir);
    cbvh_triangle_frame_of(v, f);
    const double den = v3_dot(f->n, dir), num = v3_dot(f->n, v3_sub(v[f->base], org));
    if (den == 0.0)
        return 0;
    const double proj[3] = {v3_dot(v3_sub(v[0], org), dir), v3_dot(v3_sub(v[1], org), dir),
                            v3_dot(v3_sub(v[2], org), dir)};
    double tp = cbvh_plane_t_in_span(num / den, proj, v3_len2(dir));
    /* Nor does it leave the line's interval in the triangle's bounding box (slabs in double), so it never
     * falls before the entry of a node box holding the triangle, whatever the visit order. */
    double enter = -INFINITY, leave = INFINITY;
    /* the coordinates in an array, indexed by axis (v3_get's choice of member compiles to branches) */
    const double coord[3][3] = {{v[0].x, v[1].x, v[2].x}, {v[0].y, v[1].y, v[2].y}, {v[0].z, v[1].z, v[2].z}};
    for (int axis = 0; axis < 3; axis++) {
        if (s->dir[axis] == 0.0f)
            continue;
        const double p0 = coord[axis][0], p1 = coord[axis][1], p2 = coord[axis][2];
        const double o = s->org[axis], inv = 1.0 / (double)s->dir[axis];
        const double small = cbvh_dmin(cbvh_dmin(p0, p1), p2), big = cbvh_dmax(cbvh_dmax(p0, p1), p2);
        const double t0 = (small - o) * inv, t1 = (big - o) * inv;
        /* the slab's entry and exit by min and max, without a branch on the sign of inv */
        const double slab_enter = cbvh_dmin(t0, t1), slab_leave = cbvh_dmax(t0, t1);
        enter = slab_enter > enter ? slab_enter : enter;
        leave = slab_leave < leave ? slab_leave : leave;
    }
    if (enter <= leave) {
        tp = tp < enter ? enter : tp;
        tp = tp > leave ? leave : tp;
    }
    *t = tp;
    return 1;
}

/* The barycentrics of the boundary point nearest to base + w ((x, y) outside the triangle): the nearest of
 * the three edges' clamped projections, measured in space. */
CBVH_COLD static void cbvh_barycentrics_to_boundary(const struct cbvh_triangle_frame *f, cbvh_v3 w, double *x,
                                                    double *y)
{
    /* edge k runs from start + s * d, s in [0, 1], with barycentrics (x0 + s dx, y0 + s dy) */
    const cbvh_v3 d[3] = {f->e1, f->e2, v3_sub(f->e2, f->e1)};
    const cbvh_v3 start[3] = {v3(0, 0, 0), v3(0, 0, 0), f->e1};
    const double bary[3][4] = {{0, 0, 1, 0}, {0, 0, 0, 1}, {1, 0, -1, 1}}; /* x0, y0, dx, dy */
    double best = INFINITY;
    for (int k = 0; k < 3; k++) {
        const cbvh_v3 rel = v3_sub(w, start[k]);
        const double dd = v3_len2(d[k]), dw = v3_dot(d[k], rel);
        const double t = dd > 0.0 ? (dw / dd < 0.0 ? 0.0 : dw / dd > 1.0 ? 1.0 : dw / dd) : 0.0;
        const double gap = v3_len2(v3_madd(rel, d[k], -t));
        if (gap < best) {
            best = gap;
            *x = bary[k][0] + t * bary[k][2];
            *y = bary[k][1] + t * bary[k][3];
        }
    }
}

/* Barycentrics (u: weight of b, v: weight of c) of the point at t on the ray from the triangle's frame f
 * (as cbvh_plane_t left it) in double, errors relative to the edge lengths, not the area. Out of line: only
 * accepted hits. edge: the sheared edge functions, for an underflowed frame. */
CBVH_NOINLINE void cbvh_plane_barycentrics(const struct cbvh_ray_shear *restrict s,
                                           const struct cbvh_triangle_frame *restrict f, cbvh_v3 base,
                                           double t, const double edge[3], float *u, float *v)
{
    const cbvh_v3 w = v3_madd(v3_sub(v3_from_f(s->org), base), v3_from_f(s->dir), t);
    double x, y;
    cbvh_triangle_frame_barycentrics(f, w, &x, &y);
    if (isfinite(x) && isfinite(y)) {
        /* into the closed triangle: the edge tests accept up to float precision outside it */
        if (!(x >= 0.0 && y >= 0.0 && x + y <= 1.0))
            cbvh_barycentrics_to_boundary(f, w, &x, &y);
        cbvh_frame_uv(f->base, x, y, u, v);
    } else {
        /* n.n underflowed (denormal coordinates): the edge functions' barycentrics. */
        const double sum = edge[0] + edge[1] + edge[2];
        *u = (float)(edge[1] / sum);
        *v = (float)(edge[2] / sum);
    }
}

#if defined(__AVX2__)
/* The AVX2 walks' cbvh_plane_t and cbvh_plane_barycentrics on vectors (x, y, z, 0): the same double
 * operations in the same order (dot products as (x + y) + z, MINPD / MAXPD for cbvh_dmin / cbvh_dmax), so
 * every result is the scalar code's bit for bit (test_raycast compares them). */
typedef __m256d cbvh_v4d;

static inline cbvh_v4d v4d_of(cbvh_v3 a)
{
    return _mm256_setr_pd(a.x, a.y, a.z, 0.0);
}
static inline cbvh_v3 v3_of_v4d(cbvh_v4d a)
{
    const __m128d xy = _mm256_castpd256_pd128(a);
    return v3(_mm_cvtsd_f64(xy), _mm_cvtsd_f64(_mm_unpackhi_pd(xy, xy)),
              _mm_cvtsd_f64(_mm256_extractf128_pd(a, 1)));
}
/* (x + y) + z */
static inline double v4d_sum3(cbvh_v4d a)
{
    const __m128d xy = _mm256_castpd256_pd128(a);
    return _mm_cvtsd_f64(_mm_add_sd(_mm_add_sd(xy, _mm_unpackhi_pd(xy, xy)), _mm256_extractf128_pd(a, 1)));
}
static inline double v4d_dot(cbvh_v4d a, cbvh_v4d b)
{
    return v4d_sum3(_mm256_mul_pd(a, b));
}
/* v3_cross: (y, z, x) * (z, x, y) - (z, x, y) * (y, z, x), lane 3 0 * 0 - 0 * 0 */
static inline cbvh_v4d v4d_cross(cbvh_v4d a, cbvh_v4d b)
{
    const cbvh_v4d a_yzx = _mm256_permute4x64_pd(a, _MM_SHUFFLE(3, 0, 2, 1));
    const cbvh_v4d a_zxy = _mm256_permute4x64_pd(a, _MM_SHUFFLE(3, 1, 0, 2));
    const cbvh_v4d b_yzx = _mm256_permute4x64_pd(b, _MM_SHUFFLE(3, 0, 2, 1));
    const cbvh_v4d b_zxy = _mm256_permute4x64_pd(b, _MM_SHUFFLE(3, 1, 0, 2));
    return _mm256_sub_pd(_mm256_mul_pd(a_yzx, b_zxy), _mm256_mul_pd(a_zxy, b_yzx));
}

/* struct cbvh_triangle_frame in vectors: cbvh_triangle_frame_of's choices and arithmetic. */
struct cbvh_frame4 {
    cbvh_v4d e1, e2, n;
    double nn;
    int base;
};

CBVH_KERNEL void cbvh_frame4_of(const cbvh_v4d v[3], struct cbvh_frame4 *f)
{
    const cbvh_v4d d0 = _mm256_sub_pd(v[2], v[1]), d1 = _mm256_sub_pd(v[0], v[2]),
                   d2 = _mm256_sub_pd(v[1], v[0]);
    const double len0 = v4d_dot(d0, d0), len1 = v4d_dot(d1, d1), len2 = v4d_dot(d2, d2);
    const int base = len1 > len0 ? (len2 > len1 ? 2 : 1) : (len2 > len0 ? 2 : 0);
    f->base = base;
    f->e1 = _mm256_sub_pd(v[cbvh_frame_vertex(base, 1)], v[base]);
    f->e2 = _mm256_sub_pd(v[cbvh_frame_vertex(base, 2)], v[base]);
    f->n = v4d_cross(f->e1, f->e2);
    f->nn = v4d_dot(f->n, f->n);
}

/* cbvh_plane_t on vectors. */
CBVH_KERNEL int cbvh_plane_t4(const struct cbvh_ray_shear *restrict s, const cbvh_v4d v[3],
                              struct cbvh_frame4 *restrict f, double *t)
{
    const cbvh_v4d org = _mm256_cvtps_pd(cbvh_load3(s->org)), dir = _mm256_cvtps_pd(cbvh_load3(s->dir));
    cbvh_frame4_of(v, f);
    const double den = v4d_dot(f->n, dir), num = v4d_dot(f->n, _mm256_sub_pd(v[f->base], org));
    if (den == 0.0)
        return 0;
    const double proj[3] = {v4d_dot(_mm256_sub_pd(v[0], org), dir), v4d_dot(_mm256_sub_pd(v[1], org), dir),
                            v4d_dot(_mm256_sub_pd(v[2], org), dir)};
    double tp = cbvh_plane_t_in_span(num / den, proj, v4d_dot(dir, dir));
    /* the slabs of all three axes at once (lane 3 ignored); a still axis spans (-inf, +inf), as skipped */
    const cbvh_v4d small = _mm256_min_pd(_mm256_min_pd(v[0], v[1]), v[2]);
    const cbvh_v4d big = _mm256_max_pd(_mm256_max_pd(v[0], v[1]), v[2]);
    const cbvh_v4d inv = _mm256_div_pd(_mm256_set1_pd(1.0), dir);
    const cbvh_v4d t0 = _mm256_mul_pd(_mm256_sub_pd(small, org), inv);
    const cbvh_v4d t1 = _mm256_mul_pd(_mm256_sub_pd(big, org), inv);
    const cbvh_v4d still = _mm256_cmp_pd(dir, _mm256_setzero_pd(), _CMP_EQ_OQ);
    const cbvh_v4d slab_enter = _mm256_blendv_pd(_mm256_min_pd(t0, t1), _mm256_set1_pd(-INFINITY), still);
    const cbvh_v4d slab_leave = _mm256_blendv_pd(_mm256_max_pd(t0, t1), _mm256_set1_pd(INFINITY), still);
    const __m128d enter_xy = _mm256_castpd256_pd128(slab_enter),
                  leave_xy = _mm256_castpd256_pd128(slab_leave);
    /* x, then y, then z, as the scalar loop: MAXSD(a, b) is a > b ? a : b, MINSD(a, b) a < b ? a : b */
    __m128d enter = _mm_max_sd(enter_xy, _mm_set_sd(-INFINITY)),
            leave = _mm_min_sd(leave_xy, _mm_set_sd(INFINITY));
    enter = _mm_max_sd(_mm_unpackhi_pd(enter_xy, enter_xy), enter);
    leave = _mm_min_sd(_mm_unpackhi_pd(leave_xy, leave_xy), leave);
    enter = _mm_max_sd(_mm256_extractf128_pd(slab_enter, 1), enter);
    leave = _mm_min_sd(_mm256_extractf128_pd(slab_leave, 1), leave);
    const double e = _mm_cvtsd_f64(enter), l = _mm_cvtsd_f64(leave);
    if (e <= l) {
        tp = tp < e ? e : tp;
        tp = tp > l ? l : tp;
    }
    *t = tp;
    return 1;
}

/* cbvh_plane_barycentrics on vectors for a point inside the closed triangle; any other, the scalar code. */
CBVH_KERNEL void cbvh_plane_barycentrics4(const struct cbvh_ray_shear *restrict s,
                                          const struct cbvh_frame4 *restrict f, cbvh_v4d base, double t,
                                          const double edge[3], float *u, float *v)
{
    const cbvh_v4d org = _mm256_cvtps_pd(cbvh_load3(s->org)), dir = _mm256_cvtps_pd(cbvh_load3(s->dir));
    const cbvh_v4d w = _mm256_add_pd(_mm256_sub_pd(org, base), _mm256_mul_pd(dir, _mm256_set1_pd(t)));
    const double x = v4d_dot(v4d_cross(w, f->e2), f->n) / f->nn,
                 y = v4d_dot(v4d_cross(f->e1, w), f->n) / f->nn;
    /* ordered compares: false for NaN; x + y <= 1 then also bounds x and y from above, so both are finite */
    if (CBVH_LIKELY(x >= 0.0 && y >= 0.0 && x + y <= 1.0)) {
        cbvh_frame_uv(f->base, x, y, u, v);
        return;
    }
    const struct cbvh_triangle_frame frame = {f->base, v3_of_v4d(f->e1), v3_of_v4d(f->e2), v3_of_v4d(f->n),
                                              f->nn};
    cbvh_plane_barycentrics(s, &frame, v3_of_v4d(base), t, edge, u, v);
}
#endif

/* The rest of cbvh_ray_triangle once its float edge functions u, v, w have not rejected the triangle
 * vert (its float vertices in double): other arguments and result as for cbvh_ray_triangle. */
CBVH_KERNEL int cbvh_ray_triangle_decide(const struct cbvh_ray_shear *restrict s, const cbvh_v3 vert[3],
                                         float u, float v, float w, float tmin, float tmax, const int want_uv,
                                         float *t_out, float *u_out, float *v_out)
{
    /* all non-zero with a finite sum: decided; otherwise (0, an overflow) decided in double */
    double e[3] = {u, v, w};
    if (!CBVH_LIKELY(fabsf(u + v + w) <= FLT_MAX && u != 0.0f && v != 0.0f && w != 0.0f) &&
        !cbvh_ray_triangle_edges_double(s, vert, e))
        return 0;
    double td;
#if defined(__AVX2__)
    const cbvh_v4d v4[3] = {v4d_of(vert[0]), v4d_of(vert[1]), v4d_of(vert[2])};
    struct cbvh_frame4 frame;
    if (!cbvh_plane_t4(s, v4, &frame, &td))
        return 0;
#else
    struct cbvh_triangle_frame frame;
    if (!cbvh_plane_t(s, vert, &frame, &td))
        return 0;
#endif
    const float t = (float)td;
    /* Ordered compares: an overflowed t (inf) fails t <= tmax <= CBVH_T_LIMIT. */
    if (!(t >= tmin && t <= tmax))
        return 0;
    *t_out = t;
#if defined(__AVX2__)
    if (want_uv)
        cbvh_plane_barycentrics4(s, &frame, v4[frame.base], td, e, u_out, v_out);
#else
    if (want_uv)
        cbvh_plane_barycentrics(s, &frame, vert[frame.base], td, e, u_out, v_out);
#endif
    return 1;
}

/* Tests the ray (sheared by s) against triangle (a, b, c). Returns 1 when it hits at t in [tmin, tmax] and
 * writes t and, when want_uv, the barycentrics u (weight of b) and v (weight of c). Watertight: a ray
 * through a shared edge or vertex hits at least one of the triangles sharing it (each edge function's sign
 * is exact for the float sheared coordinates, and 0 is accepted on either side). A ray in the plane and a
 * degenerate triangle miss; both windings hit. t comes from the plane (cbvh_plane_t), rounded to float. */
CBVH_KERNEL int cbvh_ray_triangle(const struct cbvh_ray_shear *restrict s, const float *restrict a,
                                  const float *restrict b, const float *restrict c, float tmin, float tmax,
                                  const int want_uv, float *t_out, float *u_out, float *v_out)
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
    /* Finite float edge functions have exact signs: two of opposite sign are a miss. A non-finite one (an
     * overflowed sheared coordinate, whose sign means nothing) or sum leaves it to the double path. */
    const int finite = fabsf(u + v + w) <= FLT_MAX;
    if (finite && (u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f))
        return 0;
    const cbvh_v3 vert[3] = {v3_from_f(a), v3_from_f(b), v3_from_f(c)};
    return cbvh_ray_triangle_decide(s, vert, u, v, w, tmin, tmax, want_uv, t_out, u_out, v_out);
}

#endif
