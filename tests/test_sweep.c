/* test_sweep.c: sphere, capsule and box sweeps against a distance-based brute force; zero-size sweeps equal
 * raycasts. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cbvh.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

static long sweeps_checked, contacts_checked;

static double rnd(uint64_t *st, double lo, double hi)
{
    return lo + (hi - lo) * scene_rand_unit(st);
}

/* Runs the kernel for the shape and fills *hit. */
static int kernel_sweep(const cbvh_file *f, const ref_shape *s, const float delta[3], cbvh_sweep_hit *hit)
{
    float p0[3], p1[3], half[3];
    for (int a = 0; a < 3; a++) {
        p0[a] = (float)s->p0[a];
        p1[a] = (float)s->p1[a];
        half[a] = (float)s->half[a];
    }
    switch (s->kind) {
    case REF_SPHERE:
        return cbvh_sweep_sphere(f, p0, (float)s->radius, delta, hit);
    case REF_CAPSULE:
        return cbvh_sweep_capsule(f, p0, p1, (float)s->radius, delta, hit);
    default:
        return cbvh_sweep_box(f, p0, half, delta, hit);
    }
}

/* A random shape near the mesh, moving by about a third of the mesh size,
 * often straight at a point of a triangle. Coordinates are floats, as the
 * kernels see them. */
static void random_sweep(const ref_fixture *fx, uint64_t *st, ref_shape_kind kind, ref_shape *s,
                         float delta[3])
{
    const double d = fx->diag;
    memset(s, 0, sizeof(*s));
    s->kind = kind;
    const size_t k = (size_t)(scene_rand_unit(st) * (double)fx->tris.count);
    const double *tri = fx->tris.v + 9 * k;
    const int aimed = scene_rand_next(st) % 3 != 0;
    for (int a = 0; a < 3; a++) {
        s->p0[a] = (float)rnd(st, fx->lo[a] - 0.2 * d, fx->hi[a] + 0.2 * d);
        const double target = (tri[a] + tri[3 + a] + tri[6 + a]) / 3.0;
        delta[a] = aimed ? (float)(1.3 * (target - s->p0[a])) : (float)rnd(st, -0.4 * d, 0.4 * d);
        s->p1[a] = kind == REF_CAPSULE ? (float)(s->p0[a] + rnd(st, -0.08 * d, 0.08 * d)) : s->p0[a];
        s->half[a] = kind == REF_BOX ? (float)rnd(st, 0.002 * d, 0.05 * d) : 0.0;
    }
    s->radius = kind == REF_BOX ? 0.0 : (float)rnd(st, 0.002 * d, 0.05 * d);
}

/* The kernel's first contact against the reference: same hit or miss, a t no
 * earlier than the reference's (which is never later than the truth) and no
 * later than it by more than tol; the contact is real (the shape touches the
 * reported triangle at t) and the point, normal and t are consistent. */
static void check_sweep(const ref_fixture *fx, const ref_shape *s, const float delta[3])
{
    const double dd[3] = {delta[0], delta[1], delta[2]};
    const double tol_d = 1e-5 * fx->diag, dlen = sqrt(dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]);
    const double tol_t = dlen > 0.0 ? 2e-5 * fx->diag / dlen + 1e-6 : 0.0;
    ref_sweep_hit ref;
    cbvh_sweep_hit h;
    const int rh = ref_sweep(&fx->tris, s, dd, 1e-9 * fx->diag, &ref);
    const int kh = kernel_sweep(fx->file, s, delta, &h);
    sweeps_checked++;
    if (rh != kh) {
        fprintf(stderr, "shape %d: kernel %s (t %.9g tri %u), reference %s (t %.9g tri %u)\n", (int)s->kind,
                kh ? "hit" : "miss", kh ? h.t : 0.0, h.tri, rh ? "hit" : "miss", ref.t, ref.tri);
        fail();
    }
    if (!kh) {
        assert_int_equal(h.tri, CBVH_NO_HIT);
        return;
    }
    contacts_checked++;
    assert_true(h.tri < fx->id_count && fx->index_of_id[h.tri] != (size_t)-1);
    const double *tri = fx->tris.v + 9 * fx->index_of_id[h.tri];
    if (!(h.t >= ref.t - tol_t && h.t <= ref.t + tol_t && h.t >= 0.0f && h.t <= 1.0f)) {
        fprintf(stderr, "shape %d: kernel t %.9g (tri %u), reference t %.9g (tri %u), tol %g\n", (int)s->kind,
                h.t, h.tri, ref.t, ref.tri, tol_t);
        fail();
    }
    /* The shape touches the reported triangle at the reported time. */
    const double gap = ref_shape_triangle_dist(s, dd, h.t, tri);
    if (!(gap <= tol_d)) {
        fprintf(stderr, "shape %d: at t %.9g the shape is %g away from tri %u\n", (int)s->kind, h.t, gap,
                h.tri);
        fail();
    }
    /* The point is on the triangle, the normal is a unit vector. */
    const double p[3] = {h.point[0], h.point[1], h.point[2]};
    assert_true(sqrt(ref_point_triangle_dist2(tri, p)) <= tol_d);
    const double nl = sqrt((double)h.normal[0] * h.normal[0] + (double)h.normal[1] * h.normal[1] +
                           (double)h.normal[2] * h.normal[2]);
    assert_true(fabs(nl - 1.0) < 1e-5);
    const double nd = h.normal[0] * dd[0] + h.normal[1] * dd[1] + h.normal[2] * dd[2];
    if (h.t > 0.0f) {
        /* Moving into the triangle: the normal (triangle to shape) opposes the motion. */
        assert_true(nd <= 1e-6 * dlen);
        if (s->kind == REF_SPHERE) { /* the normal points from the contact to the center, one radius away */
            double q[3], ql = 0.0;
            for (int a = 0; a < 3; a++) {
                q[a] = s->p0[a] + h.t * dd[a] - p[a];
                ql += q[a] * q[a];
            }
            ql = sqrt(ql);
            assert_true(fabs(ql - s->radius) <= 1e-4 * fx->diag);
            for (int a = 0; a < 3; a++)
                assert_true(fabs(q[a] / ql - h.normal[a]) < 1e-3);
        }
    }
}

static void run_sweeps(const ref_fixture *fx, int count, uint64_t seed)
{
    uint64_t st = seed;
    for (int r = 0; r < count; r++) {
        ref_shape s;
        float delta[3];
        random_sweep(fx, &st, (ref_shape_kind)(r % 3), &s, delta);
        check_sweep(fx, &s, delta);
    }
}

static void open_scene(ref_fixture *fx, scene *s)
{
    assert_int_equal(
        ref_fixture_open(fx, s->positions, s->vertex_count, s->indices, s->triangle_count, test_options()),
        CBVH_OK);
}

static void test_random_sweeps(void **state)
{
    (void)state;
    for (int m = 0; m < 3; m++) {
        scene s;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_soup(&s, 400, 0.15f, 21));
        else if (m == 1)
            assert_true(scene_sphere(&s, 600, (float[3]){0.5f, 0.5f, 0.5f}, 0.5f));
        else
            assert_true(scene_terrain(&s, 600, 10.0f));
        open_scene(&fx, &s);
        run_sweeps(&fx, (int)test_reps(150), 1000 + (uint64_t)m);
        ref_fixture_close(&fx);
        scene_free(&s);
    }
    fprintf(stderr, "test_sweep: %ld sweeps, %ld contacts checked\n", sweeps_checked, contacts_checked);
}

/* A zero-size shape is a ray from its center along delta, t in [0, 1]: the
 * same triangle and the same t as cbvh_raycast, bit for bit. */
static void test_zero_size_is_raycast(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 2000, (float[3]){0, 0, 0}, 1.0f));
    open_scene(&fx, &s);
    uint64_t st = 3;
    int hits = 0;
    for (int r = 0; r < 500; r++) {
        cbvh_ray ray = ref_make_ray(&fx, &st, r % REF_RAY_KINDS);
        ray.tmin = 0.0f;
        ray.tmax = 1.0f;
        const float zero[3] = {0, 0, 0};
        cbvh_hit h;
        cbvh_sweep_hit sh[3];
        const int hit = cbvh_raycast(fx.file, &ray, CBVH_TRAVERSAL_SORTED, &h, NULL);
        const int a = cbvh_sweep_sphere(fx.file, ray.org, 0.0f, ray.dir, &sh[0]);
        const int b = cbvh_sweep_capsule(fx.file, ray.org, ray.org, 0.0f, ray.dir, &sh[1]);
        const int c = cbvh_sweep_box(fx.file, ray.org, zero, ray.dir, &sh[2]);
        assert_int_equal(a, hit);
        assert_int_equal(b, hit);
        assert_int_equal(c, hit);
        for (int k = 0; k < 3; k++) {
            assert_int_equal(sh[k].tri, h.tri);
            if (hit) {
                assert_true(sh[k].t == h.t);
                /* The point is the ray's point, the normal the face normal against the motion. */
                double dot = 0.0;
                for (int q = 0; q < 3; q++) {
                    assert_true(fabs(sh[k].point[q] - (ray.org[q] + h.t * ray.dir[q])) < 1e-4);
                    dot += sh[k].normal[q] * ray.dir[q];
                }
                assert_true(dot <= 0.0);
            }
        }
        hits += hit;
    }
    assert_true(hits > 100);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* Shapes that already touch report t = 0, with a point on the triangle and a
 * unit normal; a shape that does not move reports contact only when touching. */
static void test_start_overlap_and_no_motion(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_true(scene_cube(&s, lo, hi));
    open_scene(&fx, &s);
    const float on_face[3] = {0.5f, 0.5f, 1.0f}, above[3] = {0.5f, 0.5f, 1.5f}, down[3] = {0, 0, -1};
    const float still[3] = {0, 0, 0}, half[3] = {0.1f, 0.1f, 0.1f};
    cbvh_sweep_hit h;
    /* Center on the top face: t = 0, point under the center, normal +z (the face normal against the motion).
     */
    assert_true(cbvh_sweep_sphere(fx.file, on_face, 0.1f, down, &h));
    assert_true(h.t == 0.0f);
    assert_true(fabsf(h.point[2] - 1.0f) < 1e-6f && fabsf(h.point[0] - 0.5f) < 1e-6f);
    assert_true(h.normal[2] > 0.999f);
    /* Penetrating from above: the normal still points out of the face towards the center. */
    const float dipped[3] = {0.5f, 0.5f, 1.05f};
    assert_true(cbvh_sweep_sphere(fx.file, dipped, 0.1f, still, &h));
    assert_true(h.t == 0.0f && h.normal[2] > 0.999f);
    assert_true(cbvh_sweep_capsule(fx.file, dipped, above, 0.1f, still, &h));
    assert_true(h.t == 0.0f && h.normal[2] > 0.999f);
    assert_true(cbvh_sweep_box(fx.file, dipped, half, still, &h));
    assert_true(h.t == 0.0f && h.normal[2] > 0.999f);
    /* Not moving and not touching: no contact. */
    assert_false(cbvh_sweep_sphere(fx.file, above, 0.1f, still, &h));
    assert_int_equal(h.tri, CBVH_NO_HIT);
    assert_false(cbvh_sweep_box(fx.file, above, half, still, &h));
    /* Falling onto the top face from above: exact times. */
    assert_true(cbvh_sweep_sphere(fx.file, above, 0.1f, down, &h));
    assert_true(fabsf(h.t - 0.4f) < 1e-6f && h.normal[2] > 0.999f);
    assert_true(cbvh_sweep_box(fx.file, above, half, down, &h));
    assert_true(fabsf(h.t - 0.4f) < 1e-6f && h.normal[2] > 0.999f);
    const float tip[3] = {0.5f, 0.5f, 2.0f};
    assert_true(cbvh_sweep_capsule(fx.file, tip, above, 0.1f, down, &h));
    assert_true(fabsf(h.t - 0.4f) < 1e-6f && h.normal[2] > 0.999f);
    /* A thin (radius 0) segment lying flat falls onto the face edge-first: exact time. It touches
     * the top face and the two side faces' top edges at once; the tie goes to the lowest cooked
     * index, which depends on the layout, and the normal is that triangle's face normal against
     * the motion. */
    const float flat0[3] = {-0.5f, 0.5f, 1.5f}, flat1[3] = {1.5f, 0.25f, 1.5f};
    assert_true(cbvh_sweep_capsule(fx.file, flat0, flat1, 0.0f, down, &h));
    assert_true(fabsf(h.t - 0.5f) < 1e-6f);
    float v0[3], v1[3], v2[3];
    assert_true(cbvh_file_get_triangle(fx.file, h.tri, v0, v1, v2));
    const double tri[9] = {v0[0], v0[1], v0[2], v1[0], v1[1], v1[2], v2[0], v2[1], v2[2]};
    double n[3];
    ref_triangle_normal(tri, n);
    const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double along = fabs(n[0] * h.normal[0] + n[1] * h.normal[1] + n[2] * h.normal[2]) / len;
    assert_true(along > 0.999999 && h.normal[2] >= 0.0f); /* the face normal, not pointing along the motion */
    ref_fixture_close(&fx);
    scene_free(&s);
}

static void test_invalid_input(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 200, (float[3]){0, 0, 0}, 1.0f));
    open_scene(&fx, &s);
    const float c[3] = {0, 0, -3}, d[3] = {0, 0, 6}, nan3[3] = {NAN, 0, 0}, inf3[3] = {0, INFINITY, 0};
    const float half[3] = {0.1f, 0.1f, 0.1f}, bad_half[3] = {0.1f, -0.1f, 0.1f};
    cbvh_sweep_hit h;
    assert_true(cbvh_sweep_sphere(fx.file, c, 0.1f, d, &h)); /* the valid baseline hits */
    h.tri = 0;
    assert_false(cbvh_sweep_sphere(fx.file, nan3, 0.1f, d, &h));
    assert_int_equal(h.tri, CBVH_NO_HIT);
    assert_false(cbvh_sweep_sphere(fx.file, c, -0.1f, d, &h));
    assert_false(cbvh_sweep_sphere(fx.file, c, NAN, d, &h));
    assert_false(cbvh_sweep_sphere(fx.file, c, INFINITY, d, &h));
    assert_false(cbvh_sweep_sphere(fx.file, c, 0.1f, inf3, &h));
    assert_false(cbvh_sweep_capsule(fx.file, c, nan3, 0.1f, d, &h));
    assert_false(cbvh_sweep_capsule(fx.file, c, c, -1.0f, d, &h));
    assert_false(cbvh_sweep_box(fx.file, c, bad_half, d, &h));
    assert_false(cbvh_sweep_box(fx.file, c, half, nan3, &h));
    assert_false(cbvh_sweep_sphere(NULL, c, 0.1f, d, &h));
    assert_false(cbvh_sweep_box(fx.file, NULL, half, d, &h));
    assert_true(cbvh_sweep_capsule(fx.file, c, c, 0.1f, d, NULL)); /* no output wanted */
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* Finding F4 (notes/findings.md): on a long sliver the face entry's
 * barycentrics came from a Gram-matrix solve that cancels catastrophically,
 * and a sphere sweep reported the midpoint of the long edge, 3 radii from the
 * sphere. The finding's case exactly (delta, center, radius), then random
 * sphere sweeps crossing slivers of aspect 1e4 to 1e9 near their long edge,
 * against the reference (contact real, point on the triangle, one radius
 * from the center along the normal). */
static void test_sliver_sweeps(void **state)
{
    (void)state;
    for (int e = 4; e <= 9; e++) {
        const float len = 1.07e8f, w = len / powf(10.0f, (float)e) * 2.0f;
        const float pos[9] = {0.0f, -len, -len, w, 1e-3f, 2e-3f, 1e-3f, 0.0f, 1e-3f};
        const uint32_t idx[3] = {0, 1, 2};
        ref_fixture fx;
        assert_int_equal(ref_fixture_open(&fx, pos, 3, idx, 1, test_options()), CBVH_OK);
        ref_shape s;
        memset(&s, 0, sizeof s);
        s.kind = REF_SPHERE;
        if (e == 8) { /* aspect 5e7: the finding's sweep */
            const float center[3] = {0.62f, -4.98e7f, -3.56e7f}, delta[3] = {-0.4f, 1.95e7f, -3.59e7f};
            for (int a = 0; a < 3; a++)
                s.p0[a] = s.p1[a] = center[a];
            s.radius = 4.02e6f;
            check_sweep(&fx, &s, delta);
        }
        uint64_t st = 77 + (uint64_t)e;
        for (int i = 0; i < 60; i++) {
            /* a point of the long edge, a center off it, a motion across it */
            const double f = rnd(&st, 0.1, 0.9);
            const double off = rnd(&st, 1.5, 4.0), r = rnd(&st, 1e6, 8e6);
            const double ang = rnd(&st, 0.0, 6.283185307179586);
            const double side[3] = {cos(ang), sin(ang) * 0.7071067811865476, -sin(ang) * 0.7071067811865476};
            float delta[3];
            for (int a = 0; a < 3; a++) {
                const double on = (double)pos[a] * (1.0 - f);
                s.p0[a] = s.p1[a] = (float)(on + side[a] * off * r);
                delta[a] = (float)(-side[a] * off * r * rnd(&st, 1.2, 2.5) + rnd(&st, -0.3, 0.3) * r);
            }
            s.radius = (float)r;
            check_sweep(&fx, &s, delta);
        }
        ref_fixture_close(&fx);
    }
}

/* Capsules whose axis runs almost along a triangle's edge of length 1e12 (near the exact range's edge,
 * cbvh.h's CBVH_COORDINATE_MAX),
 * starting inside or outside it, against the reference: the case where the
 * segment/segment closest points' Gram determinant (|d1|^2 |d2|^2 - (d1.d2)^2)
 * cancels (closest.c now forms it as |d1 x d2|^2). Written for finding F5
 * before its cause was known (test_needle_capsules reproduces it); it
 * passes with the former arithmetic too. */
static void test_huge_capsules(void **state)
{
    (void)state;
    const float L = 1e12f;
    const float pos[9] = {0, 0, 0, L, 0, 0, 0.5f * L, L, 0};
    const uint32_t idx[3] = {0, 1, 2};
    ref_fixture fx;
    assert_int_equal(ref_fixture_open(&fx, pos, 3, idx, 1, test_options()), CBVH_OK);
    uint64_t st = 3;
    for (int r = 0; r < 200; r++) {
        ref_shape s;
        memset(&s, 0, sizeof s);
        s.kind = REF_CAPSULE;
        const double off = rnd(&st, -0.02, 0.02) * L, lift = rnd(&st, 0.001, 0.05) * L;
        const double tilt = rnd(&st, -1e-6, 1e-6) * L;
        s.p0[0] = (float)(rnd(&st, 0.05, 0.3) * L);
        s.p1[0] = (float)(rnd(&st, 0.7, 0.95) * L);
        s.p0[1] = (float)off;
        s.p1[1] = (float)(off + tilt);
        s.p0[2] = s.p1[2] = (float)lift;
        s.radius = (float)(rnd(&st, 0.5, 2.0) * lift);
        const float delta[3] = {0.0f, (float)rnd(&st, -0.05, 0.05) * L, (float)(-rnd(&st, 0.0, 0.1) * L)};
        check_sweep(&fx, &s, delta);
    }
    ref_fixture_close(&fx);
}

/* F5: on a needle (two vertices 1e-28 apart, the third 5.4e16 away) the
 * closest-point inside tests used the long edges, whose directions carry
 * rounding far larger than the needle's angle, and a capsule overlapping
 * the needle's line beyond its tip got a contact point 2.4e16 past the tip.
 * The finding's needle is past the exact range (cbvh.h) and refused; the
 * same needle at 2^-16 of its size (its tip at 4e11), capsules and spheres
 * around the tips of needles of widths 2^-79 (the narrowest the range keeps
 * there) to 1e-4 (relative), overlapping at the start or moving in, against
 * the reference: contact real, point on the triangle. */
static void test_needle_capsules(void **state)
{
    (void)state;
    static const float widths[4] = {0x1p-79f, 1e-20f, 1e-10f, 1e-4f};
    for (int wi = 0; wi < 5; wi++) {
        /* wi 4: the finding's triangle as the fuzzer cooked it */
        const float tip_y = wi < 4 ? -0x1.7f4p+39f : -0x1.7f4p+55f,
                    tip_z = wi < 4 ? -0x1.8007c2p+22f : -0x1.8007c2p+38f,
                    k = wi < 4 ? widths[wi] * -tip_y : 0.0f;
        const float pos[9] = {wi < 4 ? 0.0f : 0x1.fdp-128f,
                              wi < 4 ? 0.0f : 0x1.020406p-91f,
                              wi < 4 ? 0.0f : 0x1.080026p-121f,
                              wi < 4 ? k : 0x1.142214p-103f,
                              wi < 4 ? 0.0f : 0x1.0a0816p-103f,
                              wi < 4 ? 0.0f : 0x1.181a0ap-117f,
                              wi < 4 ? 0.0f : 0x1.fb83cp-128f,
                              tip_y,
                              tip_z};
        const uint32_t idx[3] = {0, 1, 2};
        ref_fixture fx;
        if (wi == 4) {
            assert_int_equal(ref_fixture_open(&fx, pos, 3, idx, 1, test_options()), CBVH_ERROR_BAD_MESH);
            continue;
        }
        assert_int_equal(ref_fixture_open(&fx, pos, 3, idx, 1, test_options()), CBVH_OK);
        ref_shape s;
        memset(&s, 0, sizeof s);
        uint64_t st = 5 + (uint64_t)wi;
        for (int i = 0; i < (wi < 4 ? 100 : 1); i++) {
            float delta[3];
            if (wi == 4) {
                s.kind = REF_CAPSULE;
                const float p0[3] = {-0x1.89c9b8p-21f, -0x1.14a56ep+56f, -0x1.b46a78p+37f},
                            p1[3] = {-0x1.89c9b8p-21f, -0x1.05e87cp+56f, -0x1.93389p+50f},
                            d[3] = {0x1.ae4988p-20f, 0x1.ff5d98p+55f, -0x1.651acp+33f};
                for (int a = 0; a < 3; a++) {
                    s.p0[a] = p0[a];
                    s.p1[a] = p1[a];
                    delta[a] = d[a];
                }
                s.radius = 0x1.e20e4cp+50f;
            } else {
                /* a segment along the needle's line from beyond the tip, a radius that may reach it */
                s.kind = i % 4 == 3 ? REF_SPHERE : REF_CAPSULE;
                const double f0 = rnd(&st, 1.05, 1.5), f1 = s.kind == REF_SPHERE ? f0 : rnd(&st, 1.05, 1.5);
                const double lift = rnd(&st, -0.2, 0.2) * -tip_y;
                for (int a = 0; a < 3; a++) {
                    const double tip = pos[6 + a];
                    s.p0[a] = (float)(f0 * tip + (a == 0 ? lift : 0.0));
                    s.p1[a] = (float)(f1 * tip + (a == 0 ? -lift : 0.0));
                    delta[a] = (float)(rnd(&st, -0.6, 0.2) * tip);
                }
                s.radius = (float)(rnd(&st, 0.01, 0.6) * -tip_y);
            }
            check_sweep(&fx, &s, delta);
        }
        ref_fixture_close(&fx);
    }
}

static void unit3(double v[3])
{
    const double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int a = 0; a < 3; a++)
        v[a] /= l;
}

static double dot3d(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Capsules that graze one triangle, built at their moment of contact: a point q of the triangle (a vertex,
 * an edge or the face), a direction m from q that the triangle lies behind ((x - q).m <= 0 for all its
 * points x), the segment's end at q + m r (1 + eps) with the segment going no nearer (axis.m >= 0: often
 * parallel to the plane through q, or along an edge), so the capsule's distance to the triangle is exactly
 * r eps then; eps = +-1e-4, a miss or a hit far beyond both the reference's tolerance and the rounding of
 * the floats. The motion reaches that pose at tc and then stays on the triangle's side or slides along it:
 * tangent to the plane (the distance never falls below r (1 + eps): a hit only for eps < 0), approaching and
 * ending at tc = 1 (the time limit), leaving from tc = 0 (a start overlap, or a capsule just clear that
 * moves away), or approaching through tc = 0.5 (a hit near tc, on a face often by the end the axis leaves
 * from while its other end lies over the triangle too). Every kind against the reference: the capsule
 * sweep's early rejects, its test of overlap at the start and its face-first answer decide as it does.
 * Triangles: well shaped, thin (aspect 100), a sliver (aspect 1e5) and a degenerate one (its vertices on a
 * line) when the cook keeps it. */
static void test_grazing_capsules(void **state)
{
    (void)state;
    static const float shapes[5][9] = {{0, 0, 0, 1, 0, 0, 0, 1, 0},
                                       {-0.3f, 0.2f, 0.1f, 0.8f, -0.4f, 0.3f, 0.1f, 0.9f, -0.5f},
                                       {-1, 0, 0, 1, 0, 0, 0.2f, 0.01f, 0.003f},
                                       {-1, 0, 0, 1, 0, 0, 0.3f, 1e-5f, 0},
                                       {-1, 0, 0, 1, 0, 0, 0.25f, 0, 0}};
    long hits = 0, misses = 0;
    for (int shape = 0; shape < 5; shape++) {
        const uint32_t idx[3] = {0, 1, 2};
        ref_fixture fx;
        if (ref_fixture_open(&fx, shapes[shape], 3, idx, 1, test_options()) != CBVH_OK ||
            fx.tris.count != 1) {
            assert_true(shape == 4); /* only the degenerate triangle may be refused or dropped */
            if (fx.file)
                ref_fixture_close(&fx);
            continue;
        }
        const double *v = fx.tris.v;
        double n[3];
        ref_triangle_normal(v, n);
        const int flat = dot3d(n, n) == 0.0;
        if (!flat)
            unit3(n);
        uint64_t st = 900 + (uint64_t)shape;
        for (int i = 0; i < (int)test_reps(600); i++) {
            const int feature = (int)(scene_rand_next(&st) % 3), k = (int)(scene_rand_next(&st) % 3);
            const double *p = v + 3 * k, *pn = v + 3 * ((k + 1) % 3);
            double q[3], m[3], edge[3];
            const double f = rnd(&st, 0.0, 1.0), g = rnd(&st, 0.0, 1.0 - f);
            for (int a = 0; a < 3; a++) {
                edge[a] = pn[a] - p[a];
                q[a] = feature == 0   ? p[a]
                       : feature == 1 ? p[a] + f * edge[a]
                                      : v[a] + f * (v[3 + a] - v[a]) + g * (v[6 + a] - v[a]);
            }
            /* m: a random direction, until the triangle lies behind it (the face: +-n) */
            int tries = 0;
            do {
                for (int a = 0; a < 3; a++)
                    m[a] = feature == 2 && !flat ? n[a] * (f < 0.5 ? 1.0 : -1.0) : rnd(&st, -1.0, 1.0);
                if (feature == 1) { /* square to the edge */
                    const double along = dot3d(m, edge) / dot3d(edge, edge);
                    for (int a = 0; a < 3; a++)
                        m[a] -= along * edge[a];
                }
                unit3(m);
            } while (++tries < 1000 &&
                     !(dot3d(m, (double[3]){v[0] - q[0], v[1] - q[1], v[2] - q[2]}) <= 1e-12 &&
                       dot3d(m, (double[3]){v[3] - q[0], v[4] - q[1], v[5] - q[2]}) <= 1e-12 &&
                       dot3d(m, (double[3]){v[6] - q[0], v[7] - q[1], v[8] - q[2]}) <= 1e-12));
            if (tries == 1000)
                continue;
            /* the axis (no nearer to the triangle than its end) and the motion (never towards m after tc) */
            double axis[3], tangent[3], delta[3];
            const int axis_kind = (int)(scene_rand_next(&st) % 4), motion = (int)(scene_rand_next(&st) % 4);
            for (int a = 0; a < 3; a++) {
                axis[a] = axis_kind == 0 ? edge[a] : rnd(&st, -1.0, 1.0);
                tangent[a] = scene_rand_next(&st) % 4 == 0 ? edge[a] : rnd(&st, -1.0, 1.0);
            }
            const double am = dot3d(axis, m), tm = dot3d(tangent, m);
            for (int a = 0; a < 3; a++) {
                axis[a] = axis_kind == 1 ? axis[a] - am * m[a] : am < 0.0 ? -axis[a] : axis[a];
                tangent[a] -= tm * m[a];
            }
            unit3(axis);
            unit3(tangent);
            const double r = rnd(&st, 0.02, 0.2), len = axis_kind == 3 ? 0.0 : rnd(&st, 0.0, 0.6);
            const double eps = scene_rand_next(&st) % 2 ? 1e-4 : -1e-4, speed = rnd(&st, 0.3, 1.5);
            const double tc = motion == 0 ? rnd(&st, 0.0, 1.0) : motion == 1 ? 1.0 : motion == 2 ? 0.0 : 0.5;
            const double in = motion == 1 || motion == 3 ? -rnd(&st, 0.2, 1.0)
                              : motion == 2              ? rnd(&st, 0.0, 1.0)
                                                         : 0.0;
            ref_shape s;
            memset(&s, 0, sizeof s);
            s.kind = REF_CAPSULE;
            s.radius = (float)r;
            float d[3];
            for (int a = 0; a < 3; a++) {
                delta[a] = speed * (tangent[a] + in * m[a]);
                d[a] = (float)delta[a];
                const double end = q[a] + m[a] * s.radius * (1.0 + eps) - tc * d[a];
                s.p0[a] = (float)end;
                s.p1[a] = (float)(end + len * axis[a]);
            }
            const long before = contacts_checked;
            check_sweep(&fx, &s, d);
            if (contacts_checked > before)
                hits++;
            else
                misses++;
        }
        ref_fixture_close(&fx);
    }
    fprintf(stderr, "test_sweep: grazing capsules: %ld hits, %ld misses\n", hits, misses);
    assert_true(hits > 0 && misses > 0);
}

/* Every walk kernel the build and the CPU have (scalar: one triangle at a time, with no float cull; SSE2:
 * four a vector; AVX2: eight) gives the same record bit for bit, sweep for sweep, on spheres, capsules,
 * aligned and oriented boxes of sizes that put many triangles of a leaf near them, so that a float cull
 * dropping a triangle the exact test would keep changes an answer against the scalar kernel's. */
static void test_kernels_agree(void **state)
{
    (void)state;
    const int before = test_kernel_now;
    static const int kernels[] = {TEST_KERNEL_SCALAR, TEST_KERNEL_SSE2, TEST_KERNEL_AVX2};
    if (test_kernels_available(kernels, sizeof kernels / sizeof kernels[0]) < 2) {
        fprintf(stderr, "test_sweep: one walk kernel in this build and CPU, nothing to compare\n");
        skip();
    }
    long compared = 0, hits = 0, runs = 0;
    for (int m = 0; m < 3; m++) {
        scene sc;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_soup(&sc, 3000, 0.08f, 33));
        else if (m == 1)
            assert_true(scene_sphere(&sc, 4000, (float[3]){0.5f, -0.25f, 2.0f}, 0.75f));
        else
            assert_true(scene_terrain(&sc, 4000, 10.0f));
        open_scene(&fx, &sc);
        uint64_t st = 4000 + (uint64_t)m;
        for (long r = 0; r < test_reps(240); r++) {
            ref_shape rs;
            float delta[3];
            random_sweep(&fx, &st, (ref_shape_kind)(r % 3), &rs, delta);
            cbvh_shape s;
            memset(&s, 0, sizeof s);
            s.kind = rs.kind == REF_SPHERE    ? CBVH_SHAPE_SPHERE
                     : rs.kind == REF_CAPSULE ? CBVH_SHAPE_CAPSULE
                                              : CBVH_SHAPE_BOX;
            for (int a = 0; a < 3; a++) {
                s.center[a] = s.p0[a] = (float)rs.p0[a];
                s.p1[a] = (float)rs.p1[a];
                s.half_extent[a] = (float)rs.half[a];
                s.rotation[a] = r % 6 == 5 ? (float)rnd(&st, -1.0, 1.0) : 0.0f; /* every other box turned */
            }
            s.rotation[3] = r % 6 == 5 ? (float)rnd(&st, -1.0, 1.0) : 0.0f;
            s.radius = (float)rs.radius;
            cbvh_sweep_record first, rec;
            int have = 0;
            for (size_t k = 0; k < sizeof kernels / sizeof kernels[0]; k++) {
                if (!test_set_kernel(kernels[k]))
                    continue;
                assert_int_equal(cbvh_sweep_with(fx.file, &s, delta, NULL, have ? &rec : &first), CBVH_OK);
                if (have++) {
                    assert_memory_equal(&rec, &first, sizeof rec);
                    compared++;
                }
            }
            runs++;
            hits += first.tri != CBVH_NO_HIT;
        }
        ref_fixture_close(&fx);
        scene_free(&sc);
    }
    test_set_kernel(before);
    fprintf(stderr, "test_sweep: kernels agree on %ld sweeps (%ld hits), %ld comparisons\n", runs, hits,
            compared);
    assert_true(compared >= runs && hits >= test_least(200));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_sweeps),
        cmocka_unit_test(test_zero_size_is_raycast),
        cmocka_unit_test(test_start_overlap_and_no_motion),
        cmocka_unit_test(test_invalid_input),
        cmocka_unit_test(test_sliver_sweeps),
        cmocka_unit_test(test_huge_capsules),
        cmocka_unit_test(test_needle_capsules),
        cmocka_unit_test(test_grazing_capsules),
        cmocka_unit_test(test_kernels_agree),
    };
    return TEST_RUN_LAYOUTS(tests, 1);
}
