/* sweep_walk_kernel.h: the sweeps' tree walk, node and leaf tests and the shapes' exact triangle tests,
 * compiled once per instruction set (sweep_walk.c: scalar and SSE2; sweep_walk_avx2.c: AVX2). Include it in
 * one .c file each. */
#ifndef CBVH_QUERY_SWEEP_WALK_KERNEL_H
#define CBVH_QUERY_SWEEP_WALK_KERNEL_H

#include <float.h>
#include <math.h>

#include "query/grown_path.h"
#include "query/lanes.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/shape.h"
#include "query/shape_cull.h"
#include "query/shape_leaf.h"
#include "query/sweep_box.h"
#include "query/sweep_capsule.h"
#include "query/sweep_sphere.h"
#include "query/sweep_walk.h"
#include "query/triangle_frame.h"
#include "query/walk.h"

/* A sweep as the shape walk sees it: the path of its float box (cbvh_sweep_bounds), and the shape as its
 * kind's exact test takes it (bounds->kind says which). */
struct sweep_query {
    const struct cbvh_file *f;
    const float *delta;
    struct cbvh_grown_path path;
    union {
        struct sphere_shape sphere;
        struct capsule_shape capsule;
        struct box_shape box;
    } shape;
    const struct cbvh_local_shape *bounds;
    const struct cbvh_sweep_rules *rules;
    struct cbvh_sweep_contact best;
    uint32_t best_tri;
    float limit; /* best.t as the box tests read it */
#ifdef CBVH_HAVE_SIMD
    struct cbvh_cull4 cull; /* the swept shape in every lane */
#endif
};

/* A node box: the path of the shape's box crosses it before the best contact. */
static int sweep_enter(void *query, const uint32_t grid[6], float *entry)
{
    const struct sweep_query *q = query;
    return cbvh_grown_path_grid(&q->path, q->f, grid, q->limit, entry);
}

/* Culling by the motion: the sign of delta . n, n the face normal as wound; parallel or no motion keeps it.
 */
static int culled(cbvh_cull cull, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const float delta[3])
{
    const double s = v3_dot(v3_cross(v3_sub(b, a), v3_sub(c, a)), v3_from_f(delta));
    return (cull == CBVH_CULL_BACK && s > 0.0) || (cull == CBVH_CULL_FRONT && s < 0.0);
}

/* Sweeps one triangle with the shape's exact test, called directly so that it compiles in the walk's
 * instruction set and may inline: first contact with t in [0, tmax] (t = 0 when the shape already overlaps
 * the triangle). clear_at_start: 1 when the shape at t = 0 is known clear of the triangle
 * (cbvh_cull_triangle), so a test may skip its overlap test. Returns 1 and fills *out on contact. */
CBVH_FORCE_INLINE int sweep_shape_triangle(const struct sweep_query *q, cbvh_v3 a, cbvh_v3 b, cbvh_v3 c,
                                           double tmax, int clear_at_start, struct cbvh_sweep_contact *out)
{
    switch (q->bounds->kind) {
    case CBVH_SHAPE_SPHERE:
        return sphere_triangle(&q->shape.sphere, a, b, c, tmax, clear_at_start, out);
    case CBVH_SHAPE_CAPSULE:
        return capsule_triangle(&q->shape.capsule, a, b, c, tmax, clear_at_start, out);
    default:
        return box_triangle(&q->shape.box, a, b, c, tmax, clear_at_start, out);
    }
}

/* The filter's verdict on cooked triangle k, whose contact would win: its record with the barycentrics of
 * the contact point (in the triangle's best-conditioned frame, as the hit records' normals). */
CBVH_COLD static int ask_filter(const struct sweep_query *q, uint32_t k, const cbvh_v3 v[3],
                                const struct cbvh_sweep_contact *c)
{
    struct cbvh_triangle_frame fr;
    cbvh_triangle_frame_of(v, &fr);
    float u = 0.0f, w = 0.0f; /* vertex 0 for a triangle of no area */
    if (fr.nn > 0.0) {
        double x, y;
        cbvh_triangle_frame_barycentrics(&fr, v3_sub(c->point, v[fr.base]), &x, &y);
        cbvh_frame_uv(fr.base, x, y, &u, &w);
    }
    cbvh_hit_record r;
    static const struct cbvh_t_frame identity = {0.0, 1.0};
    cbvh_hit_record_fill(q->f, k, &identity, (float)c->t, u, w, q->delta, &r);
    if (q->rules->placement)
        v3_to_f(cbvh_rotate(q->rules->placement->rotation, v3_from_f(r.normal)), r.normal);
    return q->rules->filter(q->rules->user, &r);
}

/* Cooked triangle k: its box (unless it passed cbvh_grown_path_box at the current limit: box_passed_at, NAN
 * when untested; the limit only shrinks), the motion's culling, the cheap tests (unless the float cull found
 * the shape clear of it at t = 0 over a motion at least as long, clear_at_start: then they would find it
 * CBVH_CULL_CLEAR_AT_START, or CBVH_CULL_CLEAR where the sweep finds no contact either), the sweep, and the
 * filter when its contact would win. A contact at t = 0 is beaten by none of a higher index: those are
 * skipped. Returns 1 when the filter stops the walk. */
CBVH_FORCE_INLINE int sweep_triangle(struct sweep_query *q, uint32_t k, const float a[3], const float b[3],
                                     const float cc[3], float box_passed_at, int clear_at_start)
{
    const struct cbvh_sweep_rules *rules = q->rules;
    if (q->best.t == 0.0 && k > q->best_tri)
        return 0;
    if (!(q->limit == box_passed_at)) {
        float lo[3], hi[3], entry;
        cbvh_triangle_bounds(a, b, cc, lo, hi);
        if (!cbvh_grown_path_box(&q->path, lo, hi, q->limit, &entry))
            return 0;
    }
    const cbvh_v3 v[3] = {v3_from_f(a), v3_from_f(b), v3_from_f(cc)};
    if (rules && rules->cull != CBVH_CULL_NONE && culled(rules->cull, v[0], v[1], v[2], q->delta))
        return 0;
    const enum cbvh_cull_verdict cull =
        clear_at_start ? CBVH_CULL_CLEAR_AT_START
                       : cbvh_cull_triangle(q->bounds, v3_from_f(q->delta), q->best.t, v[0], v[1], v[2], 0);
    if (cull == CBVH_CULL_CLEAR)
        return 0;
    struct cbvh_sweep_contact c = {0.0, {0, 0, 0}, {0, 0, 0}, 0.0};
    if (!sweep_shape_triangle(q, v[0], v[1], v[2], q->best.t, cull == CBVH_CULL_CLEAR_AT_START, &c) ||
        !(c.t < q->best.t || (c.t == q->best.t && k < q->best_tri)))
        return 0;
    const int verdict = rules && rules->filter ? ask_filter(q, k, v, &c) : CBVH_FILTER_ACCEPT;
    if (verdict == CBVH_FILTER_REJECT)
        return 0;
    q->best = c; /* c.depth stays 0 unless the kernel found an overlap at t = 0 */
    q->best_tri = k;
    q->limit = (float)c.t;
    return verdict == CBVH_FILTER_STOP;
}

#ifdef CBVH_HAVE_SIMD
/* sweep_enter on the four slots of wide node `node` at once (cbvh_grown_path_node4: the same boxes with the
 * same keys). */
static uint32_t sweep_enter4(void *query, const uint8_t *node, float entry[4])
{
    const struct sweep_query *q = query;
    return cbvh_grown_path_node4(&q->path, node, q->limit, entry);
}

/* The CBVH_LANES triangles of group g from cooked triangle k through their box test
 * (cbvh_grown_path_triangle_lanes: exactly the triangles cbvh_grown_path_box keeps with the limit at the
 * time, so sweep_triangle tests a kept one's box again only once the limit shrank) and the float cull
 * (cbvh_cull_sweep_lanes, over the motion up to the best contact so far: limit, rounded from best.t, times
 * 1 + 2^-22 is at least best.t, which also tells the kept ones clear of the shape at t = 0), the kept ones
 * in order through the rest. */
CBVH_NOINLINE int sweep_group(void *query, uint32_t k, const struct leaf_group *g)
{
    struct sweep_query *q = query;
    const float box_limit = q->limit;
    cbvh_lanes c[3][3];
    cbvh_group_corners(g, c);
    uint32_t keep = cbvh_grown_path_triangle_lanes(&q->path, c, box_limit) & g->mask;
    if (!keep)
        return 0;
    uint32_t clear_at_start;
    keep &= cbvh_cull_sweep_lanes(&q->cull, c, box_limit * 0x1.000004p0f, &clear_at_start);
    for (; keep; keep &= keep - 1u) {
        const uint32_t j = lanes_lowest(keep);
        float a[3], b[3], cc[3];
        cbvh_group_triangle(g, j, a, b, cc);
        if (sweep_triangle(q, k + j, a, b, cc, box_limit, clear_at_start >> j & 1u))
            return 1;
    }
    return 0;
}

/* The leaf's triangles a group at a time through sweep_group. */
static int sweep_leaf_lanes(void *query, uint32_t first, uint32_t count)
{
    return cbvh_shape_leaf_groups(((const struct sweep_query *)query)->f, first, count, sweep_group, query);
}
#endif

/* The leaf's triangles one at a time (the scalar kernel). */
static int sweep_leaf_one(void *query, uint32_t first, uint32_t count)
{
    struct sweep_query *q = query;
    for (uint32_t k = first; k < first + count; k++) {
        float a[3], b[3], c[3];
        cbvh_triangle_vertices(q->f, k, a, b, c);
        if (sweep_triangle(q, k, a, b, c, NAN, 0))
            return 1;
    }
    return 0;
}

/* cbvh_sweep_walk in the including file's instruction set: with `lanes` (SIMD builds only), wide nodes'
 * slots four at once and leaf triangles CBVH_LANES at a time through the float culls; else one at a time.
 * The answers are the same either way, bit for bit. */
CBVH_FORCE_INLINE int sweep_walk_kernel(const struct cbvh_file *f, const struct cbvh_local_shape *bounds,
                                        const float delta[3], const struct cbvh_sweep_rules *rules,
                                        struct cbvh_sweep_found *found, const int lanes)
{
    cbvh_v3 lo, hi;
    float center[3], extent[3];
    cbvh_shape_bounds(bounds, &lo, &hi);
    cbvh_sweep_bounds(lo, hi, center, extent);
    struct sweep_query q = {.f = f,
                            .delta = delta,
                            .bounds = bounds,
                            .rules = rules,
                            .best = {1.0, {0, 0, 0}, {0, 0, 0}, 0.0},
                            .best_tri = UINT32_MAX,
                            .limit = 1.0f};
    if (bounds->kind == CBVH_SHAPE_SPHERE)
        sphere_shape_init(&q.shape.sphere, bounds, delta);
    else if (bounds->kind == CBVH_SHAPE_CAPSULE)
        capsule_shape_init(&q.shape.capsule, bounds, delta);
    else
        box_shape_init(&q.shape.box, bounds, delta);
    cbvh_grown_path_init(&q.path, f, center, extent, delta);
#ifdef CBVH_HAVE_SIMD
    if (lanes) {
        cbvh_cull4_init(&q.cull, bounds, NULL, NULL, delta);
        cbvh_shape_walk(f, f->layout, q.path.octant, sweep_enter, sweep_enter4, sweep_leaf_lanes, &q,
                        &q.limit);
    } else
#else
    (void)lanes;
#endif
        cbvh_shape_walk(f, f->layout, q.path.octant, sweep_enter, NULL, sweep_leaf_one, &q, &q.limit);
    found->tri = q.best_tri;
    found->contact = q.best;
    found->contact.normal = v3_normalize(q.best.normal);
    return q.best_tri != UINT32_MAX;
}

#endif
