/* test_posed.c: queries with options on any shape (cbvh_sweep_with, cbvh_overlap_with, cbvh_contacts_with):
 * oriented boxes, placed meshes, depth, culling and filters, against the double-precision reference. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cbvh.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

static double rnd(uint64_t *st, double lo, double hi)
{
    return lo + (hi - lo) * scene_rand_unit(st);
}

/* A placement as the test sees it: world = translation + scale * R local, R from the quaternion as given
 * (floats), normalized here in double, written out independently of the library's own conversion. */
typedef struct pose {
    cbvh_transform t;
    double r[3][3];
} pose;

static void quaternion_matrix(const float q[4], double m[3][3])
{
    const double n =
        sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3]);
    const double x = q[0] / n, y = q[1] / n, z = q[2] / n, w = q[3] / n;
    const double rows[3][3] = {{w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)},
                               {2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)},
                               {2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z}};
    memcpy(m, rows, sizeof rows);
}

static void random_quaternion(uint64_t *st, float q[4])
{
    for (int k = 0; k < 4; k++)
        q[k] = (float)rnd(st, -1.0, 1.0);
}

static void random_pose(uint64_t *st, pose *p)
{
    random_quaternion(st, p->t.rotation);
    for (int a = 0; a < 3; a++)
        p->t.translation[a] = (float)rnd(st, -50.0, 50.0);
    p->t.scale = (float)rnd(st, 0.4, 3.0);
    quaternion_matrix(p->t.rotation, p->r);
}

static void pose_point(const pose *p, const double in[3], double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] =
            p->t.translation[i] + p->t.scale * (p->r[i][0] * in[0] + p->r[i][1] * in[1] + p->r[i][2] * in[2]);
}

/* The fixture's triangles placed by p (p NULL: as they are). */
static void placed_tris(const ref_fixture *fx, const pose *p, ref_tris *out)
{
    out->count = fx->tris.count;
    out->v = malloc(9 * out->count * sizeof *out->v);
    out->id = malloc(out->count * sizeof *out->id);
    assert_non_null(out->v);
    assert_non_null(out->id);
    memcpy(out->id, fx->tris.id, out->count * sizeof *out->id);
    for (size_t k = 0; k < 3 * out->count; k++) {
        if (p)
            pose_point(p, fx->tris.v + 3 * k, out->v + 3 * k);
        else
            memcpy(out->v + 3 * k, fx->tris.v + 3 * k, 3 * sizeof *out->v);
    }
}

/* The triangles of `all` that `keep` accepts (a reference for culled and filtered queries). */
static void subset_tris(const ref_tris *all, int (*keep)(const double *tri, uint32_t id, const void *ctx),
                        const void *ctx, ref_tris *out)
{
    out->v = malloc(9 * all->count * sizeof *out->v + 1);
    out->id = malloc(all->count * sizeof *out->id + 1);
    assert_non_null(out->v);
    assert_non_null(out->id);
    out->count = 0;
    for (size_t k = 0; k < all->count; k++) {
        if (!keep(all->v + 9 * k, all->id[k], ctx))
            continue;
        memcpy(out->v + 9 * out->count, all->v + 9 * k, 9 * sizeof *out->v);
        out->id[out->count++] = all->id[k];
    }
}

static void free_tris(ref_tris *t)
{
    free(t->v);
    free(t->id);
}

/* A random shape of `kind` near bounds [lo, hi] (diagonal d) moving by about a third of d, often straight
 * at a triangle of `tris`; boxes turned when `turn`. Fills the library's shape and the reference's, which
 * see the same floats. */
static void random_shape(uint64_t *st, const ref_tris *tris, const double lo[3], const double hi[3], double d,
                         cbvh_shape_kind kind, int turn, cbvh_shape *s, ref_shape *r, float delta[3])
{
    memset(s, 0, sizeof *s);
    memset(r, 0, sizeof *r);
    s->kind = kind;
    r->kind = kind == CBVH_SHAPE_SPHERE ? REF_SPHERE : kind == CBVH_SHAPE_CAPSULE ? REF_CAPSULE : REF_BOX;
    const double *tri = tris->v + 9 * (size_t)(scene_rand_unit(st) * (double)tris->count);
    const int aimed = scene_rand_next(st) % 3 != 0;
    for (int a = 0; a < 3; a++) {
        s->center[a] = (float)rnd(st, lo[a] - 0.2 * d, hi[a] + 0.2 * d);
        const double target = (tri[a] + tri[3 + a] + tri[6 + a]) / 3.0;
        delta[a] = aimed ? (float)(1.3 * (target - s->center[a])) : (float)rnd(st, -0.4 * d, 0.4 * d);
        s->p0[a] = s->center[a];
        s->p1[a] = (float)(s->center[a] + rnd(st, -0.08 * d, 0.08 * d));
        s->half_extent[a] = (float)rnd(st, 0.002 * d, 0.05 * d);
        r->p0[a] = s->center[a];
        r->p1[a] = kind == CBVH_SHAPE_CAPSULE ? s->p1[a] : s->center[a];
        r->half[a] = s->half_extent[a];
    }
    s->radius = (float)rnd(st, 0.002 * d, 0.05 * d);
    r->radius = kind == CBVH_SHAPE_BOX ? 0.0 : s->radius;
    if (kind == CBVH_SHAPE_BOX && turn) {
        random_quaternion(st, s->rotation);
        quaternion_matrix(s->rotation, r->axes);
        r->rotated = 1;
    }
}

/* The reference shape moved by s * dir. */
static ref_shape moved(const ref_shape *r, const double dir[3], double s)
{
    ref_shape m = *r;
    for (int a = 0; a < 3; a++) {
        m.p0[a] += s * dir[a];
        m.p1[a] += s * dir[a];
    }
    return m;
}

static const double *tri_of(const ref_tris *tris, uint32_t id)
{
    for (size_t k = 0; k < tris->count; k++)
        if (tris->id[k] == id)
            return tris->v + 9 * k;
    fail_msg("triangle %u is not in the reference", id);
    return NULL;
}

/* A sweep record against the reference sweep over `tris` (the frame the record is in, diagonal d): same hit
 * or miss, t within tolerance, the shape touching the reported triangle at t, the point on it, a unit
 * normal; at t = 0 the depth separates: moved by depth + tol along the normal the shape is clear. */
static void check_record(const ref_tris *tris, double d, const ref_shape *r, const float delta[3],
                         const cbvh_sweep_record *h)
{
    const double dd[3] = {delta[0], delta[1], delta[2]};
    const double tol = 2e-5 * d, dlen = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
    const double tol_t = dlen > 0.0 ? 3e-5 * d / dlen + 1e-6 : 0.0;
    ref_sweep_hit ref;
    const int rh = ref_sweep(tris, r, dd, 1e-9 * d, &ref);
    const int kh = h->tri != CBVH_NO_HIT;
    if (rh != kh)
        fail_msg("shape %d: kernel %s (t %.9g tri %u), reference %s (t %.9g tri %u)", (int)r->kind,
                 kh ? "hit" : "miss", h->t, h->tri, rh ? "hit" : "miss", ref.t, ref.tri);
    if (!kh)
        return;
    if (!(h->t >= ref.t - tol_t && h->t <= ref.t + tol_t))
        fail_msg("shape %d: kernel t %.9g (tri %u), reference %.9g (tri %u)", (int)r->kind, h->t, h->tri,
                 ref.t, ref.tri);
    const double *tri = tri_of(tris, h->tri);
    const double gap = ref_shape_triangle_dist(r, dd, h->t, tri);
    if (!(gap <= tol))
        fail_msg("shape %d: at t %.9g the shape is %g from tri %u", (int)r->kind, h->t, gap, h->tri);
    const double p[3] = {h->point[0], h->point[1], h->point[2]},
                 n[3] = {h->normal[0], h->normal[1], h->normal[2]};
    assert_true(sqrt(ref_point_triangle_dist2(tri, p)) <= tol);
    assert_true(fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-5);
    if (h->t > 0.0f) {
        assert_true(h->depth == 0.0f);
        return;
    }
    assert_true(h->depth >= 0.0f);
    const ref_shape clear = moved(r, n, h->depth + tol);
    const double zero[3] = {0, 0, 0};
    if (!(ref_shape_triangle_dist(&clear, zero, 0.0, tri) > 0.0))
        fail_msg("shape %d: moved by depth %g + %g along the normal it still overlaps tri %u", (int)r->kind,
                 h->depth, tol, h->tri);
}

static void open_scene(ref_fixture *fx, int which)
{
    scene s;
    if (which == 0)
        assert_true(scene_soup(&s, 400, 0.15f, 31));
    else
        assert_true(scene_sphere(&s, 500, (float[3]){0.5f, 0.5f, 0.5f}, 0.5f));
    assert_int_equal(
        ref_fixture_open(fx, s.positions, s.vertex_count, s.indices, s.triangle_count, test_options()),
        CBVH_OK);
    scene_free(&s);
}

static void options_with(cbvh_query_options *o, const pose *p)
{
    assert_int_equal(cbvh_query_options_init(o, sizeof *o), CBVH_OK);
    o->transform = p ? &p->t : NULL;
}

/* Without options a sweep answers as cbvh_sweep_sphere / _capsule / _box, bit for bit, and adds the
 * material and a depth that separates. */
static void test_sweep_with_is_plain_sweep(void **state)
{
    (void)state;
    uint64_t st = 7;
    for (int m = 0; m < 2; m++) {
        ref_fixture fx;
        open_scene(&fx, m);
        for (int q = 0; q < test_reps(150); q++) {
            cbvh_shape s;
            ref_shape r;
            float delta[3];
            random_shape(&st, &fx.tris, fx.lo, fx.hi, fx.diag, (cbvh_shape_kind)(q % 3), 0, &s, &r, delta);
            if (q % 5 == 0) /* starting in contact: no motion */
                delta[0] = delta[1] = delta[2] = 0.0f;
            cbvh_sweep_hit plain;
            if (s.kind == CBVH_SHAPE_SPHERE)
                cbvh_sweep_sphere(fx.file, s.center, s.radius, delta, &plain);
            else if (s.kind == CBVH_SHAPE_CAPSULE)
                cbvh_sweep_capsule(fx.file, s.p0, s.p1, s.radius, delta, &plain);
            else
                cbvh_sweep_box(fx.file, s.center, s.half_extent, delta, &plain);
            cbvh_sweep_record rec;
            assert_int_equal(cbvh_sweep_with(fx.file, &s, delta, NULL, &rec), CBVH_OK);
            assert_int_equal(rec.tri, plain.tri);
            if (rec.tri == CBVH_NO_HIT)
                continue;
            assert_true(rec.t == plain.t);
            assert_memory_equal(rec.point, plain.point, sizeof rec.point);
            assert_memory_equal(rec.normal, plain.normal, sizeof rec.normal);
            assert_int_equal(rec.material, cbvh_file_get_material(fx.file, rec.tri));
            check_record(&fx.tris, fx.diag, &r, delta, &rec);
        }
        ref_fixture_close(&fx);
    }
}

/* A test mesh, placed by a random pose or left in its own frame, as the queries and the reference see it:
 * the triangles in the query's frame, a box around them, their diagonal, the options that place it. */
typedef struct placed_scene {
    ref_fixture fx;
    pose p;
    ref_tris world;
    double lo[3], hi[3], d;
    cbvh_query_options o;
} placed_scene;

static void placed_scene_open(placed_scene *ps, uint64_t *st, int which, int placed)
{
    open_scene(&ps->fx, which);
    random_pose(st, &ps->p);
    placed_tris(&ps->fx, placed ? &ps->p : NULL, &ps->world);
    ps->d = placed ? ps->fx.diag * ps->p.t.scale : ps->fx.diag;
    double mid[3], placed_mid[3];
    for (int a = 0; a < 3; a++)
        mid[a] = 0.5 * (ps->fx.lo[a] + ps->fx.hi[a]);
    pose_point(&ps->p, mid, placed_mid);
    for (int a = 0; a < 3; a++) { /* placed: half a diagonal around the placed center */
        ps->lo[a] = placed ? placed_mid[a] - 0.5 * ps->d : ps->fx.lo[a];
        ps->hi[a] = placed ? placed_mid[a] + 0.5 * ps->d : ps->fx.hi[a];
    }
    options_with(&ps->o, placed ? &ps->p : NULL);
}

static void placed_scene_close(placed_scene *ps)
{
    free_tris(&ps->world);
    ref_fixture_close(&ps->fx);
}

/* Oriented boxes, and every shape on a placed mesh, against the reference in the world. */
static void test_oriented_and_placed_sweeps(void **state)
{
    (void)state;
    uint64_t st = 11;
    long hits = 0, starts = 0;
    for (int m = 0; m < 4; m++) {
        const int placed = m % 2;
        placed_scene ps;
        placed_scene_open(&ps, &st, m / 2, placed);
        for (int q = 0; q < test_reps(120); q++) {
            cbvh_shape s;
            ref_shape r;
            float delta[3];
            random_shape(&st, &ps.world, ps.lo, ps.hi, ps.d,
                         placed ? (cbvh_shape_kind)(q % 3) : CBVH_SHAPE_BOX, 1, &s, &r, delta);
            if (q % 6 == 0)
                delta[0] = delta[1] = delta[2] = 0.0f;
            cbvh_sweep_record rec;
            assert_int_equal(cbvh_sweep_with(ps.fx.file, &s, delta, &ps.o, &rec), CBVH_OK);
            check_record(&ps.world, ps.d, &r, delta, &rec);
            hits += rec.tri != CBVH_NO_HIT;
            starts += rec.tri != CBVH_NO_HIT && rec.t == 0.0f;
        }
        placed_scene_close(&ps);
    }
    fprintf(stderr, "test_posed (%s): %ld sweep hits, %ld starting in contact\n", test_layout_name(), hits,
            starts);
    assert_true(hits > test_least(200) && starts > test_least(20));
}

/* 1 when the shape certainly overlaps the triangle (shrunk by tol it still does), -1 when it certainly does
 * not (grown by tol it still does not), 0 when it is too close to call. */
static int overlap_class(const ref_shape *r, const double tri[9], double tol)
{
    const double zero[3] = {0, 0, 0};
    ref_shape in = *r, out = *r;
    in.radius = fmax(0.0, r->radius - tol);
    out.radius = r->radius + tol;
    for (int a = 0; a < 3; a++) {
        in.half[a] = fmax(0.0, r->half[a] - tol);
        out.half[a] = r->half[a] + tol;
    }
    if (ref_shape_triangle_dist(&in, zero, 0.0, tri) == 0.0 && (r->kind != REF_BOX || r->half[0] > tol))
        return 1;
    return ref_shape_triangle_dist(&out, zero, 0.0, tri) > 0.0 ? -1 : 0;
}

/* Overlaps and contacts of oriented boxes, balls and capsules on placed meshes: the set against the
 * reference, each contact's depth against the shape moved along its normal. */
static void test_overlaps_and_contacts(void **state)
{
    (void)state;
    uint64_t st = 23;
    long found = 0, box_contacts = 0;
    for (int m = 0; m < 4; m++) {
        placed_scene ps;
        placed_scene_open(&ps, &st, m / 2, m % 2);
        const ref_tris *world = &ps.world;
        const double d = ps.d, tol = 2e-5 * d;
        for (int q = 0; q < test_reps(120); q++) {
            cbvh_shape s;
            ref_shape r;
            float delta[3];
            const double *tri = world->v + 9 * (size_t)(scene_rand_unit(&st) * (double)world->count);
            const double at[3] = {tri[0], tri[1], tri[2]};
            random_shape(&st, world, at, at, 0.5 * d, (cbvh_shape_kind)(q % 3), 1, &s, &r, delta);
            uint32_t ids[4096];
            cbvh_contact contacts[4096];
            size_t n = 0, nc = 0;
            int more = 1;
            assert_int_equal(cbvh_overlap_with(ps.fx.file, &s, &ps.o, 0, ids, 4096, &n, &more), CBVH_OK);
            assert_int_equal(more, 0);
            assert_int_equal(cbvh_contacts_with(ps.fx.file, &s, &ps.o, 0, contacts, 4096, &nc, &more),
                             CBVH_OK);
            assert_int_equal(nc, n);
            for (size_t k = 0; k < world->count; k++) {
                const int cls = overlap_class(&r, world->v + 9 * k, tol);
                int listed = 0;
                for (size_t j = 0; j < n; j++)
                    listed |= ids[j] == world->id[k];
                if ((cls == 1 && !listed) || (cls == -1 && listed))
                    fail_msg("shape %d: tri %u class %d, listed %d", (int)r.kind, world->id[k], cls, listed);
            }
            found += (long)n;
            for (size_t j = 0; j < nc; j++) {
                const cbvh_contact *c = &contacts[j];
                assert_int_equal(c->tri, ids[j]);
                const double *t = tri_of(world, c->tri), zero[3] = {0, 0, 0};
                const double nrm[3] = {c->normal[0], c->normal[1], c->normal[2]};
                const double pt[3] = {c->point[0], c->point[1], c->point[2]};
                assert_true(fabs(sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]) - 1.0) < 1e-5);
                assert_true(c->depth >= 0.0f);
                assert_true(sqrt(ref_point_triangle_dist2(t, pt)) <= tol);
                const ref_shape clear = moved(&r, nrm, c->depth + tol);
                if (!(ref_shape_triangle_dist(&clear, zero, 0.0, t) > 0.0))
                    fail_msg("shape %d: moved by depth %g + tol it overlaps tri %u", (int)r.kind, c->depth,
                             c->tri);
                /* A box's depth is the least motion along the normal: by less it does not come clear. */
                if (r.kind == REF_BOX && c->depth > 3.0 * tol) {
                    const ref_shape still = moved(&r, nrm, c->depth - 2.0 * tol);
                    if (!(ref_shape_triangle_dist(&still, zero, 0.0, t) <= 1e-9 * d))
                        fail_msg("shape %d: moved by depth %g - 2 tol it is clear of tri %u", (int)r.kind,
                                 c->depth, c->tri);
                }
                box_contacts += r.kind == REF_BOX;
            }
        }
        placed_scene_close(&ps);
    }
    fprintf(stderr, "test_posed (%s): %ld overlapping triangles, %ld box contacts\n", test_layout_name(),
            found, box_contacts);
    assert_true(found > test_least(200) && box_contacts > test_least(50));
}

/* Without a transform, the ball and capsule contacts are those of cbvh_contacts_sphere / _capsule. */
static void test_contacts_with_round_shapes(void **state)
{
    (void)state;
    uint64_t st = 5;
    ref_fixture fx;
    open_scene(&fx, 0);
    for (int q = 0; q < 100; q++) {
        cbvh_shape s;
        ref_shape r;
        float delta[3];
        const double *tri = fx.tris.v + 9 * (size_t)(scene_rand_unit(&st) * (double)fx.tris.count);
        random_shape(&st, &fx.tris, tri, tri, 0.3 * fx.diag, (cbvh_shape_kind)(q % 2), 0, &s, &r, delta);
        cbvh_contact a[512], b[512];
        size_t na = 0;
        int more_a, more_b;
        assert_int_equal(cbvh_contacts_with(fx.file, &s, NULL, 0, a, 512, &na, &more_a), CBVH_OK);
        const size_t nb = s.kind == CBVH_SHAPE_SPHERE
                              ? cbvh_contacts_sphere(fx.file, s.center, s.radius, 0, b, 512, &more_b)
                              : cbvh_contacts_capsule(fx.file, s.p0, s.p1, s.radius, 0, b, 512, &more_b);
        assert_int_equal(na, nb);
        assert_int_equal(more_a, more_b);
        if (na)
            assert_memory_equal(a, b, na * sizeof *a);
    }
    ref_fixture_close(&fx);
}

static int keep_facing(const double *t, uint32_t id, const void *ctx)
{
    (void)id;
    const float *delta = ctx;
    double n[3];
    ref_triangle_normal(t, n);
    return n[0] * delta[0] + n[1] * delta[1] + n[2] * delta[2] <= 0.0;
}

static int keep_even(const double *t, uint32_t id, const void *ctx)
{
    (void)t;
    (void)ctx;
    return id % 2 == 0;
}

struct filter_log {
    int calls, stop;
    cbvh_hit_record accepted; /* the last candidate let through */
};

static cbvh_filter_result reject_odd(void *user, const cbvh_hit_record *r)
{
    struct filter_log *log = user;
    log->calls++;
    if (!log->stop && r->tri % 2)
        return CBVH_FILTER_REJECT;
    log->accepted = *r;
    return log->stop ? CBVH_FILTER_STOP : CBVH_FILTER_ACCEPT;
}

/* Back-face culling by the motion, and a filter, on a placed mesh: the answer is the reference's over the
 * triangles they keep; a filter that stops ends the sweep with the candidate it saw. */
static void test_cull_and_filter(void **state)
{
    (void)state;
    uint64_t st = 41;
    placed_scene ps;
    placed_scene_open(&ps, &st, 0, 1);
    const ref_tris *world = &ps.world;
    const double d = ps.d;
    long culled_hits = 0, filtered_hits = 0;
    for (int q = 0; q < test_reps(150); q++) {
        cbvh_shape s;
        ref_shape r;
        float delta[3];
        random_shape(&st, world, ps.lo, ps.hi, d, (cbvh_shape_kind)(q % 3), 1, &s, &r, delta);
        if (q % 7 == 0) { /* a point: the ray kernel with the gate */
            s.radius = 0.0f;
            r.radius = 0.0;
            memset(s.half_extent, 0, sizeof s.half_extent);
            memset(r.half, 0, sizeof r.half);
            memcpy(s.p1, s.p0, sizeof s.p1);
            memcpy(r.p1, r.p0, sizeof r.p1);
        }
        cbvh_query_options o;
        options_with(&o, &ps.p);
        o.cull = CBVH_CULL_BACK;
        cbvh_sweep_record rec;
        ref_tris kept;
        assert_int_equal(cbvh_sweep_with(ps.fx.file, &s, delta, &o, &rec), CBVH_OK);
        subset_tris(world, keep_facing, delta, &kept);
        check_record(&kept, d, &r, delta, &rec);
        culled_hits += rec.tri != CBVH_NO_HIT;
        free_tris(&kept);

        struct filter_log log = {0, 0, {0}};
        options_with(&o, &ps.p);
        o.filter = reject_odd;
        o.filter_user = &log;
        assert_int_equal(cbvh_sweep_with(ps.fx.file, &s, delta, &o, &rec), CBVH_OK);
        subset_tris(world, keep_even, NULL, &kept);
        check_record(&kept, d, &r, delta, &rec);
        filtered_hits += rec.tri != CBVH_NO_HIT;
        free_tris(&kept);
        if (rec.tri != CBVH_NO_HIT) { /* the filter let the answer through last, in the world */
            assert_int_equal(log.accepted.tri, rec.tri);
            assert_true(log.accepted.t == rec.t);
            assert_int_equal(log.accepted.material, rec.material);
            const double dot = (double)log.accepted.normal[0] * delta[0] +
                               (double)log.accepted.normal[1] * delta[1] +
                               (double)log.accepted.normal[2] * delta[2];
            assert_int_equal(log.accepted.front, dot < 0.0);
        }

        struct filter_log stop = {0, 1, {0}};
        o.filter_user = &stop;
        assert_int_equal(cbvh_sweep_with(ps.fx.file, &s, delta, &o, &rec), CBVH_OK);
        assert_int_equal(stop.calls, rec.tri == CBVH_NO_HIT ? 0 : 1);
        if (stop.calls)
            assert_int_equal(stop.accepted.tri, rec.tri);
    }
    fprintf(stderr, "test_posed (%s): %ld culled and %ld filtered sweep hits\n", test_layout_name(),
            culled_hits, filtered_hits);
    assert_true(culled_hits > test_least(30) && filtered_hits > test_least(30));
    placed_scene_close(&ps);
}

/* Bad input of every kind is CBVH_ERROR_INVALID_ARGUMENT with a miss, never a silent answer. */
static void test_invalid_input(void **state)
{
    (void)state;
    ref_fixture fx;
    open_scene(&fx, 0);
    cbvh_shape good;
    memset(&good, 0, sizeof good);
    good.kind = CBVH_SHAPE_BOX;
    good.half_extent[0] = good.half_extent[1] = good.half_extent[2] = 0.1f;
    const float delta[3] = {0.0f, 0.0f, 0.5f};
    cbvh_sweep_record rec;
    cbvh_query_options o;
    size_t n = 7;
    int more = 1;
    uint32_t ids[8];
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, NULL, &rec), CBVH_OK);
    assert_int_equal(cbvh_sweep_with(NULL, &good, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(rec.tri, CBVH_NO_HIT);
    assert_int_equal(cbvh_sweep_with(fx.file, NULL, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_sweep_with(fx.file, &good, NULL, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, NULL, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    const float nan_delta[3] = {0.0f, NAN, 0.0f};
    assert_int_equal(cbvh_sweep_with(fx.file, &good, nan_delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    cbvh_shape bad = good;
    bad.kind = (cbvh_shape_kind)3;
    assert_int_equal(cbvh_sweep_with(fx.file, &bad, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_overlap_with(fx.file, &bad, NULL, 0, ids, 8, &n, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);
    assert_true(n == 0 && more == 0);
    bad = good;
    bad.half_extent[1] = -0.1f;
    assert_int_equal(cbvh_sweep_with(fx.file, &bad, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    bad = good;
    bad.rotation[2] = INFINITY;
    assert_int_equal(cbvh_sweep_with(fx.file, &bad, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    bad = good;
    bad.kind = CBVH_SHAPE_CAPSULE;
    bad.radius = -1.0f;
    assert_int_equal(cbvh_sweep_with(fx.file, &bad, delta, NULL, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    bad.radius = NAN;
    assert_int_equal(cbvh_contacts_with(fx.file, &bad, NULL, 0, NULL, 0, &n, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);

    options_with(&o, NULL);
    o.cull = (cbvh_cull)3;
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, &o, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    o.cull = CBVH_CULL_BACK; /* overlaps have no direction to cull by */
    assert_int_equal(cbvh_overlap_with(fx.file, &good, &o, 0, ids, 8, &n, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);
    options_with(&o, NULL);
    o.filter = reject_odd;
    assert_int_equal(cbvh_contacts_with(fx.file, &good, &o, 0, NULL, 0, &n, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);
    options_with(&o, NULL);
    o.struct_size = 3;
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, &o, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_overlap_with(fx.file, &good, NULL, 0, ids, 8, NULL, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);

    cbvh_transform t = {{0, 0, 0, 0}, {0, 0, 0}, 1.0f}; /* a zero quaternion places nothing */
    options_with(&o, NULL);
    o.transform = &t;
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, &o, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    t.rotation[3] = 1.0f;
    t.scale = 0.0f;
    assert_int_equal(cbvh_overlap_with(fx.file, &good, &o, 0, ids, 8, &n, &more),
                     CBVH_ERROR_INVALID_ARGUMENT);
    t.scale = 1e-30f; /* the shape does not fit in float in the mesh's frame */
    good.half_extent[0] = 1e30f;
    assert_int_equal(cbvh_sweep_with(fx.file, &good, delta, &o, &rec), CBVH_ERROR_INVALID_ARGUMENT);
    ref_fixture_close(&fx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sweep_with_is_plain_sweep), cmocka_unit_test(test_oriented_and_placed_sweeps),
        cmocka_unit_test(test_overlaps_and_contacts),     cmocka_unit_test(test_contacts_with_round_shapes),
        cmocka_unit_test(test_cull_and_filter),           cmocka_unit_test(test_invalid_input),
    };
    return TEST_RUN_LAYOUTS(tests, 0);
}
