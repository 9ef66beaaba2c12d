/* shape_cull.h: cheap tests that a shape, still or swept, cannot touch a triangle or surely does, before the
 * exact ones. */
#ifndef CBVH_QUERY_SHAPE_CULL_H
#define CBVH_QUERY_SHAPE_CULL_H

#ifdef CBVH_HAVE_SIMD
#include <emmintrin.h>
#endif

#include "query/shape.h"

/* Plain compares (one instruction each), not fminf/fmaxf, which GCC leaves as calls into libm; the values
 * are never NaN. */
static inline float cull_maxf(float x, float y)
{
    return x > y ? x : y;
}
static inline float cull_minf(float x, float y)
{
    return x < y ? x : y;
}
static inline double cull_max_abs(cbvh_v3 v)
{
    return cbvh_dmax(cbvh_dmax(fabs(v.x), fabs(v.y)), fabs(v.z));
}

/* The box [lo, hi] of a triangle's float vertices, exact: a walk's node test on it culls the triangle as it
 * would cull a leaf holding that triangle alone. */
static inline void cbvh_triangle_bounds(const float a[3], const float b[3], const float c[3], float lo[3],
                                        float hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = cull_minf(cull_minf(a[k], b[k]), c[k]);
        hi[k] = cull_maxf(cull_maxf(a[k], b[k]), c[k]);
    }
}

/* How far the shape reaches along n from its core, times |n|. */
static inline double cull_reach_along(const struct cbvh_local_shape *s, cbvh_v3 n)
{
    if (s->kind != CBVH_SHAPE_BOX)
        return s->radius * v3_len(n);
    if (!s->rotated)
        return fabs(n.x) * s->half.x + fabs(n.y) * s->half.y + fabs(n.z) * s->half.z;
    const double(*m)[3] = s->axes; /* columns are the box's axes */
    return fabs(n.x * m[0][0] + n.y * m[1][0] + n.z * m[2][0]) * s->half.x +
           fabs(n.x * m[0][1] + n.y * m[1][1] + n.z * m[2][1]) * s->half.y +
           fabs(n.x * m[0][2] + n.y * m[1][2] + n.z * m[2][2]) * s->half.z;
}

/* What the cheap tests tell of a shape moved by t * delta for t in [0, tmax] and a triangle. */
enum cbvh_cull_verdict {
    CBVH_CULL_MAY_TOUCH,      /* they cannot tell: the exact tests decide */
    CBVH_CULL_CLEAR_AT_START, /* the shape at t = 0 cannot touch the triangle; later it may */
    CBVH_CULL_CLEAR,          /* no contact for any t in [0, tmax] */
    CBVH_CULL_TOUCHES         /* the shape at t = 0 surely touches the triangle (asked for only) */
};

/* The cheap tests of shape s against triangle (a, b, c), in double, with margins that put their verdicts
 * beyond the rounding of the exact tests (span: the longest edge from a on an axis; size: the sum of the
 * largest coordinates of a vertex, the shape and the motion, of span and of the shape's own size):
 * - CBVH_CULL_CLEAR (or _AT_START): the shape, at t = 0 and moved by t * delta for every t in [0, tmax]
 *   (at t = 0 only), lies on one side of the triangle's plane. The swept shape is the hull of its core
 *   points (center, or capsule ends, at t = 0 and t = tmax) grown by its reach along the normal (radius,
 *   or half extents on the box's axes). The margin, 2^-30 span^2 size, is 2^23 times this test's own
 *   error bound in double (normal included, slivers too), and leaves a gap of about 2^-32 size: far above
 *   the rounding of the exact tests, a few ulps of size, for any shape larger than a millionth of its
 *   distance to the vertices.
 * For a still ball or capsule (`still`, an overlap's: its exact tests tell no more than yes or no), on a
 * triangle no sliver (|n|^2 >= 2^-20 span^4), with its end points' edge functions (barycentrics times |n|^2)
 * exact to far better than m = 2^-28 span^3 size:
 * - CBVH_CULL_CLEAR too when both ends lie outside one edge by more than the radius, the margin m.
 * - CBVH_CULL_TOUCHES when an end lies within the radius less 2^-20 size of the plane where it projects
 *   into the triangle (each barycentric at least m / |n|^2), or of an edge. The exact tests' closest
 *   points are then within 2^-28 size of true ones no farther than that projection or edge point, so they
 *   find a distance below the radius.
 * CBVH_CULL_MAY_TOUCH otherwise, always for a triangle of no area. Safe on any finite input. */
static inline enum cbvh_cull_verdict cbvh_cull_triangle(const struct cbvh_local_shape *s, cbvh_v3 delta,
                                                        double tmax, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                                                        const int still)
{
    const cbvh_v3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), n = v3_cross(e1, e2), motion = v3_scale(delta, tmax);
    const double s0 = v3_dot(n, v3_sub(s->p0, a)), s1 = v3_dot(n, v3_sub(s->p1, a)), m = v3_dot(n, motion);
    const double lo = cbvh_dmin(s0, s1), hi = cbvh_dmax(s0, s1);
    const double span = cbvh_dmax(cull_max_abs(e1), cull_max_abs(e2));
    const double size = cull_max_abs(a) + span + cbvh_dmax(cull_max_abs(s->p0), cull_max_abs(s->p1)) +
                        cull_max_abs(motion) + s->radius + s->half.x + s->half.y + s->half.z;
    const double gap = cull_reach_along(s, n) + 0x1p-30 * span * span * size;
    if (lo + cbvh_dmin(m, 0.0) > gap || hi + cbvh_dmax(m, 0.0) < -gap)
        return CBVH_CULL_CLEAR;
    if (lo > gap || hi < -gap)
        return CBVH_CULL_CLEAR_AT_START;
    if (!still || s->kind == CBVH_SHAPE_BOX)
        return CBVH_CULL_MAY_TOUCH;
    const double nn = v3_len2(n), span2 = span * span, margin = 0x1p-28 * span2 * span * size;
    if (!(nn > 0.0 && nn >= 0x1p-20 * span2 * span2)) /* a triangle of no area passes the second on span 0 */
        return CBVH_CULL_MAY_TOUCH;
    const double r = s->radius, reach = r - 0x1p-20 * size, reach2 = reach > 0.0 ? reach * reach : -1.0;
    const cbvh_v3 edge[3] = {v3_sub(b, a), v3_sub(c, b), v3_sub(a, c)};
    const double edge2[3] = {v3_len2(edge[0]), v3_len2(edge[1]), v3_len2(edge[2])};
    int outside = 7; /* bit k: every end so far lies outside edge k */
    for (int end = 0; end < (s->kind == CBVH_SHAPE_CAPSULE ? 2 : 1); end++) {
        const cbvh_v3 p = end ? s->p1 : s->p0;
        const double h = end ? s1 : s0;
        const cbvh_v3 w[3] = {v3_sub(p, a), v3_sub(p, b), v3_sub(p, c)};
        const double w2[3] = {v3_len2(w[0]), v3_len2(w[1]), v3_len2(w[2])};
        int inside = h * h <= reach2 * nn, near = 0;
        for (int k = 0; k < 3; k++) {
            /* edge k's function (the opposite barycentric times |n|^2, or minus the distance outside the
             * edge times |n| |edge|), and the squared distance of p to the edge's line times |edge|^2 */
            const cbvh_v3 x = v3_cross(edge[k], w[k]);
            const double e = v3_dot(x, n), t = v3_dot(w[k], edge[k]), out = -e - margin;
            inside &= e >= margin;
            near |= t <= 0.0        ? w2[k] <= reach2
                    : t >= edge2[k] ? w2[k == 2 ? 0 : k + 1] <= reach2
                                    : v3_len2(x) <= reach2 * edge2[k];
            outside &= ~((!(out > 0.0 && out * out > r * r * nn * edge2[k])) << k);
        }
        if (inside | near)
            return CBVH_CULL_TOUCHES;
    }
    return outside ? CBVH_CULL_CLEAR : CBVH_CULL_MAY_TOUCH;
}

#ifdef CBVH_HAVE_SIMD
/* A still shape and the float box around it, in every lane, for cbvh_cull4_keep. */
struct cbvh_cull4 {
    __m128 lo[3], hi[3]; /* the box around a still shape (cbvh_cull4_keep) */
    __m128 p0[3], p1[3];
    __m128 radius, half[3], axes[3][3]; /* axes[i]: the box's axis i (the identity unless rotated) */
    __m128 shape_size;                  /* the shape's part of cbvh_cull_triangle's size */
    __m128 delta[3], delta_size;        /* a swept shape's motion, its largest coordinate (sweeps) */
    int box, capsule;
};

/* Shape s, still within the box [lo, hi], or moved by delta (lo, hi NULL; delta NULL for a still one). */
static inline void cbvh_cull4_init(struct cbvh_cull4 *w, const struct cbvh_local_shape *s, const float lo[3],
                                   const float hi[3], const float delta[3])
{
    const double p[2][3] = {{s->p0.x, s->p0.y, s->p0.z}, {s->p1.x, s->p1.y, s->p1.z}};
    const double half[3] = {s->half.x, s->half.y, s->half.z};
    if (delta) {
        w->delta_size = _mm_set1_ps(cull_maxf(cull_maxf(fabsf(delta[0]), fabsf(delta[1])), fabsf(delta[2])));
        for (int a = 0; a < 3; a++)
            w->delta[a] = _mm_set1_ps(delta[a]);
    }
    for (int a = 0; a < 3; a++) {
        if (lo) {
            w->lo[a] = _mm_set1_ps(lo[a]);
            w->hi[a] = _mm_set1_ps(hi[a]);
        }
        w->p0[a] = _mm_set1_ps((float)p[0][a]);
        w->p1[a] = _mm_set1_ps((float)p[1][a]);
        if (s->kind != CBVH_SHAPE_BOX) /* read for boxes only */
            continue;
        w->half[a] = _mm_set1_ps((float)half[a]);
        for (int i = 0; i < 3; i++)
            w->axes[i][a] = _mm_set1_ps(s->rotated ? (float)s->axes[a][i] : (float)(a == i));
    }
    w->radius = _mm_set1_ps((float)s->radius);
    w->shape_size = _mm_set1_ps((float)(cbvh_dmax(cull_max_abs(s->p0), cull_max_abs(s->p1)) + s->radius +
                                        s->half.x + s->half.y + s->half.z));
    w->box = s->kind == CBVH_SHAPE_BOX;
    w->capsule = s->kind == CBVH_SHAPE_CAPSULE;
}

static inline __m128 cull4_abs(__m128 x)
{
    return _mm_andnot_ps(_mm_set1_ps(-0.0f), x);
}
static inline __m128 cull4_dot(const __m128 a[3], const __m128 b[3])
{
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1])), _mm_mul_ps(a[2], b[2]));
}

/* w ? a : b, lane by lane (SSE2 has no blend). */
static inline __m128 cull4_select(__m128 w, __m128 a, __m128 b)
{
    return _mm_or_ps(_mm_and_ps(w, a), _mm_andnot_ps(w, b));
}

/* Four triangles' corners c[v][axis] from leaf_gather4's floats (16-byte aligned). */
static inline void cull4_load(const float quad[3][3][4], __m128 c[3][3])
{
    for (int v = 0; v < 3; v++)
        for (int a = 0; a < 3; a++)
            c[v][a] = _mm_load_ps(quad[v][a]);
}

/* What both float culls read of four triangles: the edges d[k] = c[k + 1] - c[k], the face normal
 * n = (c1 - c0) x (c2 - c0) and |n|^2, span (cbvh_cull_triangle's: the largest coordinate of c1 - c0 and
 * c2 - c0), corner (the largest coordinate of c0), and the heights h0, h1 of w's core points p0, p1 over the
 * plane times |n| (h1 = h0 but for a capsule). */
struct cull4_frame {
    __m128 d[3][3], n[3], nn, span, corner, h0, h1;
};

static inline void cull4_frame_of(const struct cbvh_cull4 *w, const __m128 c[3][3], struct cull4_frame *f)
{
    __m128 w0[3], w1[3];
    f->span = f->corner = _mm_setzero_ps();
    for (int a = 0; a < 3; a++) {
        w0[a] = _mm_sub_ps(w->p0[a], c[0][a]);
        w1[a] = _mm_sub_ps(w->p1[a], c[0][a]);
        f->d[0][a] = _mm_sub_ps(c[1][a], c[0][a]);
        f->d[1][a] = _mm_sub_ps(c[2][a], c[1][a]);
        f->d[2][a] = _mm_sub_ps(c[0][a], c[2][a]);
        f->span = _mm_max_ps(f->span, _mm_max_ps(cull4_abs(f->d[0][a]), cull4_abs(f->d[2][a])));
        f->corner = _mm_max_ps(f->corner, cull4_abs(c[0][a]));
    }
    const __m128 *e1 = f->d[0], e2[3] = {_mm_sub_ps(c[2][0], c[0][0]), _mm_sub_ps(c[2][1], c[0][1]),
                                         _mm_sub_ps(c[2][2], c[0][2])};
    f->n[0] = _mm_sub_ps(_mm_mul_ps(e1[1], e2[2]), _mm_mul_ps(e1[2], e2[1]));
    f->n[1] = _mm_sub_ps(_mm_mul_ps(e1[2], e2[0]), _mm_mul_ps(e1[0], e2[2]));
    f->n[2] = _mm_sub_ps(_mm_mul_ps(e1[0], e2[1]), _mm_mul_ps(e1[1], e2[0]));
    f->nn = cull4_dot(f->n, f->n);
    f->h0 = cull4_dot(f->n, w0);
    f->h1 = w->capsule ? cull4_dot(f->n, w1) : f->h0; /* a ball's p1 is p0 */
}

/* How far w's shape reaches along n from its core, times |n| (cull_reach_along in float). */
static inline __m128 cull4_reach(const struct cbvh_cull4 *w, const __m128 n[3], __m128 nn)
{
    if (!w->box)
        return _mm_mul_ps(w->radius, _mm_sqrt_ps(nn));
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(w->half[0], cull4_abs(cull4_dot(n, w->axes[0]))),
                                 _mm_mul_ps(w->half[1], cull4_abs(cull4_dot(n, w->axes[1])))),
                      _mm_mul_ps(w->half[2], cull4_abs(cull4_dot(n, w->axes[2]))));
}

/* The lanes of a triangle of moderate size (cbvh_cull4_keep's bounds: 2^-20 <= span, size <= 2^20) with
 * |n|^2 >= sliver span^4: far from a sliver with sliver = 1/16, where the float tests of edges and distances
 * hold their margins; not quite a sliver with sliver = 2^-20, where the tests that read no normal do. */
static inline __m128 cull4_moderate(const struct cull4_frame *f, __m128 size, float sliver)
{
    const __m128 span2 = _mm_mul_ps(f->span, f->span);
    const __m128 sized =
        _mm_and_ps(_mm_cmpge_ps(f->span, _mm_set1_ps(0x1p-20f)), _mm_cmple_ps(size, _mm_set1_ps(0x1p20f)));
    return _mm_and_ps(sized, _mm_cmpge_ps(f->nn, _mm_mul_ps(_mm_set1_ps(sliver), _mm_mul_ps(span2, span2))));
}

/* The lanes where the shape, its core's points at heights h0 and h1 (times |n|) over the plane, moved by
 * up to motion m (its height change, times |n|), stays on one side of the plane by more than its reach
 * plus the margin 2^-14 span^2 size, on triangles with span at least 2^-30 (cbvh_cull4_keep). */
static inline __m128 cull4_apart(__m128 h0, __m128 h1, __m128 m, __m128 reach, __m128 span, __m128 size)
{
    const __m128 zero = _mm_setzero_ps();
    const __m128 margin = _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0x1p-14f), _mm_mul_ps(span, span)), size);
    const __m128 gap = _mm_add_ps(reach, margin), low = _mm_add_ps(_mm_min_ps(h0, h1), _mm_min_ps(m, zero));
    const __m128 high = _mm_add_ps(_mm_max_ps(h0, h1), _mm_max_ps(m, zero));
    const __m128 above = _mm_cmpgt_ps(low, gap), below = _mm_cmplt_ps(high, _mm_sub_ps(zero, gap));
    return _mm_and_ps(_mm_cmpge_ps(span, _mm_set1_ps(0x1p-30f)), _mm_or_ps(above, below));
}

/* The lanes where end point p (height h over the plane, times |n|) lies within sqrt(reach2) of an edge;
 * *inside_plane gets those where it lies within sqrt(reach2) of the plane where it projects into the triangle
 * with every edge function (d[k] x (p - c[k])) . n at least margin (cbvh_cull_triangle's still tests, in
 * float: those of an edge read no normal). outside[k], unless NULL, keeps the lanes where p also lies outside
 * edge k by more than the radius r, the margin; *far the lanes where p lies outside an edge by the margin and
 * farther than sqrt(far2) from all three: its projection then lies out of the triangle, whose nearest point
 * to p is on an edge, farther than sqrt(far2). */
CBVH_FORCE_INLINE __m128 cull4_end_touches(const __m128 c[3][3], const __m128 d[3][3], const __m128 dd[3],
                                           const __m128 n[3], const __m128 nn, const __m128 p[3], __m128 h,
                                           __m128 r, __m128 reach2, __m128 far2, __m128 margin,
                                           __m128 outside[3], __m128 *inside_plane, __m128 *far)
{
    __m128 w[3][3], w2[3];
    for (int k = 0; k < 3; k++) {
        for (int a = 0; a < 3; a++)
            w[k][a] = _mm_sub_ps(p[a], c[k][a]);
        w2[k] = cull4_dot(w[k], w[k]);
    }
    /* a vertex is a point of every edge through it: the edges' tests need their lines only where p projects
     * inside the segment (0 < t < |d|^2), and all three vertices far where every edge is */
    __m128 inside = _mm_cmple_ps(_mm_mul_ps(h, h), _mm_mul_ps(reach2, nn)), off = _mm_setzero_ps();
    __m128 near = _mm_or_ps(_mm_or_ps(_mm_cmple_ps(w2[0], reach2), _mm_cmple_ps(w2[1], reach2)),
                            _mm_cmple_ps(w2[2], reach2));
    __m128 clear = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(w2[0], far2), _mm_cmpgt_ps(w2[1], far2)),
                              _mm_cmpgt_ps(w2[2], far2));
    const __m128 minus_margin = _mm_sub_ps(_mm_setzero_ps(), margin);
    for (int k = 0; k < 3; k++) {
        const __m128 *dk = d[k], *wk = w[k];
        const __m128 x[3] = {_mm_sub_ps(_mm_mul_ps(dk[1], wk[2]), _mm_mul_ps(dk[2], wk[1])),
                             _mm_sub_ps(_mm_mul_ps(dk[2], wk[0]), _mm_mul_ps(dk[0], wk[2])),
                             _mm_sub_ps(_mm_mul_ps(dk[0], wk[1]), _mm_mul_ps(dk[1], wk[0]))};
        const __m128 t = cull4_dot(wk, dk), xx = cull4_dot(x, x);
        const __m128 mid = _mm_and_ps(_mm_cmpgt_ps(t, _mm_setzero_ps()), _mm_cmplt_ps(t, dd[k]));
        const __m128 line = _mm_cmple_ps(xx, _mm_mul_ps(reach2, dd[k]));
        const __m128 far_line = _mm_cmpgt_ps(xx, _mm_mul_ps(far2, dd[k]));
        const __m128 e = cull4_dot(x, n), out_of = _mm_cmplt_ps(e, minus_margin); /* -e - margin > 0 */
        inside = _mm_and_ps(inside, _mm_cmpge_ps(e, margin));
        near = _mm_or_ps(near, _mm_and_ps(mid, line));
        clear = _mm_andnot_ps(_mm_andnot_ps(far_line, mid), clear);
        off = _mm_or_ps(off, out_of);
        if (outside) {
            const __m128 out = _mm_sub_ps(_mm_sub_ps(_mm_setzero_ps(), e), margin);
            const __m128 out_r2 = _mm_mul_ps(_mm_mul_ps(r, r), _mm_mul_ps(nn, dd[k]));
            const __m128 beyond = _mm_cmpgt_ps(_mm_mul_ps(out, out), out_r2);
            outside[k] = _mm_and_ps(outside[k], _mm_and_ps(out_of, beyond));
        }
    }
    *far = _mm_and_ps(off, clear);
    *inside_plane = inside;
    return near;
}

/* Four triangles (quad[v][axis], 16-byte aligned, a lane each: leaf_gather4) against the still shape of w, in
 * float. Returns the lanes to test further: those whose box meets w's box (the walk's node test, exact) and
 * whose plane does not keep the shape on one side (cbvh_cull_triangle's plane test with the margin 2^-14
 * span^2 size, 10 times this test's error bound in float, when span is at least 2^-30, far from underflow; a
 * coordinate near overflow makes the margin infinite or a distance NaN, and keeps the lane). A lane dropped
 * here is one cbvh_cull_triangle, and the exact tests, would drop. *touch gets the kept lanes where a ball or
 * capsule surely touches the triangle, by cbvh_cull_triangle's still tests in float, on a triangle of
 * moderate size (2^-20 <= span, size <= 2^20, so nothing overflows or leaves the normal range): an end within
 * the radius less 2^-13 size of the plane where it projects into the triangle, each edge function at least
 * 2^-12 span^3 size, on a triangle far from a sliver (|n|^2 >= span^4 / 16), or of an edge, on one no sliver
 * by cbvh_cull_triangle's bound (|n|^2 >= 2^-20 span^4). There too a lane is dropped, for a capsule, when
 * both ends lie outside one edge by more than the radius, that margin, far from a sliver, and, for a ball, no
 * sliver, when its center lies outside an edge by the edge functions' margin and farther than the radius plus
 * 2^-13 size from every edge (cull4_end_touches' *far: it drops what the capsule's test would for a ball, but
 * for a band 2^-13 size wide, at less cost). These margins are 4 to 8 times the float error of distances and
 * edge functions there (the distance of a point to an edge's line from a cross product whose rounding is a
 * few ulps of size, not of the distance; an edge function's below 2^-14 span^3 size, whatever |n|), so the
 * exact tests find the distance below the radius, or above it: on a triangle no sliver, the error of their
 * barycentrics in double (below 2^-41 span^3 size / |n|^2: the normal's rounding is 2^-52 of its edges'
 * product, not of |n|) moves the point they take for the projection by less than 2^-18 size, and the signs
 * they read off the edge functions are those of the float tests. Only the plane's distance and the distance
 * outside an edge divide by |n|, hence the stricter bound there. */
CBVH_FORCE_INLINE uint32_t cbvh_cull4_keep(const struct cbvh_cull4 *w, const float quad[3][3][4],
                                           uint32_t *touch)
{
    __m128 c[3][3];
    cull4_load(quad, c);
    __m128 in = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (int a = 0; a < 3; a++) {
        const __m128 lo = _mm_min_ps(_mm_min_ps(c[0][a], c[1][a]), c[2][a]);
        const __m128 hi = _mm_max_ps(_mm_max_ps(c[0][a], c[1][a]), c[2][a]);
        in = _mm_and_ps(in, _mm_and_ps(_mm_cmple_ps(lo, w->hi[a]), _mm_cmpge_ps(hi, w->lo[a])));
    }
    *touch = 0;
    if (!_mm_movemask_ps(in)) /* no lane's box meets the shape's: nothing to decide */
        return 0;
    struct cull4_frame f;
    cull4_frame_of(w, c, &f);
    const __m128(*d)[3] = f.d, *n = f.n, nn = f.nn, span = f.span, s0 = f.h0, s1 = f.h1;
    const __m128 span2 = _mm_mul_ps(span, span);
    const __m128 size = _mm_add_ps(_mm_add_ps(f.corner, span), w->shape_size);
    const __m128 apart = cull4_apart(s0, s1, _mm_setzero_ps(), cull4_reach(w, n, nn), span, size);
    __m128 keep = _mm_andnot_ps(apart, in);
    if (w->box || !_mm_movemask_ps(keep))
        return (uint32_t)_mm_movemask_ps(keep);
    const __m128 moderate = cull4_moderate(&f, size, 0x1p-4f), fair = cull4_moderate(&f, size, 0x1p-20f);
    const __m128 reach_in = _mm_sub_ps(w->radius, _mm_mul_ps(_mm_set1_ps(0x1p-13f), size));
    const __m128 reaches = _mm_cmpgt_ps(reach_in, _mm_setzero_ps()); /* else no point is near enough */
    const __m128 reach2 = cull4_select(reaches, _mm_mul_ps(reach_in, reach_in), _mm_set1_ps(-1.0f));
    const __m128 reach_out = _mm_add_ps(w->radius, _mm_mul_ps(_mm_set1_ps(0x1p-13f), size));
    const __m128 far2 = _mm_mul_ps(reach_out, reach_out);
    const __m128 margin = _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0x1p-12f), _mm_mul_ps(span2, span)), size);
    const __m128 dd[3] = {cull4_dot(d[0], d[0]), cull4_dot(d[1], d[1]), cull4_dot(d[2], d[2])};
    __m128 outside[3] = {moderate, moderate, moderate};
    const __m128 r = w->radius;
    __m128 far, far1, inside, inside1, near, clear; /* clear: the lanes dropped */
    if (w->capsule) {
        near = cull4_end_touches(c, d, dd, n, nn, w->p0, s0, r, reach2, far2, margin, outside, &inside, &far);
        near = _mm_or_ps(near, cull4_end_touches(c, d, dd, n, nn, w->p1, s1, r, reach2, far2, margin, outside,
                                                 &inside1, &far1));
        inside = _mm_or_ps(inside, inside1);
        clear = _mm_or_ps(_mm_or_ps(outside[0], outside[1]), outside[2]);
    } else {
        near = cull4_end_touches(c, d, dd, n, nn, w->p0, s0, r, reach2, far2, margin, NULL, &inside, &far);
        clear = _mm_and_ps(far, fair);
    }
    keep = _mm_andnot_ps(clear, keep);
    const __m128 sure = _mm_or_ps(_mm_and_ps(inside, moderate), _mm_and_ps(near, fair));
    *touch = (uint32_t)_mm_movemask_ps(_mm_and_ps(sure, keep));
    return (uint32_t)_mm_movemask_ps(keep);
}

/* Four triangles (as for cbvh_cull4_keep) against w's shape moved by t * delta for t in [0, tmax] (w from
 * cbvh_cull4_init with delta), in float. Returns the lanes to test further: those whose plane does not keep
 * the swept shape on one side (cbvh_cull_triangle's plane test, CBVH_CULL_CLEAR, with its motion: the hull
 * of the core's points at t = 0 and t = tmax grown by the reach) with the margin 2^-14 span^2 size, size
 * now counting the motion's largest coordinate too; and, for a ball or capsule on a triangle of moderate
 * size far from a sliver (cull4_moderate), those where the core's points at t = 0 and at t = tmax all lie
 * outside one edge by more than the radius plus the margin 2^-12 span^3 size in the edge function (the
 * function is linear, so the whole swept core does: the swept shape stays beyond the plane through that
 * edge square to the triangle). The float error of a height or of an edge function, from the rounding of
 * the normal, of the edge, of the points' differences and of the dot product, is below 2^-17 span^2 size
 * or 2^-15 span^3 size: the margins are 8 and 8 times that, and 2^-14 span^2 size is 2^16 times
 * cbvh_cull_triangle's own margin. So a lane dropped here is one cbvh_cull_triangle finds clear for every
 * tmax' <= tmax (a shorter motion only moves the hull's far end inwards), and on which the exact tests find
 * no contact. *clear_at_start gets the lanes kept where the shape at t = 0 alone stays on one side of the
 * plane by that margin (the same test with no motion, its size still counting the motion): there
 * cbvh_cull_triangle finds CBVH_CULL_CLEAR_AT_START, or CBVH_CULL_CLEAR where the exact tests find no
 * contact either, for every tmax' <= tmax. */
CBVH_FORCE_INLINE uint32_t cbvh_cull4_sweep(const struct cbvh_cull4 *w, const float quad[3][3][4], float tmax,
                                            uint32_t *clear_at_start)
{
    __m128 c[3][3], motion[3];
    cull4_load(quad, c);
    struct cull4_frame f;
    cull4_frame_of(w, c, &f);
    const __m128 t = _mm_set1_ps(tmax);
    for (int a = 0; a < 3; a++)
        motion[a] = _mm_mul_ps(w->delta[a], t);
    const __m128 *n = f.n, nn = f.nn, span = f.span, zero = _mm_setzero_ps();
    const __m128 size =
        _mm_add_ps(_mm_add_ps(_mm_add_ps(f.corner, span), w->shape_size), _mm_mul_ps(w->delta_size, t));
    const __m128 h0 = f.h0, h1 = f.h1, m = cull4_dot(n, motion);
    const __m128 reach = cull4_reach(w, n, nn);
    __m128 keep =
        _mm_andnot_ps(cull4_apart(h0, h1, m, reach, span, size), _mm_castsi128_ps(_mm_set1_epi32(-1)));
    const uint32_t start_apart = (uint32_t)_mm_movemask_ps(cull4_apart(h0, h1, zero, reach, span, size));
    *clear_at_start = start_apart & (uint32_t)_mm_movemask_ps(keep);
    if (w->box || !_mm_movemask_ps(keep))
        return (uint32_t)_mm_movemask_ps(keep);
    const __m128 margin =
        _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0x1p-12f), _mm_mul_ps(_mm_mul_ps(span, span), span)), size);
    const __m128 r2nn = _mm_mul_ps(_mm_mul_ps(w->radius, w->radius), nn);
    __m128 outside = zero;
    for (int k = 0; k < 3; k++) {
        /* edge k's function at p, (d[k] x (p - c[k])) . n, is g . (p - c[k]) with g = n x d[k] */
        const __m128 *dk = f.d[k];
        const __m128 g[3] = {_mm_sub_ps(_mm_mul_ps(n[1], dk[2]), _mm_mul_ps(n[2], dk[1])),
                             _mm_sub_ps(_mm_mul_ps(n[2], dk[0]), _mm_mul_ps(n[0], dk[2])),
                             _mm_sub_ps(_mm_mul_ps(n[0], dk[1]), _mm_mul_ps(n[1], dk[0]))};
        __m128 v0[3], v1[3];
        for (int a = 0; a < 3; a++) {
            v0[a] = _mm_sub_ps(w->p0[a], c[k][a]);
            v1[a] = _mm_sub_ps(w->p1[a], c[k][a]);
        }
        const __m128 moved = _mm_max_ps(cull4_dot(g, motion), zero);
        const __m128 e = _mm_add_ps(_mm_max_ps(cull4_dot(g, v0), cull4_dot(g, v1)), moved);
        const __m128 out = _mm_sub_ps(_mm_sub_ps(zero, e), margin);
        const __m128 beyond = _mm_cmpgt_ps(_mm_mul_ps(out, out), _mm_mul_ps(r2nn, cull4_dot(dk, dk)));
        outside = _mm_or_ps(outside, _mm_and_ps(_mm_cmpgt_ps(out, zero), beyond));
    }
    keep = _mm_andnot_ps(_mm_and_ps(outside, cull4_moderate(&f, size, 0x1p-4f)), keep);
    *clear_at_start &= (uint32_t)_mm_movemask_ps(keep);
    return (uint32_t)_mm_movemask_ps(keep);
}
#endif

#endif
