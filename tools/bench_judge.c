/* bench_judge.c: whom the double-precision reference sides with where cbvh and a peer answer a shape query
 * differently. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench_judge.h"

int bench_judge_init(bench_judge *j, const cbvh_file *file, uint32_t id_count, double overlap_tolerance,
                     double sweep_tolerance)
{
    memset(j, 0, sizeof *j);
    j->id_count = id_count;
    j->overlap_tolerance = overlap_tolerance;
    j->sweep_tolerance = sweep_tolerance;
    j->reported[0] = calloc((size_t)id_count + 1, 1);
    j->reported[1] = calloc((size_t)id_count + 1, 1);
    if (!j->reported[0] || !j->reported[1] || !ref_tris_from_file(file, id_count, &j->tris)) {
        bench_judge_free(j);
        return 0;
    }
    return 1;
}

void bench_judge_free(bench_judge *j)
{
    ref_tris_free(&j->tris);
    free(j->reported[0]);
    free(j->reported[1]);
    j->reported[0] = j->reported[1] = NULL;
}

void bench_judge_mark(bench_judge *j, int side, uint32_t tri)
{
    if (tri < j->id_count)
        j->reported[side][tri] = 1;
}

static bench_side side_of(int cbvh_right, int peer_right)
{
    return cbvh_right ? (peer_right ? BENCH_SIDE_BOTH : BENCH_SIDE_CBVH)
                      : (peer_right ? BENCH_SIDE_PEER : BENCH_SIDE_NEITHER);
}

/* The query's shape for the reference, its size shrunk by `shrink` (not below 0). */
static ref_shape reference_shape(shape_kind kind, const shape_query *q, double shrink)
{
    ref_shape s;
    memset(&s, 0, sizeof s);
    const int box = kind == SHAPE_BOX || kind == SHAPE_ORIENTED_BOX;
    s.kind = kind == SHAPE_SPHERE ? REF_SPHERE : kind == SHAPE_CAPSULE ? REF_CAPSULE : REF_BOX;
    for (int a = 0; a < 3; a++) {
        s.p0[a] = q->p0[a];
        s.p1[a] = q->p1[a];
        s.half[a] = box ? fmax(0.0, q->size[a] - shrink) : 0.0;
    }
    s.radius = box ? 0.0 : fmax(0.0, q->size[0] - shrink);
    s.rotated = kind == SHAPE_ORIENTED_BOX;
    if (s.rotated)
        shape_query_axes(q, s.axes);
    return s;
}

/* A box around the shape grown by `grow`: triangles outside it are surely apart. */
static void shape_bounds(const ref_shape *s, double grow, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) {
        const double reach = s->kind == REF_BOX ? s->half[a] : s->radius;
        lo[a] = fmin(s->p0[a], s->p1[a]) - reach - grow;
        hi[a] = fmax(s->p0[a], s->p1[a]) + reach + grow;
    }
}

/* ref_*_class of triangle tri for the still shape s. */
static int overlap_class(const ref_shape *s, const double tri[9], double tol)
{
    if (s->kind == REF_SPHERE)
        return ref_sphere_class(tri, s->p0, s->radius, tol);
    if (s->kind == REF_CAPSULE)
        return ref_capsule_class(tri, s->p0, s->p1, s->radius, tol);
    double lo[3], hi[3];
    shape_bounds(s, 0.0, lo, hi);
    return ref_box_class(tri, lo, hi, tol);
}

/* overlap_class, 0 without the test for a triangle outside [lo, hi] (the shape's bounds grown by more than
 * tol). */
static int bounded_class(const ref_shape *s, const double tri[9], const double lo[3], const double hi[3],
                         double tol)
{
    for (int a = 0; a < 3; a++)
        if (fmin(tri[a], fmin(tri[3 + a], tri[6 + a])) > hi[a] ||
            fmax(tri[a], fmax(tri[3 + a], tri[6 + a])) < lo[a])
            return 0;
    return overlap_class(s, tri, tol);
}

bench_side bench_judge_overlap(bench_judge *j, shape_kind kind, const shape_query *q)
{
    const double tol = j->overlap_tolerance;
    const ref_shape s = reference_shape(kind, q, 0.0);
    double lo[3], hi[3];
    shape_bounds(&s, 2.0 * tol, lo, hi);
    int right[2] = {1, 1};
    for (size_t k = 0; k < j->tris.count; k++) {
        const int cls = bounded_class(&s, j->tris.v + 9 * k, lo, hi, tol);
        const uint32_t id = j->tris.id[k];
        for (int e = 0; e < 2; e++) {
            const int got = j->reported[e][id];
            right[e] &= !((cls == 2 && !got) || (cls == 0 && got));
            j->reported[e][id] = 0;
        }
    }
    return side_of(right[0], right[1]);
}

/* Whether a closest hit (tri, t) is borne out, given sure: the reference's closest triangle surely crossed.
 */
static int ray_hit_right(const bench_judge *j, const cbvh_ray *ray, const cbvh_hit *h,
                         const ref_ray_hit *sure)
{
    const double tol = j->overlap_tolerance;
    if (h->tri == CBVH_NO_HIT)
        return sure->index == (size_t)-1;
    const double len = sqrt((double)ray->dir[0] * ray->dir[0] + (double)ray->dir[1] * ray->dir[1] +
                            (double)ray->dir[2] * ray->dir[2]);
    if (sure->index != (size_t)-1 && (h->t - sure->t) * len > tol)
        return 0;
    for (size_t k = 0; k < j->tris.count; k++)
        if (j->tris.id[k] == h->tri) {
            double t, u, v, margin;
            return ref_ray_triangle(j->tris.v + 9 * k, ray, &t, &u, &v, &margin) && margin >= -tol &&
                   fabs(t - (double)h->t) * len <= tol;
        }
    return 0;
}

bench_side bench_judge_ray(const bench_judge *j, const cbvh_ray *ray, const cbvh_hit *cbvh,
                           const cbvh_hit *peer)
{
    ref_ray_hit sure;
    ref_ray_closest(&j->tris, ray, -j->overlap_tolerance, &sure);
    return side_of(ray_hit_right(j, ray, cbvh, &sure), ray_hit_right(j, ray, peer, &sure));
}

bench_side bench_judge_occluded(const bench_judge *j, const cbvh_ray *ray, int cbvh, int peer)
{
    ref_ray_hit sure, loose;
    const int surely = ref_ray_closest(&j->tris, ray, -j->overlap_tolerance, &sure),
              maybe = ref_ray_closest(&j->tris, ray, j->overlap_tolerance, &loose);
    return side_of(cbvh ? maybe : !surely, peer ? maybe : !surely);
}

bench_side bench_judge_first_hit(const bench_judge *j, shape_kind kind, const shape_query *q,
                                 const shape_answer *cbvh, const shape_answer *peer)
{
    const double tol = j->overlap_tolerance;
    const ref_shape s = reference_shape(kind, q, 0.0);
    double lo[3], hi[3];
    shape_bounds(&s, 2.0 * tol, lo, hi);
    const shape_answer *answers[2] = {cbvh, peer};
    int any_sure = 0, right[2] = {answers[0]->count == 0, answers[1]->count == 0};
    for (size_t k = 0; k < j->tris.count; k++) {
        const int cls = bounded_class(&s, j->tris.v + 9 * k, lo, hi, tol);
        any_sure |= cls == 2;
        for (int e = 0; e < 2; e++)
            if (answers[e]->count > 0 && answers[e]->tri == j->tris.id[k] && cls > 0)
                right[e] = 1;
    }
    for (int e = 0; e < 2; e++)
        if (answers[e]->count == 0)
            right[e] = !any_sure;
    return side_of(right[0], right[1]);
}

/* Whether a sweep's answer a is borne out by the reference's first contacts of the shape (ref) and of the
 * shape shrunk by the overlap tolerance (shrunk). */
static int sweep_right(const bench_judge *j, const ref_shape *s, const double delta[3], double length,
                       const ref_sweep_hit *ref, const ref_sweep_hit *shrunk, const shape_answer *a)
{
    if (a->tri == CBVH_NO_HIT)
        return shrunk->index == (size_t)-1;
    if (ref->index != (size_t)-1)
        return a->tri == ref->tri || fabs((double)a->t - ref->t) * length <= j->sweep_tolerance;
    for (size_t k = 0; k < j->tris.count; k++) /* a grazing contact: the shape touches that triangle at t */
        if (j->tris.id[k] == a->tri)
            return ref_shape_triangle_dist(s, delta, a->t, j->tris.v + 9 * k) <= j->overlap_tolerance;
    return 0;
}

bench_side bench_judge_sweep(const bench_judge *j, shape_kind kind, const shape_query *q,
                             const shape_answer *cbvh, const shape_answer *peer)
{
    const double delta[3] = {q->delta[0], q->delta[1], q->delta[2]};
    const double length = sqrt(delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]);
    const double touch = 1e-3 * j->overlap_tolerance; /* ref_sweep's distance that counts as contact */
    const ref_shape s = reference_shape(kind, q, 0.0), small = reference_shape(kind, q, j->overlap_tolerance);
    ref_sweep_hit ref, shrunk;
    ref_sweep(&j->tris, &s, delta, touch, &ref);
    ref_sweep(&j->tris, &small, delta, touch, &shrunk);
    return side_of(sweep_right(j, &s, delta, length, &ref, &shrunk, cbvh),
                   sweep_right(j, &s, delta, length, &ref, &shrunk, peer));
}
