/* overlap.c: box (axis-aligned or oriented), sphere and capsule overlap and contact queries: the shape walk
 * (shape_walk.h), exact per-triangle tests, callback and/or output array. overlap_avx2.c compiles the walk
 * and its tests again for AVX2 (CBVH_OVERLAP_AVX2: the walk alone, no public functions). */
#include "config.h"

#include <math.h>
#include <string.h>

#include "query/triangle_frame.h"
#include "query/closest.h"
#include "query/grown_path.h"
#include "query/leaf.h"
#include "query/sweep_walk.h"
#include "query/walk.h"
#include "query/raycast.h"
#include "query/shape.h"
#include "query/shape_cull.h"
#include "query/shape_leaf.h"
#include "query/triangle_box.h"

/* Where overlapping triangles go. */
struct overlap_sink {
    cbvh_overlap_fn callback;
    void *user;
    uint32_t *out;
    cbvh_contact *contacts; /* the contact queries' output, instead of out */
    size_t capacity;
    size_t reported;
    size_t skip;   /* overlapping triangles passed over before the first report (the _from queries) */
    int find_more; /* a full out stops the query at the next overlapping triangle, which sets more */
    int more;
};

/* Reports a triangle (and its contact, for the contact queries); returns 1 when the query must stop (the
 * callback asked, or out is full: at once, or with find_more at the next triangle). */
CBVH_FORCE_INLINE int sink_report(struct overlap_sink *s, uint32_t tri, const cbvh_contact *contact)
{
    if (s->skip > 0) {
        s->skip--;
        return 0;
    }
    if (s->find_more && s->reported >= s->capacity) {
        s->more = 1;
        return 1;
    }
    if (s->out)
        s->out[s->reported] = tri;
    if (s->contacts)
        s->contacts[s->reported] = *contact;
    s->reported++;
    if (s->callback && s->callback(s->user, tri))
        return 1;
    return !s->find_more && (s->out || s->contacts) && s->reported >= s->capacity;
}

/* The region tested against node boxes (an AABB) and against triangles: a ball, a capsule or a box (its
 * center p0 and half extents, which for cbvh_overlap_box's [min, max] are the exact double midpoint and
 * half size), in the mesh's frame; contacts go to the world of `placement` when it is not NULL. */
struct overlap_region {
    float lo[3], hi[3]; /* conservative bounds of the region, for node culling */
    struct cbvh_local_shape shape;
    struct cbvh_box box;
    const struct cbvh_placement *placement;
};

#ifdef CBVH_HAVE_AVX2
/* The overlap walk compiled for AVX2 (overlap_avx2.c), eight leaf triangles a vector through the float
 * tests, for CPUs that have it (the caller checks). Returns sink->reported. */
size_t cbvh_overlap_walk_avx2(const struct cbvh_file *f, const struct overlap_region *region,
                              struct overlap_sink *sink);
#endif

/* What the exact overlap test of a triangle found that its contact reads too: for a ball or capsule the
 * closest points of its core (center or segment) and the triangle and the square of their distance; for
 * a box, when the caller wants the contact, the separating-axis test's axis of least penetration and depth.
 */
struct triangle_exact {
    int want_contact; /* set by the caller: the box test then computes n and depth */
    int known;        /* 0 until the test (or the contact) filled the fields below */
    cbvh_v3 on_core, on_tri, n;
    double d2, depth;
};

/* Fills ex's closest points for the round shape s and triangle v unless they are known already. */
static void round_closest_of(const struct cbvh_local_shape *s, const cbvh_v3 v[3], struct triangle_exact *ex)
{
    if (ex->known)
        return;
    ex->known = 1;
    if (s->kind == CBVH_SHAPE_SPHERE) {
        ex->on_core = s->p0;
        ex->on_tri = cbvh_closest_point_in_triangle(s->p0, v);
        ex->d2 = v3_len2(v3_sub(ex->on_core, ex->on_tri));
    } else {
        ex->d2 = cbvh_closest_segment_triangle_of(s->p0, s->p1, v, &ex->on_core, &ex->on_tri);
    }
}

/* The box test of cbvh_triangle_oriented_box_sweep at rest: 1 when the box overlaps triangle (a, b, c);
 * with ex->want_contact, a hit also leaves the axis of least penetration and its depth in ex. */
static int box_touches(const struct overlap_region *r, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                       struct triangle_exact *ex)
{
    double t;
    if (!ex->want_contact)
        return cbvh_triangle_oriented_box_sweep(a, b, c, &r->box, v3(0, 0, 0), 0.0, &t, NULL, NULL);
    ex->depth = 0.0;
    ex->n = v3(0, 0, 1); /* what a contact reads should the test, run for it alone, find no overlap */
    ex->known = cbvh_triangle_oriented_box_sweep(a, b, c, &r->box, v3(0, 0, 0), 0.0, &t, &ex->n, &ex->depth);
    return ex->known;
}

/* The exact overlap test of the region and triangle (a, b, c), leaving in ex what the contact reads. */
static int region_triangle(const struct overlap_region *r, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                           struct triangle_exact *ex)
{
    const struct cbvh_local_shape *s = &r->shape;
    if (s->kind == CBVH_SHAPE_BOX)
        return box_touches(r, a, b, c, ex);
    const cbvh_v3 v[3] = {a, b, c};
    round_closest_of(s, v, ex);
    return ex->d2 <= s->radius * s->radius;
}

/* The contact of a box region with a triangle it overlaps: the separating-axis test's axis of least
 * penetration and its depth (exact: the axes hold every face normal of the obstacle), and a point of the
 * triangle inside the box. */
static void box_contact(const struct overlap_region *r, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                        struct triangle_exact *ex, cbvh_v3 *n, double *depth, cbvh_v3 *point)
{
    if (!ex->known) {
        ex->want_contact = 1;
        box_touches(r, a, b, c, ex);
    }
    *n = ex->n;
    *depth = ex->depth;
    /* No operand of the maxima is NaN (finite half extents; lengths of differences of finite vertices, at
     * most infinite), so cbvh_dmax gives what fmax, a call into libm, gives. */
    const cbvh_v3 o = r->box.center, h = r->box.half;
    const double size = cbvh_dmax(cbvh_dmax(h.x, h.y), h.z) +
                        cbvh_dmax(v3_len(v3_sub(b, a)), v3_len(v3_sub(c, a))) + fabs(o.x) + fabs(o.y) +
                        fabs(o.z);
    *point = cbvh_box_contact_point(a, b, c, &r->box, o, *n, 1e-6 * size);
}

/* The contact of a ball or capsule region with triangle v it overlaps (double precision): on the closest
 * points of core (center, segment) and triangle at distance d > 0, the normal from the triangle's point to
 * the core's and depth radius - d: moving the shape by depth along it leaves exactly the radius between
 * them, and, the normal being the separating axis of two convex sets, every other pair at least as far.
 * A core that reaches the triangle (d = 0) is pushed off the triangle's plane: along the unit face normal
 * (as wound) or against it, whichever needs less, by radius plus the depth of the core's lowest end below
 * the plane; the whole core then lies at least radius above it. */
static void round_contact(const struct cbvh_local_shape *s, const cbvh_v3 v[3], struct triangle_exact *ex,
                          cbvh_v3 *n, double *depth, cbvh_v3 *on_tri)
{
    round_closest_of(s, v, ex);
    *on_tri = ex->on_tri;
    const double d = sqrt(ex->d2);
    if (d > 0.0) {
        *n = v3_scale(v3_sub(ex->on_core, ex->on_tri), 1.0 / d);
        *depth = s->radius - d;
        return;
    }
    struct cbvh_triangle_frame f;
    cbvh_triangle_frame_of(v, &f);
    *n = v3_scale(f.n, 1.0 / sqrt(f.nn)); /* a file's triangles have a non-zero area */
    const double s0 = v3_dot(v3_sub(s->p0, v[f.base]), *n), s1 = v3_dot(v3_sub(s->p1, v[f.base]), *n);
    if (s0 + s1 >= 0.0) {
        *depth = s->radius - fmin(s0, s1);
    } else {
        *n = v3_scale(*n, -1.0);
        *depth = s->radius + fmax(s0, s1);
    }
}

/* The contact of the region with triangle v it overlaps, in the world of the region's placement. */
static void region_contact(const struct overlap_region *r, const cbvh_v3 v[3], uint32_t tri,
                           struct triangle_exact *ex, cbvh_contact *out)
{
    cbvh_v3 n, point;
    double depth;
    if (r->shape.kind == CBVH_SHAPE_BOX)
        box_contact(r, v[0], v[1], v[2], ex, &n, &depth, &point);
    else
        round_contact(&r->shape, v, ex, &n, &depth, &point);
    if (r->placement) {
        n = cbvh_rotate(r->placement->rotation, n);
        point = cbvh_point_to_world(r->placement, point);
        depth *= r->placement->scale;
    }
    out->tri = tri;
    out->depth = (float)depth;
    v3_to_f(n, out->normal);
    v3_to_f(point, out->point);
}

/* A ball's node test: node boxes (their planes as cbvh_dequantize gives them) within the radius of its
 * center, in float. */
struct ball_reach {
    float center[3]; /* the center rounded to float */
    float reach2;    /* what the squared float distance of a box from center may reach (ball_reach_of) */
};

/* Per axis the distance of the float center from a box's planes is rounded at most by 2^-24 of itself, and
 * the center's own rounding moves it by at most 2^-24 |center|: a box within r of the true center has a float
 * squared distance, each of its five operations rounded by at most 2^-24 of itself, below (r + 2^-23
 * |center|_max)^2 (1 + 2^-21), plus 2^-120 for underflow. reach2 is that bound with room to spare (the
 * exact tests' own rounding, 2^-50 of r^2, included): rounded up, and infinite when it leaves float. */
static void ball_reach_of(const struct cbvh_local_shape *s, struct ball_reach *b)
{
    v3_to_f(s->p0, b->center);
    const double reach = s->radius + 0x1p-23 * cull_max_abs(s->p0);
    const double reach2 = reach * reach * (1.0 + 0x1p-19) + 0x1p-120;
    b->reach2 = reach2 < 0x1p127 ? (float)reach2 * (1.0f + 0x1p-22f) : INFINITY;
}

/* The squared float distance of b's center from the box [lo, hi] (per axis: how far outside it lies). */
static inline float ball_distance2(const struct ball_reach *b, const float lo[3], const float hi[3])
{
    float d2 = 0.0f;
    for (int a = 0; a < 3; a++) {
        const float below = lo[a] - b->center[a], above = b->center[a] - hi[a];
        const float d = cull_maxf(cull_maxf(below, above), 0.0f);
        d2 = d2 + d * d;
    }
    return d2;
}

/* An overlap as the shape walk sees it: the region's box as a range of grid coordinates per axis; for a
 * ball its reach (ball: 1), for a capsule the path of the float box around its end ball p0 to p1 (capsule:
 * 1; capsule_path). */
struct overlap_query {
    const struct cbvh_file *f;
    const struct overlap_region *region;
    struct overlap_sink *sink;
    struct cbvh_grid_range grid;
    int ball, capsule;
    uint16_t small[3]; /* per axis, the largest extent in grid steps of a box small next to the shape */
    struct ball_reach reach;
    struct cbvh_grown_path path;
#ifdef CBVH_HAVE_SIMD
    __m128i small4[3];             /* small, in every 16-bit lane */
    struct cbvh_grid_range4 grid4; /* grid, as four wide slots at once test it */
    struct cbvh_cull4 cull4;
    __m128 center4[3], reach2, origin4[3], scale4[3]; /* a ball's reach, and the file's grid, in every lane */
    int inner;                           /* an axis-aligned box's inner box is not empty (box_inner_of) */
    cbvh_lanes inner_lo[3], inner_hi[3]; /* the inner box, in every lane */
#endif
};

/* 1 when the plane of grid coordinate q lies below x, or at x unless `strict`. */
static int plane_below(uint32_t q, float x, float origin, float scale, int strict)
{
    const float plane = cbvh_dequantize(q, origin, scale);
    return strict ? plane < x : plane <= x;
}

/* The largest grid coordinate in [0, CBVH_Q_MAX] whose plane (cbvh_dequantize) is at most x (below x when
 * `strict`), or -1. Planes grow with their coordinates (scale >= 0, every rounding monotonic), so from an
 * estimate an outward search brackets it (far from the origin many coordinates round to one plane), and
 * bisection ends it. */
static int32_t grid_last_below(float x, float origin, float scale, int strict)
{
    const int32_t top = (int32_t)CBVH_Q_MAX;
    const double e = scale > 0.0f ? ((double)x - origin) / scale : origin <= x ? top : -1;
    int32_t lo = e < -1.0 ? -1 : e > top ? top : (int32_t)e, hi, step = 1; /* lo: below x, or -1 */
    if (lo >= 0 && !plane_below((uint32_t)lo, x, origin, scale, strict)) {
        do {
            hi = lo;
            lo = hi - step < 0 ? -1 : hi - step;
            step *= 2;
        } while (lo >= 0 && !plane_below((uint32_t)lo, x, origin, scale, strict));
    } else {
        for (hi = lo + 1; hi <= top && plane_below((uint32_t)hi, x, origin, scale, strict); step *= 2) {
            lo = hi;
            hi = lo + step > top + 1 ? top + 1 : lo + step;
        }
    }
    /* the plane of lo is below x (or lo = -1), the plane of hi not (or hi = top + 1) */
    while (hi - lo > 1) {
        const int32_t mid = lo + (hi - lo) / 2;
        if (plane_below((uint32_t)mid, x, origin, scale, strict))
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

#ifdef CBVH_HAVE_SIMD
/* grid_last_below of x[a] on the grid's axes a = 0, 1, 2 at once where an estimate checks out: out[a] when
 * the plane of out[a] is at most x[a] (below x[a] when `strict`), or out[a] = -1, and the next plane is
 * not, or out[a] = CBVH_Q_MAX (the planes grow with the coordinate, so that is the answer). Returns the
 * axes left to grid_last_below: few, far from the origin, where many coordinates round to one plane. */
static uint32_t grid_last_below3(const float x[3], const struct cbvh_file *f, int strict, int32_t out[3])
{
    const __m128 origin = _mm_setr_ps(f->grid_origin[0], f->grid_origin[1], f->grid_origin[2], 0.0f);
    const __m128 scale = _mm_setr_ps(f->grid_scale[0], f->grid_scale[1], f->grid_scale[2], 1.0f);
    const __m128 xs = _mm_setr_ps(x[0], x[1], x[2], 0.0f), top = _mm_set1_ps((float)CBVH_Q_MAX);
    /* any estimate in [-1, CBVH_Q_MAX] will do (a NaN becomes CBVH_Q_MAX): the test below decides */
    const __m128 estimate = _mm_div_ps(_mm_sub_ps(xs, origin), scale);
    const __m128 e = _mm_max_ps(_mm_min_ps(estimate, top), _mm_set1_ps(-1.0f));
    const __m128i q = _mm_cvttps_epi32(e), next = _mm_add_epi32(q, _mm_set1_epi32(1));
    /* cbvh_dequantize on four lanes: the same two float operations */
    const __m128 plane = _mm_add_ps(origin, _mm_mul_ps(_mm_cvtepi32_ps(q), scale));
    const __m128 plane_next = _mm_add_ps(origin, _mm_mul_ps(_mm_cvtepi32_ps(next), scale));
    const __m128 below = strict ? _mm_cmplt_ps(plane, xs) : _mm_cmple_ps(plane, xs);
    const __m128 next_below = strict ? _mm_cmplt_ps(plane_next, xs) : _mm_cmple_ps(plane_next, xs);
    const __m128i none = _mm_cmpeq_epi32(q, _mm_set1_epi32(-1));
    const __m128i last = _mm_cmpeq_epi32(q, _mm_set1_epi32((int32_t)CBVH_Q_MAX));
    const __m128i next_above = _mm_andnot_si128(_mm_castps_si128(next_below), _mm_set1_epi32(-1));
    const __m128i ok =
        _mm_and_si128(_mm_or_si128(_mm_castps_si128(below), none), _mm_or_si128(next_above, last));
    int32_t lanes[4];
    _mm_storeu_si128((__m128i *)(void *)lanes, q);
    out[0] = lanes[0];
    out[1] = lanes[1];
    out[2] = lanes[2];
    return ~(uint32_t)_mm_movemask_ps(_mm_castsi128_ps(ok)) & 7u;
}
#endif

/* The node boxes that meet the region's box (closed: a box touching it is not culled), as ranges of grid
 * coordinates: a box's min plane is at most the region's max exactly when its coordinate is at most g->hi,
 * its max plane at least the region's min exactly when its coordinate exceeds the last one whose plane lies
 * below that min. */
static void grid_range(const struct cbvh_file *f, const struct overlap_region *r, struct cbvh_grid_range *g)
{
    int32_t below_lo[3];
    uint32_t left_hi = 7u, left_lo = 7u;
#ifdef CBVH_HAVE_SIMD
    left_hi = grid_last_below3(r->hi, f, 0, g->hi);
    left_lo = grid_last_below3(r->lo, f, 1, below_lo);
#endif
    for (int a = 0; a < 3; a++) {
        if (left_hi >> a & 1u)
            g->hi[a] = grid_last_below(r->hi[a], f->grid_origin[a], f->grid_scale[a], 0);
        if (left_lo >> a & 1u)
            below_lo[a] = grid_last_below(r->lo[a], f->grid_origin[a], f->grid_scale[a], 1);
        g->lo[a] = below_lo[a] + 1;
    }
}

/* A capsule p0-p1 of radius r as the path of the float box around the ball of radius r at p0
 * (cbvh_sweep_bounds) by delta = p1 - p0 rounded to float, its extent grown by 2^-23 |delta| (more than
 * that rounding, which moves the path's points by at most 2^-24 |delta| per axis from the segment's): a node
 * box holding a point within r of the segment is crossed by the path grown by the extent for t in [0, 1]. */
static void capsule_path(const struct cbvh_file *f, const struct cbvh_local_shape *s,
                         struct cbvh_grown_path *p)
{
    struct cbvh_local_shape ball = *s;
    ball.kind = CBVH_SHAPE_SPHERE;
    ball.p1 = ball.p0;
    cbvh_v3 lo, hi;
    cbvh_shape_bounds(&ball, &lo, &hi);
    float center[3], extent[3], delta[3];
    cbvh_sweep_bounds(lo, hi, center, extent);
    for (int a = 0; a < 3; a++) {
        delta[a] = (float)(v3_get(s->p1, a) - v3_get(s->p0, a));
        extent[a] = nextafterf(extent[a] + fabsf(delta[a]) * 0x1p-23f, INFINITY);
    }
    cbvh_grown_path_init(p, f, center, extent, delta);
}

/* 1 when the box of grid coordinates q (q[0..2] its minimum, q[3..5] its maximum) is small next to the
 * region's ball or capsule (struct overlap_query's small). */
static int box_small(const struct overlap_query *o, const uint32_t q[6])
{
    return q[3] - q[0] <= o->small[0] && q[4] - q[1] <= o->small[1] && q[5] - q[2] <= o->small[2];
}

/* The region's grid range meets the box, for a ball the box lies within its reach, for a capsule its path
 * crosses the box (when the box is small: box_small). */
static int overlap_enter(void *query, const uint32_t q[6], float *entry)
{
    const struct overlap_query *o = query;
    *entry = 0.0f;
    if (!cbvh_grid_range_meets(&o->grid, q))
        return 0;
    if ((o->ball | o->capsule) && !box_small(o, q))
        return 1;
    if (o->capsule) {
        float crossed_at;
        return cbvh_grown_path_grid(&o->path, o->f, q, 1.0f, &crossed_at);
    }
    if (!o->ball)
        return 1;
    const float *origin = o->f->grid_origin, *scale = o->f->grid_scale;
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = cbvh_dequantize(q[a], origin[a], scale[a]);
        hi[a] = cbvh_dequantize(q[3 + a], origin[a], scale[a]);
    }
    return ball_distance2(&o->reach, lo, hi) <= o->reach.reach2;
}

#ifdef CBVH_HAVE_SIMD
/* box_small on the four slots of wide node `node` at once: bit s for slot s (used or not); x <= y for
 * unsigned 16-bit x, y exactly when the saturated x - y is 0. */
static inline uint32_t slots_small4(const uint8_t *node, const __m128i small4[3])
{
    const __m128i zero = _mm_setzero_si128();
    __m128i small = _mm_set1_epi16(-1);
    for (uint32_t a = 0; a < 3; a++) {
        __m128i qmin, qmax;
        cbvh_w4_grid_planes4(node, a, &qmin, &qmax);
        const __m128i extent = _mm_subs_epu16(qmax, qmin);
        small = _mm_and_si128(small, _mm_cmpeq_epi16(_mm_subs_epu16(extent, small4[a]), zero));
    }
    return (uint32_t)_mm_movemask_epi8(_mm_packs_epi16(small, small)) & 0xFu;
}

/* overlap_enter on the four slots of a wide node at once (cbvh_grid_range4_hits; a ball's distance lane for
 * lane the same float operations in the same order as ball_distance2, _mm_max_ps(a, b) being a > b ? a : b
 * as cull_maxf). */
CBVH_FORCE_INLINE uint32_t overlap_enter4(void *query, const uint8_t *node, float entry[4])
{
    const struct overlap_query *q = query;
    _mm_storeu_ps(entry, _mm_setzero_ps());
    const uint32_t meets = cbvh_grid_range4_hits(node, &q->grid4);
    if (!(q->ball | q->capsule) || !(meets & slots_small4(node, q->small4)))
        return meets;
    if (q->capsule) {
        float crossed_at[4];
        return meets & cbvh_grown_path_node4(&q->path, node, 1.0f, crossed_at);
    }
    __m128 d2 = _mm_setzero_ps();
    for (uint32_t a = 0; a < 3; a++) {
        __m128 lo, hi;
        cbvh_w4_planes4(node, a, q->origin4[a], q->scale4[a], &lo, &hi);
        const __m128 below = _mm_sub_ps(lo, q->center4[a]), above = _mm_sub_ps(q->center4[a], hi);
        const __m128 d = _mm_max_ps(_mm_max_ps(below, above), _mm_setzero_ps());
        d2 = _mm_add_ps(d2, _mm_mul_ps(d, d));
    }
    return meets & (uint32_t)_mm_movemask_ps(_mm_cmple_ps(d2, q->reach2));
}
#define OVERLAP_ENTER4 overlap_enter4
#else
#define OVERLAP_ENTER4 NULL
#endif

/* What a triangle past the walk's box test has left to pass: the cheap tests in double, then the exact test
 * (OVERLAP_CULL: without SIMD); the exact test alone (OVERLAP_EXACT: past the float tests,
 * cbvh_cull_keep_lanes, which decide what the cheap tests would); or nothing (OVERLAP_SURE: the region surely
 * touches it). */
enum overlap_left { OVERLAP_CULL, OVERLAP_EXACT, OVERLAP_SURE };

/* 1 when the region overlaps a triangle that has the tests `left` (not OVERLAP_SURE) to pass; the exact
 * test leaves in ex what the contact reads (struct triangle_exact). */
static int overlap_tests(const struct overlap_query *q, const float a[3], const float b[3], const float c[3],
                         enum overlap_left left, struct triangle_exact *ex)
{
    const cbvh_v3 va = v3_from_f(a), vb = v3_from_f(b), vc = v3_from_f(c);
    const struct cbvh_local_shape *s = &q->region->shape;
    const enum cbvh_cull_verdict v =
        left == OVERLAP_EXACT ? CBVH_CULL_MAY_TOUCH : cbvh_cull_triangle(s, v3(0, 0, 0), 0.0, va, vb, vc, 1);
    return v != CBVH_CULL_CLEAR && (v == CBVH_CULL_TOUCHES || region_triangle(q->region, va, vb, vc, ex));
}

/* Cooked triangle k past the walk's box test: its tests (`left`) and the report. Returns 1 when the query
 * must stop. Inlined, so that a triangle the float tests found touching costs the report only. */
CBVH_FORCE_INLINE int overlap_triangle(const struct overlap_query *q, uint32_t k, const float a[3],
                                       const float b[3], const float c[3], enum overlap_left left)
{
    struct triangle_exact ex; /* the fields past `known` are written before they are read */
    ex.want_contact = q->sink->contacts && q->sink->skip == 0;
    ex.known = 0;
    if (left != OVERLAP_SURE && !overlap_tests(q, a, b, c, left, &ex))
        return 0;
    const uint32_t tri = cbvh_original_id(q->f, k);
    cbvh_contact contact;
    if (ex.want_contact) {
        const cbvh_v3 v[3] = {v3_from_f(a), v3_from_f(b), v3_from_f(c)};
        region_contact(q->region, v, tri, &ex, &contact);
    }
    return sink_report(q->sink, tri, &contact);
}

#ifndef CBVH_HAVE_SIMD
/* The region's box meets [lo, hi]: boxes are closed, so a region touching one is not culled. */
static int region_meets(const struct overlap_region *r, const float lo[3], const float hi[3])
{
    return !((lo[0] > r->hi[0]) | (hi[0] < r->lo[0]) | (lo[1] > r->hi[1]) | (hi[1] < r->lo[1]) |
             (lo[2] > r->hi[2]) | (hi[2] < r->lo[2]));
}
#endif

#ifdef CBVH_HAVE_SIMD
/* The box a triangle surely overlaps the region's axis-aligned box when a vertex lies in it: the region's
 * [lo, hi] shrunk by m = 2^-19 s + 2^-100, s the largest |lo| or |hi|, rounded to float (by at most 2^-25 s).
 * Those bounds lie at most 2^-21 |x| + 2^-126 outside the exact box (shape_region; cbvh_overlap_box's are
 * the box), so such a vertex lies inside the exact box by more than 2^-20 s on every axis, hence by 2^-20 s
 * |u|_1 on any axis u of the exact separating-axis test, whose rounding of the vertex's projection and of
 * the box's radius is below 2^-48 s |u|_1 (every coordinate relative to the box's center is at most s):
 * no axis separates them, and the exact test finds what this finds. 0 when the inner box is empty. */
static int box_inner_of(const struct overlap_region *r, float lo[3], float hi[3])
{
    double s = 0.0;
    for (int a = 0; a < 3; a++)
        s = cbvh_dmax(s, cbvh_dmax(fabs(r->lo[a]), fabs(r->hi[a])));
    const double m = 0x1p-19 * s + 0x1p-100;
    int empty = 0;
    for (int a = 0; a < 3; a++) {
        lo[a] = (float)(r->lo[a] + m);
        hi[a] = (float)(r->hi[a] - m);
        empty |= !(lo[a] <= hi[a]);
    }
    return !empty;
}

/* The lanes of corners with a vertex in the inner box (box_inner_of): those triangles surely overlap the
 * region. */
CBVH_FORCE_INLINE uint32_t inner_vertex_lanes(const struct overlap_query *q, const cbvh_lanes corners[3][3])
{
    cbvh_lanes any = lanes_zero();
    for (int k = 0; k < 3; k++) {
        cbvh_lanes in =
            lanes_and(lanes_ge(corners[k][0], q->inner_lo[0]), lanes_le(corners[k][0], q->inner_hi[0]));
        for (int a = 1; a < 3; a++)
            in = lanes_and(in, lanes_and(lanes_ge(corners[k][a], q->inner_lo[a]),
                                         lanes_le(corners[k][a], q->inner_hi[a])));
        any = lanes_or(any, in);
    }
    return (uint32_t)lanes_bits(any);
}

/* The CBVH_LANES triangles of group g through the float tests (a capsule's path against their boxes,
 * cbvh_grown_path_triangle_lanes, then cbvh_cull_keep_lanes; an axis-aligned box's inner-vertex test), the
 * kept ones in order through the exact test unless surely touching. */
CBVH_FORCE_INLINE int overlap_group(void *query, uint32_t k, const struct leaf_group *g)
{
    const struct overlap_query *q = query;
    cbvh_lanes corners[3][3];
    cbvh_group_corners(g, corners);
    uint32_t group = g->mask;
    if (q->capsule && !(group &= cbvh_grown_path_triangle_lanes(&q->path, corners, 1.0f)))
        return 0;
    uint32_t touch, keep = cbvh_cull_keep_lanes(&q->cull4, corners, &touch) & group;
    if (q->inner && (keep & ~touch))
        touch |= inner_vertex_lanes(q, corners);
    for (; keep; keep &= keep - 1u) {
        const uint32_t j = lanes_lowest(keep);
        float a[3], b[3], c[3];
        cbvh_group_triangle(g, j, a, b, c);
        if (overlap_triangle(q, k + j, a, b, c, touch >> j & 1u ? OVERLAP_SURE : OVERLAP_EXACT))
            return 1;
    }
    return 0;
}
#endif

/* With SIMD, CBVH_LANES triangles at a time (overlap_group); else one at a time through the box test. */
static int overlap_leaf(void *query, uint32_t first, uint32_t count)
{
#ifdef CBVH_HAVE_SIMD
    return cbvh_shape_leaf_groups(((const struct overlap_query *)query)->f, first, count, overlap_group,
                                  query);
#else
    const struct overlap_query *q = query;
    for (uint32_t k = first; k < first + count; k++) {
        float a[3], b[3], c[3], lo[3], hi[3];
        cbvh_triangle_vertices(q->f, k, a, b, c);
        cbvh_triangle_bounds(a, b, c, lo, hi);
        if (region_meets(q->region, lo, hi) && overlap_triangle(q, k, a, b, c, OVERLAP_CULL))
            return 1;
    }
    return 0;
#endif
}

/* How far a ball or capsule reaches for the rules below: its radius plus a quarter of its segment. */
static double round_reach(const struct cbvh_local_shape *s)
{
    return s->radius + 0.25 * v3_len(v3_sub(s->p1, s->p0));
}

/* Whether a ball's or capsule's own node tests (ball_reach, capsule_path) may run beside the bounding box's,
 * and a capsule's path test of the leaves' triangles: when the shape reaches FINE_REACH times the mesh's
 * small triangles' size (struct cbvh_file's small_triangle_extent) or more. Among smaller leaves the tests
 * cull boxes and triangles in the corners of the bounding box; among larger ones they cost without culling.
 * docs/PERFORMANCE.md gives the measurements behind the factors. Either way the answers are the same. */
#define FINE_REACH 1.25

/* The largest box extent, per axis in grid steps, that the node tests then take (box_small): SMALL_BOX_REACH
 * times the reach. A box much larger than the shape that meets its bounding box nearly always meets the
 * shape too: the test would cost without culling. */
#define SMALL_BOX_REACH 2.0

static void small_boxes(const struct cbvh_file *f, double reach, uint16_t small[3])
{
    for (int a = 0; a < 3; a++) {
        const double steps =
            f->grid_scale[a] > 0.0f ? SMALL_BOX_REACH * reach / f->grid_scale[a] : (double)CBVH_Q_MAX;
        small[a] = (uint16_t)(steps < CBVH_Q_MAX ? steps : CBVH_Q_MAX);
    }
}

/* Stored order: the order does not matter when every overlap is reported. Compiled once per instruction set
 * (overlap_walk). */
CBVH_FORCE_INLINE size_t overlap_walk_kernel(const struct cbvh_file *f, const struct overlap_region *region,
                                             struct overlap_sink *sink)
{
    struct overlap_query q; /* not cleared: every field the walk reads is set below */
    q.f = f;
    q.region = region;
    q.sink = sink;
    if ((sink->out || sink->contacts) && sink->capacity == 0 && !sink->find_more)
        return 0; /* out is full before the first report */
    grid_range(f, region, &q.grid);
    if (cbvh_grid_range_empty(&q.grid))
        return sink->reported; /* no node box can meet it */
    const double reach = region->shape.kind == CBVH_SHAPE_BOX ? 0.0 : round_reach(&region->shape);
    const int fine = reach > 0.0 && reach >= FINE_REACH * f->small_triangle_extent;
    q.ball = fine && region->shape.kind == CBVH_SHAPE_SPHERE;
    q.capsule = fine && region->shape.kind == CBVH_SHAPE_CAPSULE;
    if (q.ball)
        ball_reach_of(&region->shape, &q.reach);
    if (q.capsule)
        capsule_path(f, &region->shape, &q.path);
    q.small[0] = q.small[1] = q.small[2] = 0;
    if (fine)
        small_boxes(f, reach, q.small);
#ifdef CBVH_HAVE_SIMD
    if (fine)
        for (int a = 0; a < 3; a++)
            q.small4[a] = _mm_set1_epi16((short)q.small[a]);
    cbvh_grid_range4_of(&q.grid, &q.grid4);
    cbvh_cull4_init(&q.cull4, &region->shape, region->lo, region->hi, NULL);
    float inner_lo[3], inner_hi[3];
    /* not for contacts: their box test runs for the contact anyway */
    q.inner = region->shape.kind == CBVH_SHAPE_BOX && !region->box.rotated && !sink->contacts &&
              box_inner_of(region, inner_lo, inner_hi);
    if (q.inner)
        for (int a = 0; a < 3; a++) {
            q.inner_lo[a] = lanes_set1(inner_lo[a]);
            q.inner_hi[a] = lanes_set1(inner_hi[a]);
        }
    if (q.ball) {
        q.reach2 = _mm_set1_ps(q.reach.reach2);
        for (int a = 0; a < 3; a++) {
            q.center4[a] = _mm_set1_ps(q.reach.center[a]);
            q.origin4[a] = _mm_set1_ps(f->grid_origin[a]);
            q.scale4[a] = _mm_set1_ps(f->grid_scale[a]);
        }
    }
#endif
    cbvh_shape_walk(f, f->layout, CBVH_NO_OCTANT, overlap_enter, OVERLAP_ENTER4, overlap_leaf, &q, NULL);
    return sink->reported;
}

#ifdef CBVH_OVERLAP_AVX2
/* overlap_avx2.c's instance: its exact tests are this file's, in AVX2's encoding too; the upper halves of
 * the vector registers, which a caller's AVX code may have left in use, are cleared first all the same. */
size_t cbvh_overlap_walk_avx2(const struct cbvh_file *f, const struct overlap_region *region,
                              struct overlap_sink *sink)
{
    _mm256_zeroupper();
    return overlap_walk_kernel(f, region, sink);
}
#else
/* The walk in the instruction set of the kernel chosen for the rays (cbvh_walk_kernel): AVX2's instance
 * where it runs, else this file's (SSE2, or scalar without SIMD). */
static size_t overlap_walk(const struct cbvh_file *f, const struct overlap_region *region,
                           struct overlap_sink *sink)
{
#ifdef CBVH_HAVE_AVX2
    if (cbvh_walk_kernel() == CBVH_WALK_KERNEL_AVX2)
        return cbvh_overlap_walk_avx2(f, region, sink);
#endif
    return overlap_walk_kernel(f, region, sink);
}

/* The region of a box query; 0 for an invalid box. */
static int box_region(const float box_min[3], const float box_max[3], struct overlap_region *region)
{
    memset(region, 0, sizeof *region);
    if (!box_min || !box_max || !cbvh_all_finite(box_min, 3) || !cbvh_all_finite(box_max, 3))
        return 0;
    for (int a = 0; a < 3; a++) {
        if (!(box_min[a] <= box_max[a]))
            return 0;
        region->lo[a] = box_min[a];
        region->hi[a] = box_max[a];
    }
    const cbvh_v3 lo = v3_from_f(box_min), hi = v3_from_f(box_max);
    region->shape.kind = CBVH_SHAPE_BOX;
    region->box.center = region->shape.p0 = region->shape.p1 = v3_scale(v3_add(lo, hi), 0.5);
    region->box.half = region->shape.half = v3_scale(v3_sub(hi, lo), 0.5);
    return 1;
}

CBVH_API size_t cbvh_overlap_box(const cbvh_file *file, const float box_min[3], const float box_max[3],
                                 cbvh_overlap_fn callback, void *user, uint32_t *out, size_t capacity)
{
    struct overlap_sink sink = {callback, user, out, NULL, capacity, 0, 0, 0, 0};
    struct overlap_region region;
    if (!file || !box_region(box_min, box_max, &region))
        return 0;
    return overlap_walk(file, &region, &sink);
}

/* The region of region->shape, a shape in the mesh's frame, with a box around it for node culling. */
static void shape_region(const struct cbvh_placement *placement, struct overlap_region *region)
{
    const struct cbvh_local_shape *shape = &region->shape;
    region->placement = placement;
    if (shape->kind == CBVH_SHAPE_BOX) { /* a ball or capsule has no use for it */
        region->box.center = shape->p0;
        region->box.half = shape->half;
        region->box.rotated = shape->rotated;
        memcpy(region->box.axes, shape->axes, sizeof shape->axes);
    }
    cbvh_v3 lo, hi;
    cbvh_shape_bounds(shape, &lo, &hi);
    for (int a = 0; a < 3; a++) {
        /* Rounded to float, then widened by 2^-22 relative: more than that rounding's half ulp. */
        region->lo[a] = (float)v3_get(lo, a);
        region->hi[a] = (float)v3_get(hi, a);
        region->lo[a] -= fabsf(region->lo[a]) * 0x1p-22f + 0x1p-126f;
        region->hi[a] += fabsf(region->hi[a]) * 0x1p-22f + 0x1p-126f;
    }
}

/* The region of a sphere (p1 NULL) or capsule query; 0 for invalid input. */
static int round_region(const float p0[3], const float p1[3], float radius, struct overlap_region *region)
{
    cbvh_shape in;
    memset(&in, 0, sizeof in);
    if (!p0) /* cbvh_shape_to_mesh checks the values */
        return 0;
    in.kind = p1 ? CBVH_SHAPE_CAPSULE : CBVH_SHAPE_SPHERE;
    memcpy(in.center, p0, sizeof in.center);
    memcpy(in.p0, p0, sizeof in.p0);
    memcpy(in.p1, p1 ? p1 : p0, sizeof in.p1);
    in.radius = radius;
    if (!cbvh_shape_to_mesh(&in, NULL, &region->shape))
        return 0;
    shape_region(NULL, region);
    return 1;
}

CBVH_API size_t cbvh_overlap_sphere(const cbvh_file *file, const float center[3], float radius,
                                    cbvh_overlap_fn callback, void *user, uint32_t *out, size_t capacity)
{
    struct overlap_sink sink = {callback, user, out, NULL, capacity, 0, 0, 0, 0};
    struct overlap_region region;
    if (!file || !round_region(center, NULL, radius, &region))
        return 0;
    return overlap_walk(file, &region, &sink);
}

/* The paged queries (_from, contacts): the sink skips `first` and fills ids or contacts; it looks for one
 * more when the caller asks (more not NULL) or has no output (the call then says only whether one is there).
 */
static size_t paged_walk(const struct cbvh_file *file, const struct overlap_region *region, int valid,
                         size_t first, uint32_t *ids, cbvh_contact *contacts, size_t capacity, int *more)
{
    const int output = ids || contacts;
    struct overlap_sink sink = {NULL, NULL, ids, contacts, output ? capacity : 0, 0, first, more || !output,
                                0};
    const size_t n = file && valid ? overlap_walk(file, region, &sink) : 0;
    if (more)
        *more = sink.more;
    return n;
}

CBVH_API size_t cbvh_overlap_box_from(const cbvh_file *file, const float box_min[3], const float box_max[3],
                                      size_t first, uint32_t *out, size_t capacity, int *more)
{
    struct overlap_region region;
    const int valid = box_region(box_min, box_max, &region);
    return paged_walk(file, &region, valid, first, out, NULL, capacity, more);
}

CBVH_API size_t cbvh_overlap_sphere_from(const cbvh_file *file, const float center[3], float radius,
                                         size_t first, uint32_t *out, size_t capacity, int *more)
{
    struct overlap_region region;
    const int valid = round_region(center, NULL, radius, &region);
    return paged_walk(file, &region, valid, first, out, NULL, capacity, more);
}

CBVH_API size_t cbvh_overlap_capsule(const cbvh_file *file, const float p0[3], const float p1[3],
                                     float radius, cbvh_overlap_fn callback, void *user, uint32_t *out,
                                     size_t capacity)
{
    struct overlap_sink sink = {callback, user, out, NULL, capacity, 0, 0, 0, 0};
    struct overlap_region region;
    if (!file || !p1 || !round_region(p0, p1, radius, &region))
        return 0;
    return overlap_walk(file, &region, &sink);
}

CBVH_API size_t cbvh_overlap_capsule_from(const cbvh_file *file, const float p0[3], const float p1[3],
                                          float radius, size_t first, uint32_t *out, size_t capacity,
                                          int *more)
{
    struct overlap_region region;
    const int valid = p1 && round_region(p0, p1, radius, &region);
    return paged_walk(file, &region, valid, first, out, NULL, capacity, more);
}

CBVH_API size_t cbvh_contacts_sphere(const cbvh_file *file, const float center[3], float radius, size_t first,
                                     cbvh_contact *out, size_t capacity, int *more)
{
    struct overlap_region region;
    const int valid = round_region(center, NULL, radius, &region);
    return paged_walk(file, &region, valid, first, NULL, out, capacity, more);
}

CBVH_API size_t cbvh_contacts_capsule(const cbvh_file *file, const float p0[3], const float p1[3],
                                      float radius, size_t first, cbvh_contact *out, size_t capacity,
                                      int *more)
{
    struct overlap_region region;
    const int valid = p1 && round_region(p0, p1, radius, &region);
    return paged_walk(file, &region, valid, first, NULL, out, capacity, more);
}

/* The region of a query with options: options checked (overlaps take no culling and no filter), the shape
 * taken into the mesh's frame by the transform, whose placement *placement holds for the contacts. */
static cbvh_result region_with(const cbvh_file *file, const cbvh_shape *shape,
                               const cbvh_query_options *options, struct cbvh_placement *placement,
                               struct overlap_region *region)
{
    cbvh_query_options o;
    const struct cbvh_placement *p;
    if (!file || !shape || cbvh_query_options_read(options, &o) != CBVH_OK || o.cull != CBVH_CULL_NONE ||
        o.filter || !cbvh_placement_of_option(o.transform, placement, &p) ||
        !cbvh_shape_to_mesh(shape, p, &region->shape))
        return CBVH_ERROR_INVALID_ARGUMENT;
    shape_region(p, region);
    return CBVH_OK;
}

/* The paged walk of a query with options, into ids or contacts. */
static cbvh_result paged_with(const cbvh_file *file, const cbvh_shape *shape,
                              const cbvh_query_options *options, size_t first, uint32_t *ids,
                              cbvh_contact *contacts, size_t capacity, size_t *count, int *more)
{
    if (more)
        *more = 0;
    if (!count)
        return CBVH_ERROR_INVALID_ARGUMENT;
    struct cbvh_placement placement;
    struct overlap_region region;
    const cbvh_result r = region_with(file, shape, options, &placement, &region);
    *count = paged_walk(file, &region, r == CBVH_OK, first, ids, contacts, capacity, more);
    return r;
}

CBVH_API cbvh_result cbvh_overlap_with(const cbvh_file *file, const cbvh_shape *shape,
                                       const cbvh_query_options *options, size_t first, uint32_t *out,
                                       size_t capacity, size_t *count, int *more)
{
    return paged_with(file, shape, options, first, out, NULL, capacity, count, more);
}

CBVH_API cbvh_result cbvh_contacts_with(const cbvh_file *file, const cbvh_shape *shape,
                                        const cbvh_query_options *options, size_t first, cbvh_contact *out,
                                        size_t capacity, size_t *count, int *more)
{
    return paged_with(file, shape, options, first, NULL, out, capacity, count, more);
}
#endif
