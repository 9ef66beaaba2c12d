/* sweep_walk.c: the tree walk shared by the sphere, capsule and box sweeps, and their common helpers. */
#include "config.h"

#include <float.h>
#include <math.h>

#include "query/grown_path.h"
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/sweep_walk.h"
#include "query/shape.h"
#include "query/shape_cull.h"
#include "query/walk.h"
#include "query/triangle_frame.h"

/* A sweep as the shape walk sees it: the path of its float box (cbvh_sweep_bounds). */
struct sweep_query {
    const struct cbvh_file *f;
    const float *delta;
    struct cbvh_grown_path path;
    cbvh_sweep_triangle_fn sweep;
    const void *shape;
    const struct cbvh_local_shape *bounds;
    const struct cbvh_sweep_rules *rules;
    struct cbvh_sweep_contact best;
    uint32_t best_tri;
    float limit; /* best.t as the box tests read it */
#ifdef CBVH_HAVE_SIMD
    struct cbvh_cull4 cull4;
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
static int sweep_triangle(struct sweep_query *q, uint32_t k, const float a[3], const float b[3],
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
    if (!q->sweep(q->shape, v[0], v[1], v[2], q->best.t, cull == CBVH_CULL_CLEAR_AT_START, &c) ||
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
#define SWEEP_ENTER4 sweep_enter4

/* Four triangles through their box test (cbvh_grown_path_triangles4: exactly the triangles
 * cbvh_grown_path_box keeps with the limit at the time, so sweep_triangle tests a kept one's box again only
 * once the limit shrank) and the float
 * cull (cbvh_cull4_sweep, over the motion up to the best contact so far: limit, rounded from best.t, times
 * 1 + 2^-22 is at least best.t, which also tells the kept ones clear of the shape at t = 0), the kept ones
 * in order through the rest. */
static int sweep_quad(void *query, uint32_t k, const struct leaf_quad *t, uint32_t group)
{
    struct sweep_query *q = query;
    const float box_limit = q->limit;
    uint32_t keep = cbvh_grown_path_triangles4(&q->path, t, box_limit) & group;
    if (!keep)
        return 0;
    uint32_t clear_at_start;
    keep &= cbvh_cull4_sweep(&q->cull4, t->c, box_limit * 0x1.000004p0f, &clear_at_start);
    for (; keep; keep &= keep - 1u) {
        const uint32_t j = cbvh_lowest_lane(keep);
        const float a[3] = {t->c[0][0][j], t->c[0][1][j], t->c[0][2][j]};
        const float b[3] = {t->c[1][0][j], t->c[1][1][j], t->c[1][2][j]};
        const float c[3] = {t->c[2][0][j], t->c[2][1][j], t->c[2][2][j]};
        if (sweep_triangle(q, k + j, a, b, c, box_limit, clear_at_start >> j & 1u))
            return 1;
    }
    return 0;
}
#else
#define SWEEP_ENTER4 NULL
#endif

/* With SIMD, four triangles at a time (sweep_quad); else one at a time. */
static int sweep_leaf(void *query, uint32_t first, uint32_t count)
{
    struct sweep_query *q = query;
#ifdef CBVH_HAVE_SIMD
    return cbvh_shape_leaf_quads(q->f, first, count, sweep_quad, q);
#else
    for (uint32_t k = first; k < first + count; k++) {
        float a[3], b[3], c[3];
        cbvh_triangle_vertices(q->f, k, a, b, c);
        if (sweep_triangle(q, k, a, b, c, NAN, 0))
            return 1;
    }
    return 0;
#endif
}

int cbvh_sweep_walk(const struct cbvh_file *f, const struct cbvh_local_shape *bounds, const float delta[3],
                    cbvh_sweep_triangle_fn sweep, const void *shape, const struct cbvh_sweep_rules *rules,
                    struct cbvh_sweep_found *found)
{
    cbvh_vector_state_clear();
    cbvh_v3 lo, hi;
    float center[3], extent[3];
    cbvh_shape_bounds(bounds, &lo, &hi);
    cbvh_sweep_bounds(lo, hi, center, extent);
    struct sweep_query q = {.f = f,
                            .delta = delta,
                            .sweep = sweep,
                            .shape = shape,
                            .bounds = bounds,
                            .rules = rules,
                            .best = {1.0, {0, 0, 0}, {0, 0, 0}, 0.0},
                            .best_tri = UINT32_MAX,
                            .limit = 1.0f};
    cbvh_grown_path_init(&q.path, f, center, extent, delta);
#ifdef CBVH_HAVE_SIMD
    cbvh_cull4_init(&q.cull4, bounds, NULL, NULL, delta);
#endif
    cbvh_shape_walk(f, f->layout, q.path.octant, sweep_enter, SWEEP_ENTER4, sweep_leaf, &q, &q.limit);
    found->tri = q.best_tri;
    found->contact = q.best;
    found->contact.normal = v3_normalize(q.best.normal);
    return q.best_tri != UINT32_MAX;
}

void cbvh_sweep_bounds(cbvh_v3 lo, cbvh_v3 hi, float center[3], float extent[3])
{
    for (int a = 0; a < 3; a++) {
        const double l = v3_get(lo, a), h = v3_get(hi, a);
        center[a] = (float)(0.5 * (l + h));
        const double above = h - center[a], below = center[a] - l, e = above > below ? above : below;
        float ef = (float)e;
        if ((double)ef < e)
            ef = nextafterf(ef, INFINITY);
        extent[a] = ef;
    }
}

int cbvh_sweep_as_ray(const struct cbvh_file *f, const float center[3], const float delta[3],
                      const struct cbvh_sweep_rules *rules, struct cbvh_sweep_found *found)
{
    const cbvh_ray ray = {{center[0], center[1], center[2]}, 0.0f, {delta[0], delta[1], delta[2]}, 1.0f};
    struct cbvh_ray_ctx ctx;
    struct cbvh_hit_gate gate;
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    found->tri = UINT32_MAX;
    if (!cbvh_ray_prepare(&ctx, &ray, f, NULL))
        return 0;
    if (rules && (rules->cull != CBVH_CULL_NONE || rules->filter)) {
        cbvh_hit_gate_init(&gate, rules->cull, rules->filter, rules->user,
                           rules->placement ? rules->placement->rotation : NULL, delta, &ctx.t_frame);
        ctx.gate = &gate;
    }
    cbvh_closest(f, &ctx, CBVH_TRAVERSAL_SORTED, &best, NULL);
    if (best.tri == UINT32_MAX)
        return 0;
    float a[3], b[3], c[3];
    cbvh_triangle_vertices(f, best.tri, a, b, c);
    const cbvh_v3 va = v3_from_f(a), vb = v3_from_f(b), vc = v3_from_f(c);
    found->tri = best.tri;
    found->contact.t = cbvh_t_frame_out(&ctx.t_frame, best.t);
    found->contact.point =
        v3_madd(v3_madd(v3_scale(va, 1.0 - (double)best.u - (double)best.v), vb, best.u), vc, best.v);
    found->contact.normal = cbvh_fallback_normal(va, vb, vc, v3_from_f(delta));
    found->contact.depth = 0.0;
    return 1;
}
