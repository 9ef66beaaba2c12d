/* test_overlap.c: box, sphere and capsule overlaps and contacts against brute force; the triangle/box SAT
 * against clipping. */
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
#include "query/closest.h"
#include "query/triangle_box.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

static double rnd(uint64_t *st, double lo, double hi)
{
    return lo + (hi - lo) * scene_rand_unit(st);
}

/* A query region: a box [lo, hi], a ball (p0, radius) or a capsule (p0-p1, radius). */
enum { BOX, SPHERE, CAPSULE };
typedef struct region {
    int kind;
    float lo[3], hi[3], p0[3], p1[3], radius;
} region;

static const char *const kind_name[] = {"box", "sphere", "capsule"};

static size_t overlap(const ref_fixture *fx, const region *g, cbvh_overlap_fn callback, void *user,
                      uint32_t *out, size_t capacity)
{
    if (g->kind == BOX)
        return cbvh_overlap_box(fx->file, g->lo, g->hi, callback, user, out, capacity);
    if (g->kind == SPHERE)
        return cbvh_overlap_sphere(fx->file, g->p0, g->radius, callback, user, out, capacity);
    return cbvh_overlap_capsule(fx->file, g->p0, g->p1, g->radius, callback, user, out, capacity);
}

static size_t overlap_from(const ref_fixture *fx, const region *g, size_t first, uint32_t *out,
                           size_t capacity, int *more)
{
    if (g->kind == BOX)
        return cbvh_overlap_box_from(fx->file, g->lo, g->hi, first, out, capacity, more);
    if (g->kind == SPHERE)
        return cbvh_overlap_sphere_from(fx->file, g->p0, g->radius, first, out, capacity, more);
    return cbvh_overlap_capsule_from(fx->file, g->p0, g->p1, g->radius, first, out, capacity, more);
}

/* The reported set holds every sure overlap and no sure miss (by tol), each once. */
static void check_set_within(const ref_fixture *fx, const uint32_t *ids, size_t n, const region *g,
                             double tol)
{
    uint8_t *seen = calloc(fx->id_count + 1, 1);
    assert_non_null(seen);
    for (size_t k = 0; k < n; k++) {
        assert_true(ids[k] < fx->id_count);
        assert_false(seen[ids[k]]);
        seen[ids[k]] = 1;
    }
    const double lo[3] = {g->lo[0], g->lo[1], g->lo[2]}, hi[3] = {g->hi[0], g->hi[1], g->hi[2]};
    const double p0[3] = {g->p0[0], g->p0[1], g->p0[2]}, p1[3] = {g->p1[0], g->p1[1], g->p1[2]};
    for (size_t k = 0; k < fx->tris.count; k++) {
        const double *tri = fx->tris.v + 9 * k;
        const int cls = g->kind == BOX      ? ref_box_class(tri, lo, hi, tol)
                        : g->kind == SPHERE ? ref_sphere_class(tri, p0, g->radius, tol)
                                            : ref_capsule_class(tri, p0, p1, g->radius, tol);
        const int got = seen[fx->tris.id[k]];
        if ((cls == 2 && !got) || (cls == 0 && got)) {
            fprintf(stderr, "%s overlap: tri %u reported %d, reference class %d\n", kind_name[g->kind],
                    fx->tris.id[k], got, cls);
            fail();
        }
    }
    free(seen);
}

/* check_set_within at a millionth of the diagonal. */
static void check_set(const ref_fixture *fx, const uint32_t *ids, size_t n, const region *g)
{
    check_set_within(fx, ids, n, g, 1e-6 * fx->diag);
}

static int count_calls(void *user, uint32_t tri)
{
    (void)tri;
    (*(size_t *)user)++;
    return 0;
}

static int stop_at_first(void *user, uint32_t tri)
{
    *(uint32_t *)user = tri;
    return 1;
}

static void run_overlaps(const ref_fixture *fx, int count, uint64_t seed)
{
    uint64_t st = seed;
    uint32_t *ids = malloc(sizeof(uint32_t) * (fx->id_count + 1));
    assert_non_null(ids);
    size_t nonempty = 0;
    for (int r = 0; r < count; r++) {
        region g;
        g.kind = r % 3;
        const double size = rnd(&st, 0.0, 0.15) * fx->diag;
        for (int a = 0; a < 3; a++) {
            g.p0[a] = (float)rnd(&st, fx->lo[a] - 0.05 * fx->diag, fx->hi[a] + 0.05 * fx->diag);
            g.p1[a] = g.p0[a] + (float)(size * (2.0 * scene_rand_unit(&st) - 1.0));
            g.lo[a] = g.p0[a] - (float)(size * scene_rand_unit(&st));
            g.hi[a] = g.p0[a] + (float)(size * scene_rand_unit(&st));
        }
        g.radius = (float)(g.kind == CAPSULE ? 0.3 * size : size);
        if (g.kind == CAPSULE &&
            r % 5 == 2) /* a capsule of no length is a sphere; one of no radius a segment */
            memcpy(g.p1, g.p0, sizeof g.p1);
        if (g.kind == CAPSULE && r % 5 == 4)
            g.radius = 0.0f;
        size_t calls = 0;
        const size_t n = overlap(fx, &g, count_calls, &calls, ids, fx->id_count);
        assert_int_equal(calls, n);
        check_set(fx, ids, n, &g);
        nonempty += n > 0;
        /* Without an output array the count is the same; a callback that stops ends the query at 1. */
        assert_int_equal(overlap(fx, &g, NULL, NULL, NULL, 0), n);
        uint32_t first = CBVH_NO_HIT;
        assert_int_equal(overlap(fx, &g, stop_at_first, &first, NULL, 0), n > 0 ? 1 : 0);
        if (n > 0) {
            int found = 0;
            for (size_t k = 0; k < n; k++)
                found |= ids[k] == first;
            assert_true(found);
        }
        /* A small array fills and stops the query; capacity 0 reports nothing. */
        uint32_t small[3] = {CBVH_NO_HIT, CBVH_NO_HIT, CBVH_NO_HIT};
        assert_int_equal(overlap(fx, &g, NULL, NULL, small, 2), n < 2 ? n : 2);
        assert_int_equal(small[2], CBVH_NO_HIT);
        assert_int_equal(overlap(fx, &g, count_calls, &calls, small, 0), 0);
        /* Pages of 1, 4 and 7: the same triangles in the same order as the whole query, *more exactly while
         * some are left, every page but the last full. */
        for (size_t page = 1; page <= 7; page += 3) {
            uint32_t buf[8];
            size_t got = 0;
            for (int more = 1; more;) {
                more = -1;
                const size_t k = overlap_from(fx, &g, got, buf, page, &more);
                assert_true(got + k <= n);
                for (size_t j = 0; j < k; j++)
                    assert_int_equal(buf[j], ids[got + j]);
                got += k;
                assert_int_equal(more, got < n);
                if (more)
                    assert_int_equal(k, page);
            }
            assert_int_equal(got, n);
        }
        /* Without *more, a page is the same and the query stops once out is full: capacity 1 is a first-hit
         * query, giving the first triangle of the whole query's order. */
        for (size_t page = 1; page <= 3; page++) {
            uint32_t buf[4] = {CBVH_NO_HIT, CBVH_NO_HIT, CBVH_NO_HIT, CBVH_NO_HIT};
            const size_t k = overlap_from(fx, &g, 0, buf, page, NULL);
            assert_int_equal(k, n < page ? n : page);
            for (size_t j = 0; j < k; j++)
                assert_int_equal(buf[j], ids[j]);
            assert_int_equal(buf[k], CBVH_NO_HIT);
        }
        /* Without an output array: whether any overlapping triangle lies past `first`. */
        int more = -1;
        assert_int_equal(overlap_from(fx, &g, 0, NULL, 5, &more), 0);
        assert_int_equal(more, n > 0);
        more = -1;
        assert_int_equal(overlap_from(fx, &g, n, ids, 1, &more), 0);
        assert_int_equal(more, 0);
    }
    assert_true(nonempty > (size_t)count / 4);
    free(ids);
}

static void test_overlaps(void **state)
{
    (void)state;
    for (int m = 0; m < 3; m++) {
        scene s;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_soup(&s, 2000, 0.1f, 5));
        else if (m == 1)
            assert_true(scene_sphere(&s, 3000, (float[3]){0, 0, 0}, 1.0f));
        else
            assert_true(scene_terrain(&s, 3000, 40.0f));
        assert_int_equal(
            ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, test_options()),
            CBVH_OK);
        run_overlaps(&fx, (int)test_reps(300), 50 + (uint64_t)m);
        ref_fixture_close(&fx);
        scene_free(&s);
    }
}

/* Balls that reach a vertex from the corner of its box (the center off the vertex by the same amount on
 * every axis, so the node boxes' corners lie as far from it as the vertex), and capsules square to an axis
 * off the vertex along it, their float radius the distance of the vertex rounded up: the node tests (a
 * ball's float distance to the node boxes, a capsule's path through them grown by its radius) must keep
 * them, far from the origin too. Every triangle the double reference finds within the radius by
 * more than its own rounding is reported, in the whole query and as its first hit. */
static void test_grazing_rounds(void **state)
{
    (void)state;
    for (int m = 0; m < 3; m++) {
        scene s;
        ref_fixture fx;
        if (m < 2) {
            assert_true(
                scene_sphere(&s, 3000, (float[3]){m ? 3000.0f : 0.0f, m ? -1000.0f : 0.0f, 500.0f}, 1.0f));
            assert_int_equal(ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count,
                                              test_options()),
                             CBVH_OK);
        } else {
            /* triangles along the diagonal, each from its box's lowest corner to its highest, far from the
             * origin: the corners of many node boxes are vertices */
            enum { DIAGONAL = 300 };
            static float positions[DIAGONAL * 9];
            static uint32_t indices[DIAGONAL * 3];
            for (uint32_t i = 0; i < DIAGONAL; i++) {
                const float o = 1000.0f + 2.0f * (float)i;
                const float v[9] = {o, o, o, o + 1.0f, o + 1.0f, o + 1.0f, o + 1.0f, o, o + 0.5f};
                memcpy(positions + 9 * i, v, sizeof v);
                for (uint32_t j = 0; j < 3; j++)
                    indices[3 * i + j] = 3 * i + j;
            }
            memset(&s, 0, sizeof s);
            assert_int_equal(
                ref_fixture_open(&fx, positions, 3 * DIAGONAL, indices, DIAGONAL, test_options()), CBVH_OK);
        }
        uint32_t *ids = malloc(sizeof(uint32_t) * (fx.id_count + 1));
        assert_non_null(ids);
        uint64_t st = 70 + (uint64_t)m;
        const int count = (int)test_reps(400);
        int grazing = 0;
        for (int r = 0; r < count; r++) {
            /* the diagonal's lowest vertex lies on the grid's origin planes, exactly its boxes' corner */
            const int lowest = m == 2 && r % 4 < 2, capsule = r % 2;
            size_t k = (size_t)(scene_rand_unit(&st) * (double)fx.tris.count) % fx.tris.count;
            for (size_t j = 0; lowest && j < fx.tris.count; j++)
                if (fx.tris.v[9 * j] < fx.tris.v[9 * k])
                    k = j;
            const double *v = fx.tris.v + 9 * k + 3 * (size_t)(lowest ? 0 : r % (m < 2 ? 3 : 2));
            /* the node tests of balls and capsules run for shapes large next to the leaves: every other
             * one here is */
            const double reach =
                r % 8 < 4 ? rnd(&st, 1e-4, 0.05) * (m < 2 ? fx.diag : 1.0) : rnd(&st, 0.05, 0.3) * fx.diag;
            region g;
            memset(&g, 0, sizeof g);
            g.kind = capsule ? CAPSULE : SPHERE;
            /* a capsule lies square to one axis, off the vertex along it, where its box grown by the radius
             * ends: the path test's face; its segment runs across that axis, its middle nearest */
            const int axis = (r / 2) % 3;
            const double turn = rnd(&st, 0.0, 6.283), length = reach * rnd(&st, 0.2, 2.0);
            for (int a = 0; a < 3; a++) {
                const int up =
                    m < 2 ? r >> (a + 2) & 1 : !lowest && r % 4 >= 2; /* the diagonal's corners face out */
                const double away = capsule ? (a == axis) * reach : reach / sqrt(3.0);
                const double across = a == (axis + 1) % 3 ? cos(turn) : a == (axis + 2) % 3 ? sin(turn) : 0.0;
                g.p0[a] = (float)(v[a] + (up ? away : -away) - capsule * length * across);
                g.p1[a] = (float)(v[a] + (up ? away : -away) + capsule * length * across);
            }
            /* the distance of the vertex from the segment (a point for a ball), in double */
            double d2 = 0.0, along = 0.0, len2 = 0.0;
            for (int a = 0; a < 3; a++) {
                along += ((double)g.p1[a] - g.p0[a]) * (v[a] - g.p0[a]);
                len2 += ((double)g.p1[a] - g.p0[a]) * ((double)g.p1[a] - g.p0[a]);
            }
            const double at = len2 > 0.0 ? fmin(fmax(along / len2, 0.0), 1.0) : 0.0;
            for (int a = 0; a < 3; a++) {
                const double x = g.p0[a] + at * ((double)g.p1[a] - g.p0[a]) - v[a];
                d2 += x * x;
            }
            g.radius = (float)sqrt(d2);
            if ((double)g.radius < sqrt(d2))
                g.radius = nextafterf(g.radius, INFINITY);
            const double c[3] = {g.p0[0], g.p0[1], g.p0[2]}, c1[3] = {g.p1[0], g.p1[1], g.p1[2]};
            /* above the reference's own rounding, a few ulps of the coordinates */
            const double tol = 1e-14 * fx.diag + 1e-15 * fmax(fmax(fabs(c[0]), fabs(c[1])), fabs(c[2]));
            grazing += (capsule ? ref_capsule_class(fx.tris.v + 9 * k, c, c1, g.radius, tol)
                                : ref_sphere_class(fx.tris.v + 9 * k, c, g.radius, tol)) == 2;
            const size_t n = overlap(&fx, &g, NULL, NULL, ids, fx.id_count);
            check_set_within(&fx, ids, n, &g, tol);
            uint32_t first = CBVH_NO_HIT;
            assert_int_equal(overlap(&fx, &g, stop_at_first, &first, NULL, 0), n > 0 ? 1 : 0);
        }
        fprintf(stderr,
                "grazing balls and capsules: %d of %d reach their vertex by more than the tolerance\n",
                grazing, count);
        assert_true(grazing > count / 4);
        free(ids);
        ref_fixture_close(&fx);
        if (m < 2)
            scene_free(&s);
    }
}

/* The static SAT agrees with clipping on random triangles and boxes, touching
 * and flat cases included (triangles on box planes, zero-size boxes). */
static void test_triangle_box_sat(void **state)
{
    (void)state;
    uint64_t st = 17;
    long sure_in = 0, sure_out = 0;
    for (int r = 0; r < 200000; r++) {
        double tri[9], lo[3], hi[3];
        for (int k = 0; k < 9; k++)
            tri[k] = (float)rnd(&st, -1.0, 1.0);
        for (int a = 0; a < 3; a++) {
            const double c = (float)rnd(&st, -1.0, 1.0), h = r % 10 == 0 ? 0.0 : (float)rnd(&st, 0.0, 0.6);
            lo[a] = c - h;
            hi[a] = c + h;
        }
        if (r % 7 == 0) /* a triangle lying in a box plane */
            tri[2] = tri[5] = tri[8] = hi[2];
        double t;
        cbvh_v3 n;
        const int got = cbvh_triangle_box_sweep(
            v3(tri[0], tri[1], tri[2]), v3(tri[3], tri[4], tri[5]), v3(tri[6], tri[7], tri[8]),
            v3(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])),
            v3(0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1]), 0.5 * (hi[2] - lo[2])), v3(0, 0, 0), 0.0, &t, &n,
            NULL);
        const int cls = ref_box_class(tri, lo, hi, 1e-9);
        if ((cls == 2 && !got) || (cls == 0 && got)) {
            fprintf(stderr, "SAT %d, clipping class %d at case %d\n", got, cls, r);
            fail();
        }
        if (got)
            assert_true(t == 0.0);
        sure_in += cls == 2;
        sure_out += cls == 0;
    }
    assert_true(sure_in > 10000 && sure_out > 10000);
}

static void test_invalid_input(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 200, (float[3]){0, 0, 0}, 1.0f));
    assert_int_equal(
        ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, test_options()),
        CBVH_OK);
    const float lo[3] = {-2, -2, -2}, hi[3] = {2, 2, 2}, nan3[3] = {0, NAN, 0}, c[3] = {0, 0, 0};
    assert_true(cbvh_overlap_box(fx.file, lo, hi, NULL, NULL, NULL, 0) == fx.tris.count);
    assert_int_equal(cbvh_overlap_box(fx.file, hi, lo, NULL, NULL, NULL, 0), 0); /* min > max */
    assert_int_equal(cbvh_overlap_box(fx.file, nan3, hi, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_box(NULL, lo, hi, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_sphere(fx.file, c, -1.0f, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_sphere(fx.file, c, NAN, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_sphere(fx.file, nan3, 1.0f, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_capsule(fx.file, c, nan3, 1.0f, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_capsule(fx.file, c, NULL, 1.0f, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_capsule(fx.file, c, hi, -1.0f, NULL, NULL, NULL, 0), 0);
    assert_int_equal(cbvh_overlap_capsule(NULL, c, hi, 1.0f, NULL, NULL, NULL, 0), 0);
    /* the paged queries: nothing written and no more for what the plain ones reject */
    uint32_t buf[4];
    int more = -1;
    assert_int_equal(cbvh_overlap_box_from(fx.file, hi, lo, 0, buf, 4, &more), 0);
    assert_int_equal(more, 0);
    more = -1;
    assert_int_equal(cbvh_overlap_box_from(NULL, lo, hi, 0, buf, 4, &more), 0);
    assert_int_equal(more, 0);
    more = -1;
    assert_int_equal(cbvh_overlap_sphere_from(fx.file, c, NAN, 0, buf, 4, &more), 0);
    assert_int_equal(more, 0);
    assert_int_equal(cbvh_overlap_box_from(fx.file, lo, hi, 0, buf, 4, NULL), 4); /* more may be NULL */
    more = -1;
    assert_int_equal(cbvh_overlap_capsule_from(fx.file, c, NULL, 1.0f, 0, buf, 4, &more), 0);
    assert_int_equal(more, 0);
    /* A capsule inside the closed sphere mesh touches nothing; one that pokes out touches. */
    const float in0[3] = {-0.4f, 0, 0}, in1[3] = {0.4f, 0, 0}, out1[3] = {1.5f, 0, 0};
    assert_int_equal(cbvh_overlap_capsule(fx.file, in0, in1, 0.5f, NULL, NULL, NULL, 0), 0);
    assert_true(cbvh_overlap_capsule(fx.file, in0, out1, 0.1f, NULL, NULL, NULL, 0) > 0);
    /* The ball inside the closed sphere mesh touches nothing; a radius reaching the surface touches. */
    assert_int_equal(cbvh_overlap_sphere(fx.file, c, 0.5f, NULL, NULL, NULL, 0), 0);
    assert_true(cbvh_overlap_sphere(fx.file, c, 1.0f, NULL, NULL, NULL, 0) > 0);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* The reference distance from the core (center, or segment p0-p1) of a round region to triangle k. */
static double core_dist(const ref_fixture *fx, size_t k, const double p0[3], const double p1[3], int capsule)
{
    const double *tri = fx->tris.v + 9 * k;
    return capsule ? ref_segment_triangle_dist(tri, p0, p1) : sqrt(ref_point_triangle_dist2(tri, p0));
}

/* Contacts of balls and capsules: the overlap's triangles in its order; each normal a unit vector, each
 * point on its triangle; depth = radius - the reference core distance when the core is clear of the
 * triangle; the shape moved by depth along the normal (and a little more) no longer overlaps the triangle
 * in the reference, and moved a little less still does (the least motion). */
static void check_contacts(const ref_fixture *fx, int count, uint64_t seed)
{
    uint64_t st = seed;
    uint32_t *ids = malloc(sizeof(uint32_t) * (fx->id_count + 1));
    cbvh_contact *contacts = malloc(sizeof(cbvh_contact) * (fx->id_count + 1));
    assert_non_null(ids);
    assert_non_null(contacts);
    const double tol = 2e-5 * fx->diag;
    size_t total = 0, touching = 0;
    for (int r = 0; r < count; r++) {
        const int capsule = r % 2;
        float p0[3], p1[3];
        const double size = rnd(&st, 0.0, 0.1) * fx->diag;
        for (int a = 0; a < 3; a++) {
            p0[a] = (float)rnd(&st, fx->lo[a], fx->hi[a]);
            p1[a] = p0[a] + (float)(size * (2.0 * scene_rand_unit(&st) - 1.0));
        }
        const float radius = (float)(capsule ? 0.5 * size : size);
        const size_t n = capsule
                             ? cbvh_overlap_capsule(fx->file, p0, p1, radius, NULL, NULL, ids, fx->id_count)
                             : cbvh_overlap_sphere(fx->file, p0, radius, NULL, NULL, ids, fx->id_count);
        int more = -1;
        const size_t m =
            capsule ? cbvh_contacts_capsule(fx->file, p0, p1, radius, 0, contacts, fx->id_count, &more)
                    : cbvh_contacts_sphere(fx->file, p0, radius, 0, contacts, fx->id_count, &more);
        assert_int_equal(m, n);
        assert_int_equal(more, 0);
        for (size_t i = 0; i < m; i++) {
            const cbvh_contact *c = &contacts[i];
            assert_int_equal(c->tri, ids[i]);
            const size_t k = fx->index_of_id[c->tri];
            assert_true(k != (size_t)-1);
            const double nl = sqrt((double)c->normal[0] * c->normal[0] + (double)c->normal[1] * c->normal[1] +
                                   (double)c->normal[2] * c->normal[2]);
            assert_true(fabs(nl - 1.0) < 1e-5);
            const double pt[3] = {c->point[0], c->point[1], c->point[2]};
            assert_true(sqrt(ref_point_triangle_dist2(fx->tris.v + 9 * k, pt)) <= tol);
            const double q0[3] = {p0[0], p0[1], p0[2]}, q1[3] = {p1[0], p1[1], p1[2]};
            const double d = core_dist(fx, k, q0, capsule ? q1 : q0, capsule);
            assert_true(c->depth >= 0.0f && d <= radius + tol);
            if (d > tol) {
                if (!(fabs(c->depth - (radius - d)) <= tol))
                    fail_msg("%s contact with tri %u: depth %g, radius - distance %g",
                             capsule ? "capsule" : "sphere", c->tri, (double)c->depth, radius - d);
            } else {
                touching++;
            }
            /* moved by depth (+ tol) along the normal: clear of the triangle; by depth - 2 tol: not yet */
            for (int sign = 1; sign >= -1; sign -= 2) {
                const double move = c->depth + sign * (sign > 0 ? tol : 2.0 * tol);
                if (move < 0.0 || (sign < 0 && d <= tol))
                    continue;
                double m0[3], m1[3];
                for (int a = 0; a < 3; a++) {
                    m0[a] = q0[a] + move * c->normal[a];
                    m1[a] = q1[a] + move * c->normal[a];
                }
                const double moved = core_dist(fx, k, m0, capsule ? m1 : m0, capsule);
                if (sign > 0 ? !(moved >= radius - tol) : !(moved < radius))
                    fail_msg(
                        "%s contact with tri %u (distance %g, depth %g): moved by %g along the normal, the "
                        "core is %g from it, radius %g",
                        capsule ? "capsule" : "sphere", c->tri, d, (double)c->depth, move, moved,
                        (double)radius);
            }
        }
        total += m;
        /* pages of 3: the same contacts */
        size_t got = 0;
        for (int again = 1; again;) {
            cbvh_contact page[3];
            const size_t k = capsule ? cbvh_contacts_capsule(fx->file, p0, p1, radius, got, page, 3, &again)
                                     : cbvh_contacts_sphere(fx->file, p0, radius, got, page, 3, &again);
            for (size_t j = 0; j < k; j++)
                assert_memory_equal(&page[j], &contacts[got + j], sizeof page[j]);
            got += k;
        }
        assert_int_equal(got, m);
        /* first hit: capacity 1 without *more, the first contact of the whole query */
        cbvh_contact one;
        const size_t k = capsule ? cbvh_contacts_capsule(fx->file, p0, p1, radius, 0, &one, 1, NULL)
                                 : cbvh_contacts_sphere(fx->file, p0, radius, 0, &one, 1, NULL);
        assert_int_equal(k, m > 0);
        if (k)
            assert_memory_equal(&one, &contacts[0], sizeof one);
    }
    printf("contacts: %zu, %zu of them with the core reaching the triangle\n", total, touching);
    assert_true(total > (size_t)count);
    free(ids);
    free(contacts);
}

static void test_contacts(void **state)
{
    (void)state;
    for (int m = 0; m < 3; m++) {
        scene s;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_sphere(&s, 3000, (float[3]){0, 0, 0}, 1.0f));
        else if (m == 1)
            assert_true(scene_terrain(&s, 3000, 40.0f));
        else
            assert_true(scene_soup(&s, 2000, 0.1f, 9));
        assert_int_equal(
            ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, test_options()),
            CBVH_OK);
        check_contacts(&fx, 200, 90 + (uint64_t)m);
        ref_fixture_close(&fx);
        scene_free(&s);
    }
    /* invalid input */
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 200, (float[3]){0, 0, 0}, 1.0f));
    assert_int_equal(
        ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, test_options()),
        CBVH_OK);
    const float c[3] = {0, 0, 0}, nan3[3] = {NAN, 0, 0};
    cbvh_contact out[2];
    int more = -1;
    assert_int_equal(cbvh_contacts_sphere(fx.file, c, -1.0f, 0, out, 2, &more), 0);
    assert_int_equal(more, 0);
    more = -1;
    assert_int_equal(cbvh_contacts_capsule(fx.file, c, nan3, 1.0f, 0, out, 2, &more), 0);
    assert_int_equal(more, 0);
    assert_int_equal(cbvh_contacts_capsule(fx.file, c, NULL, 1.0f, 0, out, 2, NULL), 0);
    assert_int_equal(cbvh_contacts_sphere(NULL, c, 1.0f, 0, out, 2, NULL), 0);
    /* a ball around the center of the closed unit sphere mesh, radius 1.5: every triangle, each pushed along
     * its normal toward the inside by about 1.5 - its distance */
    more = -1;
    assert_int_equal(cbvh_contacts_sphere(fx.file, c, 1.5f, 0, out, 2, &more), 2);
    assert_int_equal(more, 1);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* A ball's or capsule's core in the plane of an axis-aligned triangle gets the triangle's unit normal as
 * wound, (0, 0, 1) to the bit: no component a negative zero (which a frame edge taken as the negated
 * opposite edge, (-0, 1, -0) for (0, 1, 0), would give), the point the core's own. */
static void test_contact_normal_in_plane(void **state)
{
    (void)state;
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t indices[3] = {0, 1, 2};
    ref_fixture fx;
    assert_int_equal(ref_fixture_open(&fx, positions, 3, indices, 1, test_options()), CBVH_OK);
    const float center[3] = {0.25f, 0.25f, 0.0f}, below[3] = {0.25f, 0.25f, -0.0625f},
                above[3] = {0.25f, 0.25f, 0.0625f};
    for (int capsule = 0; capsule < 2; capsule++) {
        cbvh_contact c;
        const size_t n = capsule ? cbvh_contacts_capsule(fx.file, below, above, 0.125f, 0, &c, 1, NULL)
                                 : cbvh_contacts_sphere(fx.file, center, 0.125f, 0, &c, 1, NULL);
        assert_int_equal(n, 1);
        const uint32_t want[3] = {0u, 0u, 0x3f800000u}; /* +0, +0, 1 */
        for (int a = 0; a < 3; a++) {
            uint32_t bits;
            memcpy(&bits, &c.normal[a], sizeof bits);
            assert_int_equal(bits, want[a]);
            assert_true(c.point[a] == center[a]);
        }
    }
    ref_fixture_close(&fx);
}

/* Finding F4 addendum (notes/findings.md): a sphere overlap missed a sliver
 * of aspect 8e9 whose long edge passes 2.0 from the center of a sphere of
 * radius 3.26e8 (the float-era closest point lost every digit). The
 * finding's case, then spheres around points of slivers' long edges at
 * aspects 1e4 to 1e10: every sphere holding a point of the long edge (a
 * point-to-segment distance, exact enough in double) must report it, and
 * the reported set matches the reference. */
static void test_sliver_overlaps(void **state)
{
    (void)state;
    for (int e = 4; e <= 10; e++) {
        const float len = 3.7e9f;
        const float pos[9] = {0.0f, -len, 0.0f, 2.0f, -1.0f, 2.0f, 1.56f, -2.06f, 2.0f};
        float p[9];
        memcpy(p, pos, sizeof p);
        /* the finding's triangle at e = 10 (aspect 8e9); narrower ends shrink towards the long edge */
        const float shrink = e == 10 ? 1.0f : powf(10.0f, (float)(e - 10));
        for (int k = 1; k < 3; k++) {
            p[3 * k] *= shrink;
            p[3 * k + 2] *= shrink;
        }
        const uint32_t idx[3] = {0, 1, 2};
        ref_fixture fx;
        assert_int_equal(ref_fixture_open(&fx, p, 3, idx, 1, test_options()), CBVH_OK);
        uint64_t st = 5 + (uint64_t)e;
        for (int i = 0; i < 200; i++) {
            float center[3], radius;
            if (i == 0 && e == 10) {
                center[0] = 0.02f;
                center[1] = -3.2e9f;
                center[2] = -1.7f;
                radius = 3.26e8f;
            } else {
                const double f = rnd(&st, 0.05, 0.95), r = rnd(&st, 1.0, 1e8);
                for (int a = 0; a < 3; a++)
                    center[a] =
                        (float)((double)p[a] * (1.0 - f) + (double)p[3 + a] * f + rnd(&st, -0.7, 0.7) * r);
                radius = (float)r;
            }
            /* distance from the center to the long edge (vertex 0 - vertex 1) */
            double ab[3], ap[3], ab2 = 0, t = 0, d2 = 0;
            for (int a = 0; a < 3; a++) {
                ab[a] = (double)p[3 + a] - p[a];
                ap[a] = (double)center[a] - p[a];
                ab2 += ab[a] * ab[a];
                t += ab[a] * ap[a];
            }
            t = fmin(1.0, fmax(0.0, t / ab2));
            for (int a = 0; a < 3; a++)
                d2 += (ap[a] - t * ab[a]) * (ap[a] - t * ab[a]);
            uint32_t ids[2];
            const size_t n = cbvh_overlap_sphere(fx.file, center, radius, NULL, NULL, ids, 2);
            if (sqrt(d2) <= 0.999 * radius && n != 1)
                fail_msg(
                    "aspect 1e%d sphere %d: the long edge is %g from the center, radius %g, not reported", e,
                    i, sqrt(d2), (double)radius);
            region g = {SPHERE, {0, 0, 0}, {0, 0, 0}, {center[0], center[1], center[2]}, {0, 0, 0}, radius};
            check_set(&fx, ids, n, &g);
        }
        ref_fixture_close(&fx);
    }
}

/* The distance of p from segment a-b (clamped projection). */
static double point_segment_dist(cbvh_v3 p, cbvh_v3 a, cbvh_v3 b)
{
    const cbvh_v3 d = v3_sub(b, a);
    const double len2 = v3_len2(d), s = len2 > 0.0 ? v3_dot(v3_sub(p, a), d) / len2 : 0.0;
    return v3_len(v3_sub(p, v3_madd(a, d, s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s)));
}

/* cbvh_closest_segment_triangle against the reference's golden-section minimum, on random segments and
 * triangles and on the cases its candidates are chosen for: a segment crossing the triangle, one parallel to
 * it above its inside with both ends projecting outside, an end projecting inside, an end nearest an edge or
 * a vertex, segments of no length, and triangles of no area (two equal corners, three in a row). The points
 * it returns lie on the segment and the triangle and are as far apart as the distance it returns. */
static void test_segment_triangle_distance(void **state)
{
    (void)state;
    uint64_t st = 0x5e67e7;
    for (int r = 0; r < 6000; r++) {
        double tri[9], p0[3], p1[3];
        for (int k = 0; k < 9; k++)
            tri[k] = rnd(&st, -1.0, 1.0);
        for (int a = 0; a < 3; a++) {
            p0[a] = rnd(&st, -1.5, 1.5);
            p1[a] = rnd(&st, -1.5, 1.5);
        }
        const int shape = r % 8;
        if (shape == 1) /* two equal corners */
            memcpy(tri + 6, tri + 3, 3 * sizeof(double));
        if (shape == 2) /* three corners in a row */
            for (int a = 0; a < 3; a++)
                tri[6 + a] = tri[a] + 0.37 * (tri[3 + a] - tri[a]);
        if (shape == 3) /* no length */
            memcpy(p1, p0, sizeof p1);
        double n[3];
        ref_triangle_normal(tri, n);
        const double w = rnd(&st, 0.05, 0.3), h = rnd(&st, -0.2, 0.2);
        for (int a = 0; a < 3 && shape >= 4; a++) {
            const double inside = (tri[a] + tri[3 + a] + tri[6 + a]) / 3.0;
            const double edge_mid = 0.5 * (tri[a] + tri[3 + a]);
            if (shape == 4) { /* through the inside, across the plane */
                p0[a] = inside + n[a];
                p1[a] = inside - 0.5 * n[a];
            } else if (shape == 5) { /* parallel, above the inside, both ends beyond the triangle */
                const double along = tri[3 + a] - tri[6 + a];
                p0[a] = inside + h * n[a] - 2.0 * along;
                p1[a] = inside + h * n[a] + 2.0 * along;
            } else if (shape == 6) { /* one end over the inside, the other far */
                p0[a] = inside + w * n[a];
                p1[a] = inside + 3.0 * n[a] + (tri[3 + a] - tri[a]);
            } else { /* one end just outside an edge */
                p0[a] = edge_mid + 1e-9 * (edge_mid - inside) + h * 1e-6 * n[a];
            }
        }
        cbvh_v3 on_seg, on_tri;
        const double d2 = cbvh_closest_segment_triangle(
            v3(p0[0], p0[1], p0[2]), v3(p1[0], p1[1], p1[2]), v3(tri[0], tri[1], tri[2]),
            v3(tri[3], tri[4], tri[5]), v3(tri[6], tri[7], tri[8]), &on_seg, &on_tri);
        const double tol = 1e-7, ref = ref_segment_triangle_dist(tri, p0, p1);
        assert_true(fabs(sqrt(d2) - ref) <= tol);
        assert_true(fabs(sqrt(v3_len2(v3_sub(on_seg, on_tri))) - sqrt(d2)) <= tol);
        const double t[3] = {on_tri.x, on_tri.y, on_tri.z};
        assert_true(sqrt(ref_point_triangle_dist2(tri, t)) <= tol);
        if (shape == 2) /* corners in a row: the triangle is the segment of its first two */
            assert_true(point_segment_dist(on_tri, v3(tri[0], tri[1], tri[2]), v3(tri[3], tri[4], tri[5])) <=
                        tol);
        assert_true(point_segment_dist(on_seg, v3(p0[0], p0[1], p0[2]), v3(p1[0], p1[1], p1[2])) <= tol);
    }
}

/* The reference's point-triangle distance on triangles whose corners lie in a row (up to rounding): the
 * distance to the segment they span, whatever way the rounding tilts the plane. */
static void test_reference_point_distance_in_a_row(void **state)
{
    (void)state;
    uint64_t st = 0x12a0;
    for (int r = 0; r < 20000; r++) {
        double tri[9], p[3];
        const double at = rnd(&st, 0.05, 0.95);
        for (int a = 0; a < 3; a++) {
            tri[a] = rnd(&st, -1.0, 1.0);
            tri[3 + a] = rnd(&st, -1.0, 1.0);
            tri[6 + a] = tri[a] + at * (tri[3 + a] - tri[a]);
            p[a] = rnd(&st, -1.5, 1.5);
        }
        const double on = rnd(&st, -0.2, 1.2), off = r % 2 ? 0.0 : rnd(&st, 0.0, 1e-6);
        for (int a = 0; a < 3 && r % 4 < 2; a++) /* on or next to the segment */
            p[a] = tri[a] + on * (tri[3 + a] - tri[a]) + off * p[a];
        const double to_segment =
            point_segment_dist(v3(p[0], p[1], p[2]), v3(tri[0], tri[1], tri[2]), v3(tri[3], tri[4], tri[5]));
        assert_true(fabs(sqrt(ref_point_triangle_dist2(tri, p)) - to_segment) <= 1e-9);
    }
}

/* Every walk kernel the build and the CPU have (SSE2: four leaf triangles a vector; AVX2: eight; the scalar
 * kernel's overlaps are SSE2's) reports the same triangles, in the same order, with the same contacts bit
 * for bit, for balls, capsules, aligned and oriented boxes from a tenth of a triangle's size to many
 * triangles' (so that both the float tests of the leaves and the fine node tests run), so that a float test
 * dropping a triangle the exact test would keep changes an answer against the other kernel's. */
static void test_kernels_agree(void **state)
{
    (void)state;
    enum { CAP = 4096 };
    static cbvh_contact first[CAP], again[CAP];
    static uint32_t first_ids[CAP], again_ids[CAP];
    const int before = test_kernel_now;
    static const int kernels[] = {TEST_KERNEL_SSE2, TEST_KERNEL_AVX2};
    if (test_kernels_available(kernels, sizeof kernels / sizeof kernels[0]) < 2) {
        fprintf(stderr, "test_overlap: one walk kernel in this build and CPU, nothing to compare\n");
        skip();
    }
    long compared = 0, reported = 0, runs = 0;
    for (int m = 0; m < 3; m++) {
        scene sc;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_sphere(&sc, 4000, (float[3]){0.25f, 0.5f, -1.0f}, 1.0f));
        else if (m == 1)
            assert_true(scene_terrain(&sc, 4000, 40.0f));
        else
            assert_true(scene_soup(&sc, 3000, 0.1f, 19));
        assert_int_equal(ref_fixture_open(&fx, sc.positions, sc.vertex_count, sc.indices, sc.triangle_count,
                                          test_options()),
                         CBVH_OK);
        uint64_t st = 7000 + (uint64_t)m;
        for (long r = 0; r < test_reps(240); r++) {
            const size_t k = (size_t)(scene_rand_unit(&st) * (double)fx.tris.count);
            const double *tri = fx.tris.v + 9 * k;
            const double size = fx.diag * exp(rnd(&st, log(2e-4), log(0.1)));
            cbvh_shape s;
            memset(&s, 0, sizeof s);
            s.kind = (cbvh_shape_kind)(r % 3);
            for (int a = 0; a < 3; a++) {
                const double at = (tri[a] + tri[3 + a] + tri[6 + a]) / 3.0 + rnd(&st, -size, size);
                s.center[a] = s.p0[a] = (float)at;
                s.p1[a] = (float)(at + rnd(&st, -size, size));
                s.half_extent[a] = (float)rnd(&st, 0.2 * size, size);
                s.rotation[a] = r % 6 == 5 ? (float)rnd(&st, -1.0, 1.0) : 0.0f; /* every other box turned */
            }
            s.rotation[3] = r % 6 == 5 ? (float)rnd(&st, -1.0, 1.0) : 0.0f;
            s.radius = (float)size;
            size_t n_first = 0, n_ids = 0;
            int have = 0;
            for (size_t q = 0; q < sizeof kernels / sizeof kernels[0]; q++) {
                if (!test_set_kernel(kernels[q]))
                    continue;
                size_t n = 0, ids = 0;
                int more = 0;
                assert_int_equal(
                    cbvh_contacts_with(fx.file, &s, NULL, 0, have ? again : first, CAP, &n, &more), CBVH_OK);
                assert_false(more);
                assert_int_equal(
                    cbvh_overlap_with(fx.file, &s, NULL, 0, have ? again_ids : first_ids, CAP, &ids, &more),
                    CBVH_OK);
                if (have++) {
                    assert_int_equal(n, n_first);
                    assert_int_equal(ids, n_ids);
                    assert_memory_equal(again, first, n * sizeof first[0]);
                    assert_memory_equal(again_ids, first_ids, ids * sizeof first_ids[0]);
                    compared++;
                } else {
                    n_first = n;
                    n_ids = ids;
                }
            }
            runs++;
            reported += (long)n_first;
        }
        ref_fixture_close(&fx);
        scene_free(&sc);
    }
    test_set_kernel(before);
    fprintf(stderr, "test_overlap: kernels agree on %ld queries (%ld contacts), %ld comparisons\n", runs,
            reported, compared);
    assert_true(reported >= test_least(1000));
}

/* Triangles with one vertex at a face of an axis-aligned box, on it or off it by 0 to 2^16 ulps of the face's
 * coordinate (around the margin of the walk's float test of vertices in the box), the other two farther out
 * through that face: the triangle meets the closed box exactly when that vertex lies on the face's inner side
 * or on it. And triangles across an edge of the box, beyond the plane x_a + x_b = 2 e + d (vertices
 * (e + d, e), (e, e + d) and (e + 2d, e + 2d) on axes a, b, e the edge's coordinate on both, d from 1 to 2^15
 * ulps of e): their boxes meet the box and two vertices lie within d of it, yet they miss it.
 * cbvh_overlap_box and cbvh_overlap_with (an unturned box, whose float bounds the walk widens) against those
 * rules, near the origin and far from it. */
static void test_box_vertex_at_faces(void **state)
{
    (void)state;
    enum { FACES = 1200, N = FACES + 600 };
    static float positions[N * 9];
    static uint32_t indices[N * 3];
    static const double origins[3] = {0.0, 1000.0, -3e5};
    for (int o = 0; o < 3; o++) {
        const double base = origins[o], ext = o == 2 ? 40.0 : 2.0;
        float lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = (float)(base - 0.5 * ext + 0.1 * a);
            hi[a] = (float)(base + 0.5 * ext + 0.1 * a);
        }
        uint8_t expect[N];
        uint64_t st = 77 + (uint64_t)o;
        for (int i = FACES; i < N; i++) { /* across the edge of axes a and b at their high faces */
            const int a = i % 3, b = (a + 1) % 3, c = 3 - a - b, steps = 1 + (i / 3) % 16;
            const float ea = hi[a], eb = hi[b];
            float xa = ea, xb = eb;
            for (int k = 0; k < 1 << (steps - 1) && (double)xa - ea < 0.1 * ext; k++) {
                xa = nextafterf(xa, INFINITY);
                xb = nextafterf(xb, INFINITY);
            }
            const double z = lo[c] + (0.25 + 0.5 * scene_rand_unit(&st)) * (hi[c] - lo[c]);
            float v[3][3];
            v[0][a] = xa, v[0][b] = eb, v[0][c] = (float)z;
            v[1][a] = ea, v[1][b] = xb, v[1][c] = (float)z;
            v[2][a] = (float)(2.0 * xa - ea), v[2][b] = (float)(2.0 * xb - eb),
            v[2][c] = (float)(z + 0.1 * ext);
            memcpy(positions + 9 * i, v, sizeof v);
            for (int j = 0; j < 3; j++)
                indices[3 * i + j] = 3 * (uint32_t)i + (uint32_t)j;
            expect[i] = 0;
        }
        for (int i = 0; i < FACES; i++) {
            const int a = i % 3, high = (i / 3) % 2, out = (i / 6) % 2, steps = (i / 12) % 17;
            const float face = high ? hi[a] : lo[a];
            const float outward = high ? INFINITY : -INFINITY;
            float x =
                face; /* 0, 1, 2, 4, ... 2^15 ulps off the face, out or in, at most a tenth of the box */
            for (int k = 0; k < (steps == 0 ? 0 : 1 << (steps - 1)) && fabs((double)x - face) < 0.1 * ext;
                 k++)
                x = nextafterf(x, out ? outward : -outward);
            float v[3][3];
            for (int b = 0; b < 3; b++) {
                const double inner = lo[b] + (0.25 + 0.5 * scene_rand_unit(&st)) * (hi[b] - lo[b]);
                v[0][b] = b == a ? x : (float)inner;
                for (int j = 1; j < 3; j++)
                    v[j][b] =
                        b == a ? (float)(x + (high ? 1.0 : -1.0) * (0.2 + 0.3 * scene_rand_unit(&st)) * ext)
                               : (float)(inner + rnd(&st, -0.2, 0.2) * ext);
            }
            memcpy(positions + 9 * i, v, sizeof v);
            for (int j = 0; j < 3; j++)
                indices[3 * i + j] = 3 * (uint32_t)i + (uint32_t)j;
            expect[i] = high ? x <= face : x >= face;
        }
        ref_fixture fx;
        assert_int_equal(ref_fixture_open(&fx, positions, 3 * N, indices, N, test_options()), CBVH_OK);
        assert_int_equal(fx.tris.count, N);
        static uint32_t ids[N + 1];
        cbvh_shape box;
        memset(&box, 0, sizeof box);
        box.kind = CBVH_SHAPE_BOX;
        box.rotation[3] = 1.0f;
        for (int a = 0; a < 3; a++) {
            box.center[a] = (float)(0.5 * ((double)lo[a] + hi[a]));
            box.half_extent[a] = (float)(0.5 * ((double)hi[a] - lo[a]));
        }
        for (int api = 0; api < 2; api++) {
            size_t n = 0;
            if (api == 0) {
                n = cbvh_overlap_box(fx.file, lo, hi, NULL, NULL, ids, N + 1);
            } else { /* the exact box is center +- half extent, in double */
                assert_int_equal(cbvh_overlap_with(fx.file, &box, NULL, 0, ids, N + 1, &n, NULL), CBVH_OK);
                for (int i = 0; i < FACES; i++) {
                    const int a = i % 3, high = (i / 3) % 2;
                    const double x = positions[9 * i + a];
                    const double c = box.center[a], h = box.half_extent[a];
                    expect[i] = high ? x <= c + h : x >= c - h;
                }
            }
            uint8_t got[N] = {0};
            for (size_t k = 0; k < n; k++) {
                assert_true(ids[k] < N && !got[ids[k]]);
                got[ids[k]] = 1;
            }
            for (int i = 0; i < N; i++)
                if (got[i] != expect[i]) {
                    fprintf(stderr, "box vertex at faces: origin %g api %d tri %d got %d expected %d\n", base,
                            api, i, got[i], expect[i]);
                    fail();
                }
        }
        ref_fixture_close(&fx);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_overlaps),
        cmocka_unit_test(test_triangle_box_sat),
        cmocka_unit_test(test_invalid_input),
        cmocka_unit_test(test_sliver_overlaps),
        cmocka_unit_test(test_contacts),
        cmocka_unit_test(test_contact_normal_in_plane),
        cmocka_unit_test(test_grazing_rounds),
        cmocka_unit_test(test_segment_triangle_distance),
        cmocka_unit_test(test_reference_point_distance_in_a_row),
        cmocka_unit_test(test_kernels_agree),
        cmocka_unit_test(test_box_vertex_at_faces),
    };
    return TEST_RUN_LAYOUTS(tests, 1);
}
