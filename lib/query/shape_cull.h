/* shape_cull.h: cheap tests that a shape, still or swept, cannot touch a triangle or surely does, before the
 * exact ones. */
#ifndef CBVH_QUERY_SHAPE_CULL_H
#define CBVH_QUERY_SHAPE_CULL_H

#include "query/lanes.h"
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
/* A shape, still with the float box around it or swept, in every lane (CBVH_LANES: 4, or 8 in the files
 * compiled for AVX2), for the float culls below. */
struct cbvh_cull4 {
    cbvh_lanes lo[3], hi[3]; /* the box around a still shape (cbvh_cull_keep_lanes) */
    cbvh_lanes p0[3], p1[3];
    cbvh_lanes radius, half[3], axes[3][3]; /* axes[i]: the box's axis i (the identity unless rotated) */
    cbvh_lanes shape_size;                  /* the shape's part of cbvh_cull_triangle's size */
    cbvh_lanes delta[3], delta_size;        /* a swept shape's motion, its largest coordinate (sweeps) */
    int box, capsule;
};

/* Shape s, still within the box [lo, hi], or moved by delta (lo, hi NULL; delta NULL for a still one). */
static inline void cbvh_cull4_init(struct cbvh_cull4 *w, const struct cbvh_local_shape *s, const float lo[3],
                                   const float hi[3], const float delta[3])
{
    const double p[2][3] = {{s->p0.x, s->p0.y, s->p0.z}, {s->p1.x, s->p1.y, s->p1.z}};
    const double half[3] = {s->half.x, s->half.y, s->half.z};
    if (delta) {
        w->delta_size = lanes_set1(cull_maxf(cull_maxf(fabsf(delta[0]), fabsf(delta[1])), fabsf(delta[2])));
        for (int a = 0; a < 3; a++)
            w->delta[a] = lanes_set1(delta[a]);
    }
    for (int a = 0; a < 3; a++) {
        if (lo) {
            w->lo[a] = lanes_set1(lo[a]);
            w->hi[a] = lanes_set1(hi[a]);
        }
        w->p0[a] = lanes_set1((float)p[0][a]);
        w->p1[a] = lanes_set1((float)p[1][a]);
        if (s->kind != CBVH_SHAPE_BOX) /* read for boxes only */
            continue;
        w->half[a] = lanes_set1((float)half[a]);
        for (int i = 0; i < 3; i++)
            w->axes[i][a] = lanes_set1(s->rotated ? (float)s->axes[a][i] : (float)(a == i));
    }
    w->radius = lanes_set1((float)s->radius);
    w->shape_size = lanes_set1((float)(cbvh_dmax(cull_max_abs(s->p0), cull_max_abs(s->p1)) + s->radius +
                                       s->half.x + s->half.y + s->half.z));
    w->box = s->kind == CBVH_SHAPE_BOX;
    w->capsule = s->kind == CBVH_SHAPE_CAPSULE;
}

CBVH_FORCE_INLINE cbvh_lanes cull4_abs(cbvh_lanes x)
{
    return lanes_andnot(lanes_set1(-0.0f), x);
}
CBVH_FORCE_INLINE cbvh_lanes cull4_dot(const cbvh_lanes a[3], const cbvh_lanes b[3])
{
    return lanes_add(lanes_add(lanes_mul(a[0], b[0]), lanes_mul(a[1], b[1])), lanes_mul(a[2], b[2]));
}

/* w ? a : b, lane by lane (SSE2 has no blend). */
CBVH_FORCE_INLINE cbvh_lanes cull4_select(cbvh_lanes w, cbvh_lanes a, cbvh_lanes b)
{
    return lanes_or(lanes_and(w, a), lanes_andnot(w, b));
}

/* What both float culls read of CBVH_LANES triangles: the edges d[k] = c[k + 1] - c[k], the face normal
 * n = (c1 - c0) x (c2 - c0) and |n|^2, span (cbvh_cull_triangle's: the largest coordinate of c1 - c0 and
 * c2 - c0), corner (the largest coordinate of c0), and the heights h0, h1 of w's core points p0, p1 over the
 * plane times |n| (h1 = h0 but for a capsule). */
struct cull4_frame {
    cbvh_lanes d[3][3], n[3], nn, span, corner, h0, h1;
};

CBVH_FORCE_INLINE void cull4_frame_of(const struct cbvh_cull4 *w, const cbvh_lanes c[3][3],
                                      struct cull4_frame *f)
{
    cbvh_lanes w0[3], w1[3];
    f->span = f->corner = lanes_zero();
    for (int a = 0; a < 3; a++) {
        w0[a] = lanes_sub(w->p0[a], c[0][a]);
        w1[a] = lanes_sub(w->p1[a], c[0][a]);
        f->d[0][a] = lanes_sub(c[1][a], c[0][a]);
        f->d[1][a] = lanes_sub(c[2][a], c[1][a]);
        f->d[2][a] = lanes_sub(c[0][a], c[2][a]);
        f->span = lanes_max(f->span, lanes_max(cull4_abs(f->d[0][a]), cull4_abs(f->d[2][a])));
        f->corner = lanes_max(f->corner, cull4_abs(c[0][a]));
    }
    const cbvh_lanes *e1 = f->d[0], e2[3] = {lanes_sub(c[2][0], c[0][0]), lanes_sub(c[2][1], c[0][1]),
                                             lanes_sub(c[2][2], c[0][2])};
    f->n[0] = lanes_sub(lanes_mul(e1[1], e2[2]), lanes_mul(e1[2], e2[1]));
    f->n[1] = lanes_sub(lanes_mul(e1[2], e2[0]), lanes_mul(e1[0], e2[2]));
    f->n[2] = lanes_sub(lanes_mul(e1[0], e2[1]), lanes_mul(e1[1], e2[0]));
    f->nn = cull4_dot(f->n, f->n);
    f->h0 = cull4_dot(f->n, w0);
    f->h1 = w->capsule ? cull4_dot(f->n, w1) : f->h0; /* a ball's p1 is p0 */
}

/* How far w's shape reaches along n from its core, times |n| (cull_reach_along in float). */
CBVH_FORCE_INLINE cbvh_lanes cull4_reach(const struct cbvh_cull4 *w, const cbvh_lanes n[3], cbvh_lanes nn)
{
    if (!w->box)
        return lanes_mul(w->radius, lanes_sqrt(nn));
    return lanes_add(lanes_add(lanes_mul(w->half[0], cull4_abs(cull4_dot(n, w->axes[0]))),
                               lanes_mul(w->half[1], cull4_abs(cull4_dot(n, w->axes[1])))),
                     lanes_mul(w->half[2], cull4_abs(cull4_dot(n, w->axes[2]))));
}

/* The lanes of a triangle of moderate size (cbvh_cull_keep_lanes's bounds: 2^-20 <= span, size <= 2^20) with
 * |n|^2 >= sliver span^4: far from a sliver with sliver = 1/16, where the float tests of edges and distances
 * hold their margins; not quite a sliver with sliver = 2^-20, where the tests that read no normal do. */
CBVH_FORCE_INLINE cbvh_lanes cull4_moderate(const struct cull4_frame *f, cbvh_lanes size, float sliver)
{
    const cbvh_lanes span2 = lanes_mul(f->span, f->span);
    const cbvh_lanes sized =
        lanes_and(lanes_ge(f->span, lanes_set1(0x1p-20f)), lanes_le(size, lanes_set1(0x1p20f)));
    return lanes_and(sized, lanes_ge(f->nn, lanes_mul(lanes_set1(sliver), lanes_mul(span2, span2))));
}

/* The lanes where the shape, its core's points at heights h0 and h1 (times |n|) over the plane, moved by
 * up to motion m (its height change, times |n|), stays on one side of the plane by more than its reach
 * plus the margin 2^-14 span^2 size, on triangles with span at least 2^-30 (cbvh_cull_keep_lanes). */
CBVH_FORCE_INLINE cbvh_lanes cull4_apart(cbvh_lanes h0, cbvh_lanes h1, cbvh_lanes m, cbvh_lanes reach,
                                         cbvh_lanes span, cbvh_lanes size)
{
    const cbvh_lanes zero = lanes_zero();
    const cbvh_lanes margin = lanes_mul(lanes_mul(lanes_set1(0x1p-14f), lanes_mul(span, span)), size);
    const cbvh_lanes gap = lanes_add(reach, margin), low = lanes_add(lanes_min(h0, h1), lanes_min(m, zero));
    const cbvh_lanes high = lanes_add(lanes_max(h0, h1), lanes_max(m, zero));
    const cbvh_lanes above = lanes_gt(low, gap), below = lanes_lt(high, lanes_sub(zero, gap));
    return lanes_and(lanes_ge(span, lanes_set1(0x1p-30f)), lanes_or(above, below));
}

/* The lanes where end point p (height h over the plane, times |n|) lies within sqrt(reach2) of an edge;
 * *inside_plane gets those where it lies within sqrt(reach2) of the plane where it projects into the triangle
 * with every edge function (d[k] x (p - c[k])) . n at least margin (cbvh_cull_triangle's still tests, in
 * float: those of an edge read no normal). outside[k], unless NULL, keeps the lanes where p also lies outside
 * edge k by more than the radius r, the margin; *far the lanes where p lies outside an edge by the margin and
 * farther than sqrt(far2) from all three: its projection then lies out of the triangle, whose nearest point
 * to p is on an edge, farther than sqrt(far2). */
CBVH_FORCE_INLINE cbvh_lanes cull4_end_touches(const cbvh_lanes c[3][3], const cbvh_lanes d[3][3],
                                               const cbvh_lanes dd[3], const cbvh_lanes n[3],
                                               const cbvh_lanes nn, const cbvh_lanes p[3], cbvh_lanes h,
                                               cbvh_lanes r, cbvh_lanes reach2, cbvh_lanes far2,
                                               cbvh_lanes margin, cbvh_lanes outside[3],
                                               cbvh_lanes *inside_plane, cbvh_lanes *far)
{
    cbvh_lanes w[3][3], w2[3];
    for (int k = 0; k < 3; k++) {
        for (int a = 0; a < 3; a++)
            w[k][a] = lanes_sub(p[a], c[k][a]);
        w2[k] = cull4_dot(w[k], w[k]);
    }
    /* a vertex is a point of every edge through it: the edges' tests need their lines only where p projects
     * inside the segment (0 < t < |d|^2), and all three vertices far where every edge is */
    cbvh_lanes inside = lanes_le(lanes_mul(h, h), lanes_mul(reach2, nn)), off = lanes_zero();
    cbvh_lanes near =
        lanes_or(lanes_or(lanes_le(w2[0], reach2), lanes_le(w2[1], reach2)), lanes_le(w2[2], reach2));
    cbvh_lanes clear =
        lanes_and(lanes_and(lanes_gt(w2[0], far2), lanes_gt(w2[1], far2)), lanes_gt(w2[2], far2));
    const cbvh_lanes minus_margin = lanes_sub(lanes_zero(), margin);
    for (int k = 0; k < 3; k++) {
        const cbvh_lanes *dk = d[k], *wk = w[k];
        const cbvh_lanes x[3] = {lanes_sub(lanes_mul(dk[1], wk[2]), lanes_mul(dk[2], wk[1])),
                                 lanes_sub(lanes_mul(dk[2], wk[0]), lanes_mul(dk[0], wk[2])),
                                 lanes_sub(lanes_mul(dk[0], wk[1]), lanes_mul(dk[1], wk[0]))};
        const cbvh_lanes t = cull4_dot(wk, dk), xx = cull4_dot(x, x);
        const cbvh_lanes mid = lanes_and(lanes_gt(t, lanes_zero()), lanes_lt(t, dd[k]));
        const cbvh_lanes line = lanes_le(xx, lanes_mul(reach2, dd[k]));
        const cbvh_lanes far_line = lanes_gt(xx, lanes_mul(far2, dd[k]));
        const cbvh_lanes e = cull4_dot(x, n), out_of = lanes_lt(e, minus_margin); /* -e - margin > 0 */
        inside = lanes_and(inside, lanes_ge(e, margin));
        near = lanes_or(near, lanes_and(mid, line));
        clear = lanes_andnot(lanes_andnot(far_line, mid), clear);
        off = lanes_or(off, out_of);
        if (outside) {
            const cbvh_lanes out = lanes_sub(lanes_sub(lanes_zero(), e), margin);
            const cbvh_lanes out_r2 = lanes_mul(lanes_mul(r, r), lanes_mul(nn, dd[k]));
            const cbvh_lanes beyond = lanes_gt(lanes_mul(out, out), out_r2);
            outside[k] = lanes_and(outside[k], lanes_and(out_of, beyond));
        }
    }
    *far = lanes_and(off, clear);
    *inside_plane = inside;
    return near;
}

/* CBVH_LANES triangles (corners c[v][axis], a lane each) against the still shape of w, in float. Returns the
 * lanes to test further: those whose box meets w's box (the walk's node test, exact) and whose plane does not
 * keep the shape on one side (cbvh_cull_triangle's plane test with the margin 2^-14 span^2 size, 10 times
 * this test's error bound in float, when span is at least 2^-30, far from underflow; a coordinate near
 * overflow makes the margin infinite or a distance NaN, and keeps the lane). A lane dropped here is one
 * cbvh_cull_triangle, and the exact tests, would drop. *touch gets the kept lanes where a ball or capsule
 * surely touches the triangle, by cbvh_cull_triangle's still tests in float, on a triangle of moderate size
 * (2^-20 <= span, size <= 2^20, so nothing overflows or leaves the normal range): an end within the radius
 * less 2^-13 size of the plane where it projects into the triangle, each edge function at least 2^-12 span^3
 * size, on a triangle far from a sliver (|n|^2 >= span^4 / 16), or of an edge, on one no sliver by
 * cbvh_cull_triangle's bound (|n|^2 >= 2^-20 span^4). There too a lane is dropped, for a capsule, when both
 * ends lie outside one edge by more than the radius, that margin, far from a sliver, and, for a ball, no
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
CBVH_FORCE_INLINE uint32_t cbvh_cull_keep_lanes(const struct cbvh_cull4 *w, const cbvh_lanes c[3][3],
                                                uint32_t *touch)
{
    cbvh_lanes in = lanes_all();
    for (int a = 0; a < 3; a++) {
        const cbvh_lanes lo = lanes_min(lanes_min(c[0][a], c[1][a]), c[2][a]);
        const cbvh_lanes hi = lanes_max(lanes_max(c[0][a], c[1][a]), c[2][a]);
        in = lanes_and(in, lanes_and(lanes_le(lo, w->hi[a]), lanes_ge(hi, w->lo[a])));
    }
    *touch = 0;
    if (!lanes_bits(in)) /* no lane's box meets the shape's: nothing to decide */
        return 0;
    struct cull4_frame f;
    cull4_frame_of(w, c, &f);
    const cbvh_lanes(*d)[3] = f.d, *n = f.n, nn = f.nn, span = f.span, s0 = f.h0, s1 = f.h1;
    const cbvh_lanes span2 = lanes_mul(span, span);
    const cbvh_lanes size = lanes_add(lanes_add(f.corner, span), w->shape_size);
    const cbvh_lanes apart = cull4_apart(s0, s1, lanes_zero(), cull4_reach(w, n, nn), span, size);
    cbvh_lanes keep = lanes_andnot(apart, in);
    if (w->box || !lanes_bits(keep))
        return (uint32_t)lanes_bits(keep);
    const cbvh_lanes moderate = cull4_moderate(&f, size, 0x1p-4f), fair = cull4_moderate(&f, size, 0x1p-20f);
    const cbvh_lanes reach_in = lanes_sub(w->radius, lanes_mul(lanes_set1(0x1p-13f), size));
    const cbvh_lanes reaches = lanes_gt(reach_in, lanes_zero()); /* else no point is near enough */
    const cbvh_lanes reach2 = cull4_select(reaches, lanes_mul(reach_in, reach_in), lanes_set1(-1.0f));
    const cbvh_lanes reach_out = lanes_add(w->radius, lanes_mul(lanes_set1(0x1p-13f), size));
    const cbvh_lanes far2 = lanes_mul(reach_out, reach_out);
    const cbvh_lanes margin = lanes_mul(lanes_mul(lanes_set1(0x1p-12f), lanes_mul(span2, span)), size);
    const cbvh_lanes dd[3] = {cull4_dot(d[0], d[0]), cull4_dot(d[1], d[1]), cull4_dot(d[2], d[2])};
    cbvh_lanes outside[3] = {moderate, moderate, moderate};
    const cbvh_lanes r = w->radius;
    cbvh_lanes far, far1, inside, inside1, near, clear; /* clear: the lanes dropped */
    if (w->capsule) {
        near = cull4_end_touches(c, d, dd, n, nn, w->p0, s0, r, reach2, far2, margin, outside, &inside, &far);
        near = lanes_or(near, cull4_end_touches(c, d, dd, n, nn, w->p1, s1, r, reach2, far2, margin, outside,
                                                &inside1, &far1));
        inside = lanes_or(inside, inside1);
        clear = lanes_or(lanes_or(outside[0], outside[1]), outside[2]);
    } else {
        near = cull4_end_touches(c, d, dd, n, nn, w->p0, s0, r, reach2, far2, margin, NULL, &inside, &far);
        clear = lanes_and(far, fair);
    }
    keep = lanes_andnot(clear, keep);
    const cbvh_lanes sure = lanes_or(lanes_and(inside, moderate), lanes_and(near, fair));
    *touch = (uint32_t)lanes_bits(lanes_and(sure, keep));
    return (uint32_t)lanes_bits(keep);
}

/* CBVH_LANES triangles (as for cbvh_cull_keep_lanes) against w's shape moved by t * delta for t in [0, tmax]
 * (w from cbvh_cull4_init with delta), in float. Returns the lanes to test further: those whose plane does
 * not keep the swept shape on one side (cbvh_cull_triangle's plane test, CBVH_CULL_CLEAR, with its motion:
 * the hull of the core's points at t = 0 and t = tmax grown by the reach) with the margin 2^-14 span^2 size,
 * size now counting the motion's largest coordinate too; and, for a ball or capsule on a triangle of moderate
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
CBVH_FORCE_INLINE uint32_t cbvh_cull_sweep_lanes(const struct cbvh_cull4 *w, const cbvh_lanes c[3][3],
                                                 float tmax, uint32_t *clear_at_start)
{
    cbvh_lanes motion[3];
    struct cull4_frame f;
    cull4_frame_of(w, c, &f);
    const cbvh_lanes t = lanes_set1(tmax);
    for (int a = 0; a < 3; a++)
        motion[a] = lanes_mul(w->delta[a], t);
    const cbvh_lanes *n = f.n, nn = f.nn, span = f.span, zero = lanes_zero();
    const cbvh_lanes size =
        lanes_add(lanes_add(lanes_add(f.corner, span), w->shape_size), lanes_mul(w->delta_size, t));
    const cbvh_lanes h0 = f.h0, h1 = f.h1, m = cull4_dot(n, motion);
    const cbvh_lanes reach = cull4_reach(w, n, nn);
    cbvh_lanes keep = lanes_andnot(cull4_apart(h0, h1, m, reach, span, size), lanes_all());
    const uint32_t start_apart = (uint32_t)lanes_bits(cull4_apart(h0, h1, zero, reach, span, size));
    *clear_at_start = start_apart & (uint32_t)lanes_bits(keep);
    if (w->box || !lanes_bits(keep))
        return (uint32_t)lanes_bits(keep);
    const cbvh_lanes margin =
        lanes_mul(lanes_mul(lanes_set1(0x1p-12f), lanes_mul(lanes_mul(span, span), span)), size);
    const cbvh_lanes r2nn = lanes_mul(lanes_mul(w->radius, w->radius), nn);
    cbvh_lanes outside = zero;
    for (int k = 0; k < 3; k++) {
        /* edge k's function at p, (d[k] x (p - c[k])) . n, is g . (p - c[k]) with g = n x d[k] */
        const cbvh_lanes *dk = f.d[k];
        const cbvh_lanes g[3] = {lanes_sub(lanes_mul(n[1], dk[2]), lanes_mul(n[2], dk[1])),
                                 lanes_sub(lanes_mul(n[2], dk[0]), lanes_mul(n[0], dk[2])),
                                 lanes_sub(lanes_mul(n[0], dk[1]), lanes_mul(n[1], dk[0]))};
        cbvh_lanes v0[3], v1[3];
        for (int a = 0; a < 3; a++) {
            v0[a] = lanes_sub(w->p0[a], c[k][a]);
            v1[a] = lanes_sub(w->p1[a], c[k][a]);
        }
        const cbvh_lanes moved = lanes_max(cull4_dot(g, motion), zero);
        const cbvh_lanes e = lanes_add(lanes_max(cull4_dot(g, v0), cull4_dot(g, v1)), moved);
        const cbvh_lanes out = lanes_sub(lanes_sub(zero, e), margin);
        const cbvh_lanes beyond = lanes_gt(lanes_mul(out, out), lanes_mul(r2nn, cull4_dot(dk, dk)));
        outside = lanes_or(outside, lanes_and(lanes_gt(out, zero), beyond));
    }
    keep = lanes_andnot(lanes_and(outside, cull4_moderate(&f, size, 0x1p-4f)), keep);
    *clear_at_start &= (uint32_t)lanes_bits(keep);
    return (uint32_t)lanes_bits(keep);
}

#endif

#endif
