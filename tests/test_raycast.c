/* test_raycast.c: ray kernels: watertight triangle test, robust slab test, every traversal against brute
 * force. */
#ifdef HAVE_CONFIG_H
#include "config.h" /* CBVH_HAVE_SIMD: the ray set-up as the library runs it */
#endif
#include <float.h>
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
#include "layout/encodings.h"
#include "query/ray_box.h"
#include "query/ray_triangle.h"
#include "query/raycast.h"
#include "query/walk.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

#define PI 3.14159265358979323846

static const cbvh_traversal traversals[4] = {CBVH_TRAVERSAL_SORTED, CBVH_TRAVERSAL_STACKLESS,
                                             CBVH_TRAVERSAL_UNSORTED, CBVH_TRAVERSAL_DISTANCE};

/* ------------------------------------------------------------------ */
/* Primitive tests, no file                                            */
/* ------------------------------------------------------------------ */

static int tri_hit(const float org[3], const float dir[3], const float *a, const float *b, const float *c,
                   float *t, float *u, float *v)
{
    const cbvh_ray ray = {{org[0], org[1], org[2]}, 0.0f, {dir[0], dir[1], dir[2]}, INFINITY};
    struct cbvh_ray_ctx ctx;
    memset(&ctx, 0, sizeof ctx); /* assert_true does not tell the compiler that a failed setup stops here */
    assert_true(cbvh_ray_setup(&ctx, &ray));
    const int hit = cbvh_ray_triangle(&ctx.shear, a, b, c, ctx.tmin, ctx.tmax, 1, t, u, v);
    if (hit)
        *t = cbvh_t_frame_out(&ctx.t_frame, *t); /* on the caller's ray */
    return hit;
}

static void test_triangle_basic(void **state)
{
    (void)state;
    const float a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    float t, u, v;
    /* Front and back: both windings hit, t and barycentrics exact for this simple case. */
    assert_true(tri_hit((float[3]){0.25f, 0.5f, 2.0f}, (float[3]){0, 0, -1}, a, b, c, &t, &u, &v));
    assert_true(t == 2.0f && u == 0.25f && v == 0.5f);
    assert_true(tri_hit((float[3]){0.25f, 0.5f, -2.0f}, (float[3]){0, 0, 0.5f}, a, b, c, &t, &u, &v));
    assert_true(t == 4.0f && u == 0.25f && v == 0.5f);
    assert_true(tri_hit((float[3]){0.25f, 0.5f, 2.0f}, (float[3]){0, 0, -1}, a, c, b, &t, &u, &v));
    /* Outside, behind the origin, in the plane (det == 0), degenerate triangle: misses. */
    assert_false(tri_hit((float[3]){0.75f, 0.5f, 2.0f}, (float[3]){0, 0, -1}, a, b, c, &t, &u, &v));
    assert_false(tri_hit((float[3]){0.25f, 0.25f, 2.0f}, (float[3]){0, 0, 1}, a, b, c, &t, &u, &v));
    assert_false(tri_hit((float[3]){-1.0f, 0.25f, 0.0f}, (float[3]){1, 0, 0}, a, b, c, &t, &u, &v));
    assert_false(
        tri_hit((float[3]){0.25f, 0.0f, 2.0f}, (float[3]){0, 0, -1}, a, b, (float[3]){2, 0, 0}, &t, &u, &v));
    /* On the edge and on a vertex: accepted (closed triangle). */
    assert_true(tri_hit((float[3]){0.5f, 0.0f, 1.0f}, (float[3]){0, 0, -1}, a, b, c, &t, &u, &v));
    assert_true(tri_hit((float[3]){1.0f, 0.0f, 1.0f}, (float[3]){0, 0, -1}, a, b, c, &t, &u, &v));
}

/* A fan of triangles around one shared vertex: every ray aimed at the shared
 * vertex or at a point of a shared edge must hit at least one triangle of the
 * fan (no leak), from either side and any direction. (Non-planar closed
 * surfaces are covered by test_closed_mesh_no_leaks.) */
static void test_watertight_fan(void **state)
{
    (void)state;
    enum { FAN = 13, RAYS = 20000 };
    float center[3] = {0.3f, 0.2f, 0.1f}, rim[FAN][3];
    uint64_t st = 12345;
    for (int k = 0; k < FAN; k++) {
        const double ang = 2.0 * PI * k / FAN + 0.2 * scene_rand_unit(&st);
        rim[k][0] = center[0] + (float)(cos(ang) * (1.0 + scene_rand_unit(&st)));
        rim[k][1] = center[1] + (float)(sin(ang) * (1.0 + scene_rand_unit(&st)));
        rim[k][2] = center[2]; /* planar: a folded fan can hide its vertex on a silhouette, legitimately */
    }
    long leaks = 0;
    for (int r = 0; r < RAYS; r++) {
        float target[3], org[3], dir[3];
        const int edge = (int)(scene_rand_unit(&st) * FAN);
        /* Half the rays at the shared vertex, half at a float point on a shared edge. */
        const float s = r % 2 ? (float)(0.05 + 0.85 * scene_rand_unit(&st)) : 0.0f;
        for (int a = 0; a < 3; a++)
            target[a] = center[a] + s * (rim[edge][a] - center[a]);
        const double z = 2.0 * scene_rand_unit(&st) - 1.0, phi = 2.0 * PI * scene_rand_unit(&st);
        const double dist = 0.5 + 10.0 * scene_rand_unit(&st);
        org[0] = target[0] + (float)(dist * sqrt(1 - z * z) * cos(phi));
        org[1] = target[1] + (float)(dist * sqrt(1 - z * z) * sin(phi));
        org[2] = target[2] + (float)(dist * z);
        for (int a = 0; a < 3; a++)
            dir[a] = target[a] - org[a];
        int hits = 0;
        for (int k = 0; k < FAN; k++) {
            float t, u, v;
            hits += tri_hit(org, dir, center, rim[k], rim[(k + 1) % FAN], &t, &u, &v);
        }
        /* The fan is planar and the targets lie in its plane, strictly inside
         * the union of the triangles: every ray must hit one. */
        if (hits == 0)
            leaks++;
    }
    assert_int_equal(leaks, 0);
}

/* Exact answer of "does [tmin, tmax] of the ray meet the closed box", in
 * double, with each axis handled by cases instead of reciprocals. Returns
 * the gap: <= 0 when they meet, else how far apart in t-interval terms. */
static double slab_reference(const double lo[3], const double hi[3], const double o[3], const double d[3],
                             double tmin, double tmax)
{
    double t0 = tmin, t1 = tmax;
    for (int a = 0; a < 3; a++) {
        if (d[a] == 0.0) {
            if (o[a] < lo[a] || o[a] > hi[a])
                return INFINITY;
            continue;
        }
        double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
    }
    return t0 - t1;
}

/* The per-ray choices the kernels compute without branches (ray_setup.h, ray_box.h) against their
 * definitions written out plainly: kz is the last axis of largest |dir| (so ties and zeros are covered),
 * kx and ky the next two in cyclic order, swapped when dir[kz] < 0 (not for -0); the near plane on axis a
 * is the maximum (3 + a) when the octant says the reciprocal is negative, else the minimum. */
static void test_shear_axes_and_slab_select(void **state)
{
    (void)state;
    static const float values[] = {0.0f,  -0.0f,  1.0f,    -1.0f,     2.0f,
                                   -2.0f, 1e-30f, -1e-30f, 0x1p-149f, -0x1p-149f};
    const size_t nv = sizeof values / sizeof values[0];
    size_t checked = 0;
    for (size_t i = 0; i < nv; i++)
        for (size_t j = 0; j < nv; j++)
            for (size_t k = 0; k < nv; k++) {
                const float dir[3] = {values[i], values[j], values[k]}, org[3] = {0.5f, -0.25f, 3.0f};
                if (dir[0] == 0.0f && dir[1] == 0.0f && dir[2] == 0.0f)
                    continue;
                struct cbvh_ray_shear s;
                cbvh_shear_setup(&s, org, dir);
                uint32_t kz = 0;
                for (uint32_t a = 0; a < 3; a++)
                    if (fabsf(dir[a]) >= fabsf(dir[kz]))
                        kz = a;
                uint32_t kx = (kz + 1u) % 3u, ky = (kz + 2u) % 3u;
                if (dir[kz] < 0.0f) {
                    const uint32_t t = kx;
                    kx = ky;
                    ky = t;
                }
                if (s.kz != kz || s.kx != kx || s.ky != ky)
                    fail_msg("dir (%g, %g, %g): axes (%u, %u, %u), expected (%u, %u, %u)", (double)dir[0],
                             (double)dir[1], (double)dir[2], s.kx, s.ky, s.kz, kx, ky, kz);
                checked++;
            }
    assert_int_equal(checked, nv * nv * nv - 8); /* every direction but the 8 all-zero ones */
    for (uint32_t octant = 0; octant < 8; octant++) {
        const struct cbvh_slab_select sel = cbvh_slab_select_of(octant);
        const uint32_t near[3] = {sel.near_x, sel.near_y, sel.near_z},
                       far[3] = {sel.far_x, sel.far_y, sel.far_z};
        for (uint32_t a = 0; a < 3; a++) {
            assert_int_equal(near[a], octant >> a & 1u ? 3u + a : a);
            assert_int_equal(far[a], octant >> a & 1u ? a : 3u + a);
        }
    }
}

/* The wide layout's orders are the 24 permutations of four slots in lexicographic order, and its visit
 * table (what the walk visits of a node, by order and hit mask) lists the hit slots of each order in that
 * order, two bits each. */
static void test_wide4_visit_table(void **state)
{
    (void)state;
    for (uint32_t o = 0; o < CBVH_W4_ORDERS; o++) {
        const uint8_t *p = cbvh_wide4_orders[o];
        assert_true(p[0] < 4 && p[1] < 4 && p[2] < 4 && p[3] < 4);
        assert_int_equal((1u << p[0]) | (1u << p[1]) | (1u << p[2]) | (1u << p[3]), 0xFu);
        if (o > 0)
            assert_true(memcmp(cbvh_wide4_orders[o - 1], p, 4) < 0);
        for (uint32_t hits = 0; hits < 16; hits++) {
            uint32_t expected = 0, n = 0;
            for (int k = 0; k < 4; k++) {
                if (hits >> p[k] & 1u)
                    expected |= (uint32_t)p[k] << (2u * n++);
            }
            if (cbvh_wide4_visits[o][hits] != expected || cbvh_w4_popcount(hits) != n)
                fail_msg("order %u hits %x: visit %02x, expected %02x (%u slots)", o, hits,
                         cbvh_wide4_visits[o][hits], expected, n);
        }
    }
}

/* The descent table (how the SIMD walks go down a node) follows the visit order: byte 3 is the first
 * child visited, bytes 0 .. n - 2 the others from the last visited (pushed first, popped last) to the
 * second. */
static void test_wide4_descent_table(void **state)
{
    (void)state;
    for (uint32_t o = 0; o < CBVH_W4_ORDERS; o++)
        for (uint32_t hits = 1; hits < 16; hits++) {
            uint32_t list[4], n = 0;
            for (int k = 0; k < 4; k++)
                if (hits >> cbvh_wide4_orders[o][k] & 1u)
                    list[n++] = cbvh_wide4_orders[o][k];
            const uint32_t d = cbvh_wide4_descents[o][hits];
            if ((d >> 24) != list[0])
                fail_msg("order %u hits %x: descent %08x goes on to slot %u, not %u", o, hits, d, d >> 24,
                         list[0]);
            for (uint32_t j = 0; j + 1 < n; j++)
                if ((d >> (8u * j) & 0xFFu) != list[n - 1u - j])
                    fail_msg("order %u hits %x: descent %08x pushes slot %u at %u, not %u", o, hits, d,
                             d >> (8u * j) & 0xFFu, j, list[n - 1u - j]);
        }
}

#ifdef CBVH_HAVE_SIMD
/* walk_w4_refs, the SIMD walks' references of all four slots at once, gives cbvh_w4_child_ref's for
 * every used slot of every node a file can hold: each set of used and internal slots, every leaf count. */
static void test_wide4_refs(void **state)
{
    (void)state;
    long checked = 0;
    uint8_t node[CBVH_W4_NODE_SIZE];
    memset(node, 0, sizeof node);
    for (uint32_t used = 1; used < 16; used++)
        for (uint32_t internal = 0; internal < 16; internal++) {
            if (internal & ~used)
                continue;
            const uint32_t leaves = used & ~internal;
            for (uint32_t c = 0; c < 4096u; c++) { /* three bits a slot: count - 1 of each leaf */
                if (c & ~(0u + (leaves & 1u ? 07u : 0u) + (leaves & 2u ? 070u : 0u) +
                          (leaves & 4u ? 0700u : 0u) + (leaves & 8u ? 07000u : 0u)))
                    continue;
                uint32_t count[4], order[8] = {0};
                for (uint32_t s = 0; s < 4; s++)
                    count[s] = (c >> (3u * s) & 7u) + 1u;
                const uint64_t meta = cbvh_w4_make_meta(count, used, internal, order);
                const uint32_t first_child = 0x7FFFFFF0u - 7u * c, first_triangle = 0x0FFFFFD0u - 5u * c;
                memcpy(node + CBVH_W4_FIRST_CHILD, &first_child, 4);
                memcpy(node + CBVH_W4_FIRST_TRIANGLE, &first_triangle, 4);
                _Alignas(16) uint32_t refs[4];
                _mm_store_si128((__m128i *)(void *)refs, walk_w4_refs(node, meta));
                for (uint32_t s = 0; s < 4; s++)
                    if ((used >> s & 1u) && refs[s] != cbvh_w4_child_ref(node, meta, s))
                        fail_msg("used %x internal %x counts %o slot %u: %08x, expected %08x", used, internal,
                                 c, s, refs[s], cbvh_w4_child_ref(node, meta, s));
                checked++;
            }
        }
    assert_int_equal(checked, 9999); /* each slot unused, internal or a leaf of 1..8: 10^4, less all unused */
}
#endif

static void test_slab_edge_cases(void **state)
{
    (void)state;
    const float dirs[] = {0.0f, -0.0f, 1e-40f, -1e-40f, 1e30f, -1e30f, 1.0f, -1.0f, 0.37f, -3.0f};
    const float coords[] = {-2.0f, -1.0f, 0.0f, 0.5f, 1.0f, 1.5f, 3.0f};
    const float boxes[][6] = {{-1, -1, -1, 1, 1, 1},
                              {0, 0, 0, 0, 0, 0},
                              {-1e30f, 0, 0.5f, 1e30f, 1, 0.5f},
                              {1e-38f, -1e-38f, 0, 2e-38f, 1e-38f, 1}};
    long checked = 0;
    for (size_t bx = 0; bx < sizeof(boxes) / sizeof(boxes[0]); bx++)
        for (size_t i = 0; i < 1000000 && checked < 300000; i++) {
            uint64_t st = i * 7919u + bx;
            cbvh_ray ray;
            for (int a = 0; a < 3; a++) {
                ray.org[a] = coords[scene_rand_next(&st) % 7];
                if (scene_rand_next(&st) % 3 == 0) /* origins on the box's own planes */
                    ray.org[a] = boxes[bx][a + 3 * (int)(scene_rand_next(&st) % 2)];
                ray.dir[a] = dirs[scene_rand_next(&st) % 10];
            }
            ray.tmin = scene_rand_next(&st) % 2 ? 0.0f : 0.5f;
            ray.tmax = scene_rand_next(&st) % 2 ? INFINITY : 2.0f;
            struct cbvh_ray_ctx ctx;
            if (!cbvh_ray_setup(&ctx, &ray))
                continue;
            const struct cbvh_slab_select sel = cbvh_slab_select_of(ctx.octant);
            const float *b = boxes[bx];
            float entry;
            const int hit =
                cbvh_slab_test(b[sel.near_x], b[sel.near_y], b[sel.near_z], b[sel.far_x], b[sel.far_y],
                               b[sel.far_z], ctx.shear.org, ctx.rcp, ctx.tmin, ctx.tmax, &entry);
            /* the rays' pre-test of a file's top box (raycast.h) decides as this test does, ray for ray */
            struct cbvh_file top;
            memset(&top, 0, sizeof top);
            memcpy(top.top_lo, b, 3 * sizeof(float));
            memcpy(top.top_hi, b + 3, 3 * sizeof(float));
            assert_int_equal(cbvh_ray_enters_top_box(&ctx, ray.org, &top), hit);
            const double lo[3] = {b[0], b[1], b[2]}, hi[3] = {b[3], b[4], b[5]};
            const double o[3] = {ray.org[0], ray.org[1], ray.org[2]},
                         d[3] = {ray.dir[0], ray.dir[1], ray.dir[2]};
            const double gap =
                slab_reference(lo, hi, o, d, ray.tmin, ray.tmax < CBVH_T_LIMIT ? ray.tmax : CBVH_T_LIMIT);
            if (gap <= 0.0 && !hit) {
                fprintf(stderr, "box %zu missed: org %g %g %g dir %g %g %g t [%g %g]\n", bx, o[0], o[1], o[2],
                        d[0], d[1], d[2], ray.tmin, ray.tmax);
                fail();
            }
            /* Clear misses must be misses: a ray that stays away from the box
             * grown by 1e-5 in space (a direction too small for its reciprocal
             * to be finite moves the ray by less than that). */
            double glo[3], ghi[3];
            for (int a = 0; a < 3; a++) {
                glo[a] = lo[a] - 1e-5 * (1.0 + fabs(lo[a]));
                ghi[a] = hi[a] + 1e-5 * (1.0 + fabs(hi[a]));
            }
            if (hit && slab_reference(glo, ghi, o, d, ray.tmin, ray.tmax) > 0.0) {
                fprintf(stderr, "box %zu false hit: org %g %g %g dir %g %g %g t [%g %g]\n", bx, o[0], o[1],
                        o[2], d[0], d[1], d[2], ray.tmin, ray.tmax);
                fail();
            }
            checked++;
        }
    assert_true(checked > 1000);
    /* Lines through an edge of a box, where the entry and exit distances agree but for rounding (the slab
     * test's pad decides about half of them): the pre-test decides as the slab test, ray for ray. */
    const float box[6] = {0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f};
    struct cbvh_file top;
    memset(&top, 0, sizeof top);
    memcpy(top.top_lo, box, 3 * sizeof(float));
    memcpy(top.top_hi, box + 3, 3 * sizeof(float));
    long padded = 0;
    for (uint64_t i = 0; i < 20000; i++) {
        uint64_t st = 1000003u * i + 17u;
        cbvh_ray ray = {{0, 0, 0}, 0.0f, {0, 0, 0}, INFINITY};
        const float corner[3] = {1.0f, 1.0f, 0.25f + 0.5f * (float)scene_rand_unit(&st)};
        ray.org[0] = (float)(0.9 * scene_rand_unit(&st));
        ray.org[1] = (float)(1.1 + 2.0 * scene_rand_unit(&st));
        ray.org[2] = corner[2];
        for (int a = 0; a < 3; a++)
            ray.dir[a] = corner[a] - ray.org[a];
        struct cbvh_ray_ctx ctx;
        memset(&ctx, 0,
               sizeof ctx); /* set up below; the compiler cannot see that a failed assert ends the test */
        assert_true(cbvh_ray_setup(&ctx, &ray));
        const struct cbvh_slab_select sel = cbvh_slab_select_of(ctx.octant);
        float entry;
        const int hit =
            cbvh_slab_test(box[sel.near_x], box[sel.near_y], box[sel.near_z], box[sel.far_x], box[sel.far_y],
                           box[sel.far_z], ctx.shear.org, ctx.rcp, ctx.tmin, ctx.tmax, &entry);
        assert_int_equal(cbvh_ray_enters_top_box(&ctx, ray.org, &top), hit);
        const float exit_x = (box[3] - ray.org[0]) * ctx.rcp[0];
        padded += entry > exit_x;
    }
    assert_true(padded > 100);
}

#ifdef CBVH_HAVE_SIMD
/* The wide layout's affine box test (walk.h, struct cbvh_w4_simd_ray) against the slab test in double on
 * the dequantized planes: it must enter every box that test enters, with an entry distance no later, and
 * miss the boxes the ray stays clear of. Grids and rays from ordinary to extreme (denormal scales, origins
 * and coordinates near 1e30, directions from 1e-30 to 1e20); the rays the affine form cannot take (a zero
 * or tiny direction component, overflow) take the exact form, which is checked the same way. */
static void test_wide4_affine_box_test(void **state)
{
    (void)state;
    const float grid_origins[] = {0.0f, -1.0f, 3.5f, 1e6f, -2e30f, 1e-30f};
    const float grid_scales[] = {1e-5f, 3e-4f, 0.0f, 1e-40f, 2e25f, 1.0f};
    const float coords[] = {0.0f, -0.5f, 0.7f, 2.0f, 1e6f, -1e6f, 1e30f, -1e30f, 1e-30f};
    const float dirs[] = {1.0f, -1.0f, 0.37f, -3.0f, 1e-3f, 1e-20f, -1e-30f, 1e20f, 0.0f, -0.0f};
    long affine = 0, exact = 0, entered = 0;
    uint64_t st = 12345;
    for (int i = 0; i < test_reps(200000); i++) {
        /* three rays in four on ordinary grids (the first three origins and scales) */
        const uint64_t extreme = scene_rand_next(&st) % 4 == 0 ? 3u : 0u;
        float go[3], gs[3];
        for (int a = 0; a < 3; a++) {
            go[a] = grid_origins[scene_rand_next(&st) % (3u + extreme)];
            gs[a] = grid_scales[scene_rand_next(&st) % (3u + extreme)];
        }
        uint8_t node[CBVH_W4_NODE_SIZE] = {0};
        double lo[4][3], hi[4][3];
        for (uint32_t s = 0; s < 4; s++)
            for (uint32_t a = 0; a < 3; a++) {
                uint32_t q0 = (uint32_t)(scene_rand_next(&st) % 65536),
                         q1 = (uint32_t)(scene_rand_next(&st) % 65536);
                if (scene_rand_next(&st) % 4 == 0)
                    q1 = q0; /* flat boxes */
                if (q0 > q1) {
                    const uint32_t x = q0;
                    q0 = q1;
                    q1 = x;
                }
                const uint16_t v0 = (uint16_t)q0, v1 = (uint16_t)q1;
                memcpy(node + cbvh_w4_plane_offset(a, s), &v0, 2);
                memcpy(node + cbvh_w4_plane_offset(3u + a, s), &v1, 2);
                lo[s][a] = cbvh_dequantize(q0, go[a], gs[a]);
                hi[s][a] = cbvh_dequantize(q1, go[a], gs[a]);
            }
        cbvh_ray ray;
        for (int a = 0; a < 3; a++) {
            /* origins on a plane of a box, inside the grid, near its origin, or anywhere; directions
             * mostly ordinary, some tiny, huge or zero */
            const uint64_t pick = scene_rand_next(&st) % 4;
            const float inside = go[a] + gs[a] * (float)(scene_rand_next(&st) % 65536);
            ray.org[a] = pick == 0   ? (float)lo[scene_rand_next(&st) % 4][a]
                         : pick == 1 ? inside
                         : pick == 2 ? go[a] + coords[scene_rand_next(&st) % 9] * 1e-3f
                                     : coords[scene_rand_next(&st) % 9];
            ray.dir[a] = dirs[scene_rand_next(&st) % (scene_rand_next(&st) % 8 ? 4 : 10)];
        }
        ray.tmin = scene_rand_next(&st) % 2 ? 0.0f : 0.25f;
        ray.tmax = scene_rand_next(&st) % 2 ? INFINITY : 1e3f;
        struct cbvh_ray_ctx ctx;
        if (!cbvh_ray_setup(&ctx, &ray))
            continue;
        if (!isfinite(cbvh_dequantize(CBVH_Q_MAX, go[0], gs[0])) ||
            !isfinite(cbvh_dequantize(CBVH_Q_MAX, go[1], gs[1])) ||
            !isfinite(cbvh_dequantize(CBVH_Q_MAX, go[2], gs[2])))
            continue; /* a grid the loader rejects */
        struct cbvh_box_ray box;
        cbvh_box_ray_init(&box, go, gs, ctx.shear.org, ctx.rcp, ctx.octant);
        struct cbvh_w4_simd_ray w;
        walk_w4_simd_ray_init(&w, &box, go, gs, ctx.shear.org, ctx.rcp, ctx.octant, 0u, ctx.tmin);
        if (w.exact)
            exact++;
        else
            affine++;
        float entry[4];
        const uint32_t hits = walk_w4_test_sse2(node, &w, ctx.tmax, entry);
        const double o[3] = {ctx.shear.org[0], ctx.shear.org[1], ctx.shear.org[2]};
        const double d[3] = {ctx.shear.dir[0], ctx.shear.dir[1], ctx.shear.dir[2]}; /* the kernels' ray */
        for (uint32_t s = 0; s < 4; s++) {
            /* the exact slab test on the float planes, and the entry it finds */
            double t0 = ctx.tmin, t1 = ctx.tmax;
            for (int a = 0; a < 3; a++) {
                if (d[a] == 0.0) {
                    if (o[a] < lo[s][a] || o[a] > hi[s][a])
                        t0 = INFINITY;
                    continue;
                }
                const double ta = (lo[s][a] - o[a]) / d[a], tb = (hi[s][a] - o[a]) / d[a];
                t0 = fmax(t0, fmin(ta, tb));
                t1 = fmin(t1, fmax(ta, tb));
            }
            if (t0 <= t1) {
                entered++;
                /* the exact form's entry may round late, by less than the pad of ray_box.h, or by a few
                 * subnormal steps on the extreme grids with subnormal scales (outside the exact range of
                 * docs/EXACTNESS.md: no cooked file has them) */
                const double late = w.exact ? fabs(t0) * 0x1p-21 + 0x1p-146 : 0.0;
                if (!(hits >> s & 1u) || !((double)entry[s] <= t0 + late))
                    fail_msg(
                        "%s test: box %u missed or entered late (entry %.9g, exact %.9g): org %g %g %g dir "
                        "%g %g %g grid %g %g %g / %g %g %g",
                        w.exact ? "exact" : "affine", s, (double)entry[s], t0, o[0], o[1], o[2], d[0], d[1],
                        d[2], (double)go[0], (double)go[1], (double)go[2], (double)gs[0], (double)gs[1],
                        (double)gs[2]);
            }
            /* clear misses stay misses: the box grown by 1e-5 of the size of its coordinates, the origin's
             * and the grid's, and by the ray's travel over the affine form's least pad in t, 2^-120 */
            double glo[3], ghi[3];
            const double travel = 0x1p-118 * (fabs(d[0]) + fabs(d[1]) + fabs(d[2]));
            for (int a = 0; a < 3; a++) {
                const double grid = fabs(go[a]) + CBVH_Q_MAX * (double)gs[a];
                const double grow = 1e-5 * (fabs(lo[s][a]) + fabs(hi[s][a]) + fabs(o[a]) + grid) + travel;
                glo[a] = lo[s][a] - grow;
                ghi[a] = hi[s][a] + grow;
            }
            if ((hits >> s & 1u) && slab_reference(glo, ghi, o, d, ctx.tmin, ctx.tmax * 1.00001) > 0.0)
                fail_msg("%s test: box %u entered at %.9g, but the ray stays clear of it: org %g %g %g dir "
                         "%g %g %g t "
                         "[%g %g] box %g %g %g - %g %g %g grid %g %g %g / %g %g %g",
                         w.exact ? "exact" : "affine", s, (double)entry[s], o[0], o[1], o[2], d[0], d[1],
                         d[2], (double)ctx.tmin, (double)ctx.tmax, lo[s][0], lo[s][1], lo[s][2], hi[s][0],
                         hi[s][1], hi[s][2], (double)go[0], (double)go[1], (double)go[2], (double)gs[0],
                         (double)gs[1], (double)gs[2]);
        }
    }
    printf("affine box test: %ld rays affine, %ld exact, %ld boxes entered\n", affine, exact, entered);
    assert_true(affine > test_least(100000) && exact > test_least(20000) && entered > test_least(10000));
}
#endif

/* ------------------------------------------------------------------ */
/* End to end                                                          */
/* ------------------------------------------------------------------ */

/* Tolerance on t for a ray: float rounding of coordinates of this size, in units of dir. */
static double t_tolerance(const ref_fixture *fx, const cbvh_ray *ray, double t)
{
    double scale = fx->diag, dl = 0.0;
    for (int a = 0; a < 3; a++) {
        scale = fmax(scale, fmax(fabs(fx->lo[a]), fabs(fx->hi[a])));
        scale = fmax(scale, fabs(ray->org[a]));
        dl += (double)ray->dir[a] * ray->dir[a];
    }
    return 2e-5 * scale / sqrt(dl) + 1e-6 * fabs(t);
}

static long checks_done;

/* A closest hit (or miss) from the kernel against the reference: a robust
 * hit (well inside a triangle and the t range) must be found; what is found
 * must be a hit of that triangle within tolerance, no farther than the
 * robust closest hit and no nearer than any near-hit. */
static void check_closest(const ref_fixture *fx, const cbvh_ray *ray, int hit, const cbvh_hit *h)
{
    ref_ray_hit strict, loose;
    if (!ref_ray_valid(ray)) {
        assert_false(hit);
        assert_int_equal(h->tri, CBVH_NO_HIT);
        return;
    }
    const double tol = t_tolerance(fx, ray, 0.0), slack = 2e-5 * fx->diag;
    cbvh_ray in = *ray, out = *ray;
    in.tmin = (float)(ray->tmin + tol);
    in.tmax = (float)(ray->tmax - tol);
    out.tmin = (float)fmax(0.0, ray->tmin - tol);
    out.tmax = (float)(ray->tmax + tol);
    const int rs = in.tmin <= in.tmax && ref_ray_closest(&fx->tris, &in, -slack, &strict);
    const int rl = ref_ray_closest(&fx->tris, &out, slack, &loose);
    checks_done++;
    if (!hit) {
        assert_int_equal(h->tri, CBVH_NO_HIT);
        if (rs)
            fprintf(stderr, "missed a robust hit: tri %u t %.9g margin %g\n", strict.tri, strict.t,
                    strict.margin);
        assert_false(rs);
        return;
    }
    assert_true(rl);
    assert_true(h->tri < fx->id_count);
    const size_t k = fx->index_of_id[h->tri];
    assert_true(k != (size_t)-1);
    /* The reported point must lie on the reported triangle (a distance test:
     * barycentrics of a plane crossing are ill-conditioned at grazing angles). */
    const double tol_t = t_tolerance(fx, ray, h->t);
    double p[3], dl2 = 0.0;
    for (int a = 0; a < 3; a++) {
        p[a] = ray->org[a] + (double)h->t * ray->dir[a];
        dl2 += (double)ray->dir[a] * ray->dir[a];
    }
    const double off = sqrt(ref_point_triangle_dist2(fx->tris.v + 9 * k, p));
    if (!(off <= tol_t * sqrt(dl2))) {
        fprintf(stderr, "hit tri %u t %.9g: the point is %g off the triangle\n", h->tri, h->t, off);
        fail();
    }
    if (rs && !(h->t <= strict.t + tol_t)) {
        fprintf(stderr, "hit t %.9g beyond the robust closest %.9g (tri %u)\n", h->t, strict.t, strict.tri);
        fail();
    }
    assert_true(h->t >= loose.t - tol_t);
    double t, u, v, m;
    if (ref_ray_triangle(fx->tris.v + 9 * k, ray, &t, &u, &v, &m) && m > slack) {
        /* well inside the triangle: the barycentrics agree */
        assert_true(fabs(u - h->u) < 1e-3 && fabs(v - h->v) < 1e-3);
    }
}

/* Casts rays with every traversal: all four give the same hit (triangle, t,
 * u, v identical thanks to the shared triangle test and tie rule), any-hit
 * agrees with closest-hit, and the hit matches the reference. */
static void check_fixture(const ref_fixture *fx, int rays, uint64_t seed)
{
    uint64_t st = seed;
    rays = (int)test_reps(rays);
    for (int r = 0; r < rays; r++) {
        const cbvh_ray ray = ref_make_ray(fx, &st, r % REF_RAY_KINDS);
        cbvh_hit h[4];
        int hit[4];
        for (int k = 0; k < 4; k++) {
            hit[k] = cbvh_raycast(fx->file, &ray, traversals[k], &h[k], NULL);
            const int occ = cbvh_occluded(fx->file, &ray, traversals[k], NULL);
            assert_int_equal(occ, hit[k]);
        }
        for (int k = 1; k < 4; k++) {
            assert_int_equal(hit[k], hit[0]);
            assert_int_equal(h[k].tri, h[0].tri);
            if (hit[0])
                assert_true(h[k].t == h[0].t && h[k].u == h[0].u && h[k].v == h[0].v);
        }
        check_closest(fx, &ray, hit[0], &h[0]);
    }
}

static void open_scene(ref_fixture *fx, scene *s, const cbvh_cook_options *options)
{
    assert_int_equal(
        ref_fixture_open(fx, s->positions, s->vertex_count, s->indices, s->triangle_count, options), CBVH_OK);
}

/* The filter of test_any_hit_order: the t of the first candidate it sees, then REJECT (the walk goes on). */
static cbvh_filter_result first_candidate(void *user, const cbvh_hit_record *candidate)
{
    float *first = user;
    if (*first < 0.0f)
        *first = candidate->t;
    return CBVH_FILTER_REJECT;
}

/* The order an any-hit walk visits children in (ray_setup.h's any_flip): from an origin inside the mesh's
 * bounds the farthest first, from outside the nearest first, on every layout and kernel and on both
 * sides of each axis. Eight parallel squares one apart, leaves of two triangles (one square): a ray along
 * the axis through all of them from inside the bounds (half way between squares 0 and 1) sees its first
 * candidate in the far half, one from outside in the near half; a closest-hit query, the nearest first
 * either way, is not flipped. */
static void test_any_hit_order(void **state)
{
    (void)state;
    for (int axis = 0; axis < 3; axis++)
        for (int sign = -1; sign <= 1; sign += 2) {
            float pos[8 * 4 * 3];
            uint32_t idx[8 * 6];
            for (int q = 0; q < 8; q++) {
                const float corners[4][2] = {{-4, -4}, {4, -4}, {4, 4}, {-4, 4}};
                for (int c = 0; c < 4; c++) {
                    float *p = pos + 3 * (4 * q + c);
                    p[axis] = (float)(sign * q);
                    p[(axis + 1) % 3] = corners[c][0];
                    p[(axis + 2) % 3] = corners[c][1];
                }
                const uint32_t b = 4u * (uint32_t)q, tri[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
                memcpy(idx + 6 * q, tri, sizeof tri);
            }
            cbvh_cook_options co;
            test_options_init(&co);
            co.max_leaf_size = 2;
            ref_fixture fx;
            assert_int_equal(ref_fixture_open(&fx, pos, 32, idx, 16, &co), CBVH_OK);
            const float starts[2] = {0.5f, -1.5f}; /* inside the bounds, then outside */
            for (int outside = 0; outside < 2; outside++)
                for (int any = 1; any >= 0; any--) {
                    cbvh_ray ray = {{0.25f, -0.5f, 0.75f}, 0.0f, {0, 0, 0}, INFINITY};
                    ray.org[axis] = (float)sign * starts[outside];
                    ray.dir[axis] = (float)sign;
                    float first = -1.0f;
                    cbvh_query_options opt;
                    assert_int_equal(cbvh_query_options_init(&opt, sizeof opt), CBVH_OK);
                    opt.filter = first_candidate;
                    opt.filter_user = &first;
                    int occluded = -1;
                    cbvh_hit_record rec;
                    if (any)
                        assert_int_equal(cbvh_occluded_with(fx.file, &ray, &opt, &occluded, NULL), CBVH_OK);
                    else
                        assert_int_equal(cbvh_raycast_with(fx.file, &ray, &opt, &rec, NULL), CBVH_OK);
                    const float t0 = 1.0f - starts[outside], far = !outside && any ? 1.0f : 0.0f;
                    /* squares 1..7 (inside) or 0..7 (outside) lie at t0 .. 7 - starts */
                    const int in_far_half = first > 0.5f * (t0 + 7.0f - starts[outside]);
                    if (!(first >= t0 - 1.0f) || in_far_half != (far > 0.0f))
                        fail_msg(
                            "%s axis %d sign %d, origin %s: first candidate at t %g, expected in the %s half",
                            test_layout_name(), axis, sign, outside ? "outside" : "inside", (double)first,
                            far > 0.0f ? "far" : "near");
                }
            ref_fixture_close(&fx);
        }
}

static void test_soup(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_soup(&s, 3000, 0.1f, 7));
    open_scene(&fx, &s, test_options());
    check_fixture(&fx, 4000, 1);
    ref_fixture_close(&fx);
    scene_free(&s);
}

static void test_sphere_and_terrain(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 4000, (float[3]){0.5f, -0.25f, 2.0f}, 3.0f));
    open_scene(&fx, &s, test_options());
    check_fixture(&fx, 3000, 2);
    ref_fixture_close(&fx);
    scene_free(&s);
    assert_true(scene_terrain(&s, 4000, 50.0f));
    open_scene(&fx, &s, test_options());
    check_fixture(&fx, 3000, 3);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* Every cook variant gives files the kernels read alike: quantized vertices,
 * cooked ids, zlib sections, the smallest and largest leaves. */
static void test_cook_variants(void **state)
{
    (void)state;
    scene s;
    assert_true(scene_soup(&s, 1500, 0.15f, 99));
    for (int variant = 0; variant < 5; variant++) {
        cbvh_cook_options o;
        test_options_init(&o);
        if (variant == 0)
            o.vertex_format = CBVH_VERTEX_QUANTIZED16;
        if (variant == 1)
            o.keep_remap = 0;
        if (variant == 2)
            o.compress_level = 6;
        if (variant == 3)
            o.max_leaf_size = 1;
        if (variant == 4)
            o.max_leaf_size = 16;
        ref_fixture fx;
        open_scene(&fx, &s, &o);
        check_fixture(&fx, 1500, 10 + (uint64_t)variant);
        ref_fixture_close(&fx);
    }
    scene_free(&s);
}

/* A closed mesh leaks no ray: from inside, aimed at its vertices (shared by
 * up to dozens of triangles at the poles), at edge points and anywhere. */
static void test_closed_mesh_no_leaks(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    const float c[3] = {0.1f, 0.2f, 0.3f};
    assert_true(scene_sphere(&s, 20000, c, 1.0f));
    open_scene(&fx, &s, test_options());
    uint64_t st = 5;
    long missed = 0, total = 0;
    const size_t stride = (size_t)test_reps_stride(1);
    for (size_t vtx = 0; vtx < s.vertex_count; vtx += stride) {
        for (int kind = 0; kind < 3; kind++) {
            cbvh_ray ray = {{c[0], c[1], c[2]}, 0.0f, {0, 0, 0}, INFINITY};
            const float *p = s.positions + 3 * vtx, *q = s.positions + 3 * ((vtx + 1) % s.vertex_count);
            for (int a = 0; a < 3; a++) {
                if (kind == 0)
                    ray.dir[a] = p[a] - c[a];
                else if (kind == 1) /* a point on a float edge between neighbouring vertices */
                    ray.dir[a] = 0.5f * (p[a] + q[a]) - c[a];
                else
                    ray.dir[a] = (float)(scene_rand_unit(&st) - 0.5);
                if (kind != 2) /* from an inner point off the center, too */
                    ray.org[a] = c[a] + 0.3f * (float)(scene_rand_unit(&st) - 0.5);
            }
            if (kind != 2)
                for (int a = 0; a < 3; a++)
                    ray.dir[a] = (kind == 0 ? p[a] : 0.5f * (p[a] + q[a])) - ray.org[a];
            for (int k = 0; k < 4; k++) {
                cbvh_hit h;
                missed += !cbvh_raycast(fx.file, &ray, traversals[k], &h, NULL);
                missed += !cbvh_occluded(fx.file, &ray, traversals[k], NULL);
                total += 2;
            }
        }
    }
    assert_int_equal(missed, 0);
    assert_true(total > test_least(100000));
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* A mesh whose vertices do not stay in the caches (past CBVH_CACHED_VERTEX_BYTES: vertices_far) takes the
 * walks' early vertex requests and the streams' interleaved walks: the same answers as brute force, on
 * every traversal. */
static void test_far_vertices(void **state)
{
    (void)state;
    /* the binary layout's walks and the scalar kernel's make no early requests: nothing new to see */
    if (test_layout == CBVH_LAYOUT_BINARY || cbvh_walk_kernel() == CBVH_WALK_KERNEL_SCALAR)
        return;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 100000, (float[3]){0.5f, -0.25f, 2.0f}, 3.0f)); /* 600 KB of vertices */
    open_scene(&fx, &s, test_options());
    assert_true(fx.file->vertices_far);
    assert_true(fx.file->info.vertex_count *
                    cbvh_element_size(CBVH_SECTION_VERTICES, fx.file->vertex_encoding) >
                CBVH_CACHED_VERTEX_BYTES);
    check_fixture(&fx, 150, 31);
    /* the streams' way there (interleaved walks): each ray's answer is its single-ray walk's */
    enum { RAYS = 300 };
    cbvh_ray rays[RAYS];
    cbvh_hit hits[RAYS];
    uint8_t occluded[RAYS];
    uint64_t st = 17;
    for (int r = 0; r < RAYS; r++)
        rays[r] = ref_make_ray(&fx, &st, r % REF_RAY_KINDS);
    cbvh_raycast_stream(fx.file, rays, RAYS, hits, NULL);
    cbvh_occluded_stream(fx.file, rays, RAYS, occluded, NULL);
    for (int r = 0; r < RAYS; r++) {
        cbvh_hit h;
        const int hit = cbvh_raycast(fx.file, &rays[r], CBVH_TRAVERSAL_SORTED, &h, NULL);
        assert_int_equal(hits[r].tri, hit ? h.tri : CBVH_NO_HIT);
        if (hit)
            assert_true(hits[r].t == h.t && hits[r].u == h.u && hits[r].v == h.v);
        assert_int_equal(occluded[r], hit);
    }
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* 16-bit boxes are relative to the mesh: far from the origin nothing changes. */
static void test_far_from_origin(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 3000, (float[3]){70000.0f, -70000.0f, 35000.0f}, 10.0f));
    open_scene(&fx, &s, test_options());
    check_fixture(&fx, 2000, 4);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* ------------------------------------------------------------------ */
/* Findings F1 and F2 (notes/findings.md)                              */
/* ------------------------------------------------------------------ */

/* Every traversal, the any-hit query and a one-ray stream agree on ray r. */
static int hit_everywhere(const cbvh_file *f, const cbvh_ray *r, cbvh_hit *out)
{
    cbvh_hit h[4], sh;
    int got[4];
    for (int k = 0; k < 4; k++) {
        got[k] = cbvh_raycast(f, r, traversals[k], &h[k], NULL);
        assert_int_equal(cbvh_occluded(f, r, traversals[k], NULL), got[k]);
    }
    cbvh_raycast_stream(f, r, 1, &sh, NULL);
    for (int k = 1; k < 4; k++) {
        assert_int_equal(got[k], got[0]);
        assert_int_equal(h[k].tri, h[0].tri);
        if (got[0])
            assert_true(h[k].t == h[0].t);
    }
    assert_int_equal(sh.tri, h[0].tri);
    if (got[0])
        assert_true(sh.t == h[0].t);
    *out = h[0];
    return got[0];
}

/* F1: coordinates beyond ~1e12 relative to the origin overflowed the float
 * triangle test (coord^2 edge functions, coord^3 for t) and every ray
 * missed. A tetrahedron of edge s up to CBVH_COORDINATE_MAX (the exact
 * range, cbvh.h): rays through a face from outside, axis-aligned and
 * diagonal, must all hit it at the right t. Past the range (1e15 to 1e36)
 * the cooker refuses it. */
static void test_huge_coordinates(void **state)
{
    (void)state;
    for (int e = 6; e <= 39; e += 3) {
        const float s = e == 39 ? CBVH_COORDINATE_MAX : powf(10.0f, (float)(e <= 12 ? e : e - 3));
        const float p[12] = {0, 0, 0, s, 0, 0, 0, s, 0, 0, 0, s};
        const uint32_t idx[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
        void *buf = NULL;
        cbvh_file *f = NULL;
        if (s > CBVH_COORDINATE_MAX) {
            assert_int_equal(ref_cook_open(p, 4, idx, 4, NULL, &buf, &f), CBVH_ERROR_BAD_MESH);
            continue;
        }
        assert_int_equal(ref_cook_open(p, 4, idx, 4, NULL, &buf, &f), CBVH_OK);
        for (int i = 0; i < 100; i++) {
            const float a = (float)(i % 10 + 0.5) / 20, b = (float)(i / 10 % 10 + 0.5) / 20;
            /* Through the face z = 0 at (a s, b s): t = 1 for both rays. */
            const cbvh_ray rays[2] = {{{a * s, b * s, -s}, 0, {0, 0, s}, INFINITY},
                                      {{a * s - s, b * s - 2 * s, -s}, 0, {s, 2 * s, s}, INFINITY}};
            for (int k = 0; k < 2; k++) {
                cbvh_hit h;
                if (!hit_everywhere(f, &rays[k], &h))
                    fail_msg("s = 1e%d ray %d/%d missed the tetrahedron", e, i, k);
                assert_int_equal(h.tri, 0);
                assert_true(fabs(h.t - 1.0) <= 1e-6);
            }
        }
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
}

/* Rays from outside a unit cube (12 triangles, closed), along an axis (the other components 0 or -0) or
 * diagonal, aimed at points of a face with coordinates 0, 1/2 and 1 (edges and corners: the faces of the
 * cube's bounds, so of the top box every ray from outside is first tested against, raycast.h): each hits at
 * the distance to the face, also with its range ending exactly there, and misses when the range ends
 * short of it or when it passes a hair outside the cube. */
static void test_top_box_grazing_rays(void **state)
{
    (void)state;
    const float p[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
    const uint32_t idx[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                              2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    void *buf = NULL;
    cbvh_file *f = NULL;
    assert_int_equal(ref_cook_open(p, 8, idx, 12, NULL, &buf, &f), CBVH_OK);
    const float at[3] = {0.0f, 0.5f, 1.0f}, zeros[2] = {0.0f, -0.0f};
    long rays = 0;
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++)
            for (int i = 0; i < 9; i++)
                for (int z = 0; z < 4; z++)
                    for (int diagonal = 0; diagonal < 2; diagonal++) {
                        /* the target on face `side` of `axis`; the origin 0.5 outside it (1.5 along a
                         * diagonal) */
                        float target[3], dir[3];
                        target[axis] = (float)side;
                        target[(axis + 1) % 3] = at[i % 3];
                        target[(axis + 2) % 3] = at[i / 3];
                        dir[axis] = side ? -1.0f : 1.0f;
                        dir[(axis + 1) % 3] = diagonal ? (at[i % 3] < 0.75f ? 1.0f : -1.0f) : zeros[z % 2];
                        dir[(axis + 2) % 3] = diagonal ? (at[i / 3] < 0.75f ? 1.0f : -1.0f) : zeros[z / 2];
                        cbvh_ray r = {{0, 0, 0}, 0.0f, {dir[0], dir[1], dir[2]}, INFINITY};
                        for (int a = 0; a < 3; a++)
                            r.org[a] = target[a] - 0.5f * dir[a];
                        cbvh_hit h;
                        if (!hit_everywhere(f, &r, &h))
                            fail_msg("axis %d side %d target %g %g %g dir %g %g %g missed", axis, side,
                                     target[0], target[1], target[2], dir[0], dir[1], dir[2]);
                        assert_true(fabsf(h.t - 0.5f) <= 1e-6f);
                        r.tmax = h.t;
                        assert_int_equal(hit_everywhere(f, &r, &h), 1);
                        r.tmax = nextafterf(0.5f, 0.0f) * 0.999f;
                        assert_int_equal(hit_everywhere(f, &r, &h), 0);
                        /* a hair outside the cube beside the target, along the same direction */
                        r.tmax = INFINITY;
                        const int off = (axis + 1) % 3;
                        if (!diagonal && (at[i % 3] == 0.0f || at[i % 3] == 1.0f)) {
                            r.org[off] = at[i % 3] == 0.0f ? -1e-5f : 1.0f + 1e-5f;
                            assert_int_equal(hit_everywhere(f, &r, &h), 0);
                        }
                        rays++;
                    }
    assert_int_equal(rays, 3 * 2 * 9 * 4 * 2);
    cbvh_close(f);
    cbvh_buffer_free(NULL, buf);
}

/* F8: a triangle spanning the float range, rays from origins just as far
 * on the other side, so vertex - origin differences passed FLT_MAX. An
 * overflowed sheared coordinate made two float edge functions opposite
 * infinities, and a clear hit was rejected as a miss. The cooker now refuses
 * such a triangle (cbvh.h's exact range); the finding's triangle scaled by
 * 2^-88 spans the range instead, and rays from origins anywhere in the float
 * range (most more than 1e38 away) through points well inside it must hit it
 * at the t of the double-precision plane crossing. */
static void test_near_flt_max(void **state)
{
    (void)state;
    const float found[9] = {0x1.fefefep+127f, 0x1.fdfcp-135f,   0, 0x1.0000c2p-99f,
                            0x1.ff1d9ep+127f, 0x1.fefefep+127f, 0, 0x1.000054p-123f,
                            0x1.5988p-136f};
    float pos[9];
    for (int k = 0; k < 9; k++)
        pos[k] = ldexpf(found[k], -88);
    {
        void *refused = NULL;
        cbvh_file *none = NULL;
        assert_int_equal(ref_cook_open(found, 3, (const uint32_t[3]){0, 1, 2}, 1, NULL, &refused, &none),
                         CBVH_ERROR_BAD_MESH);
    }
    const uint32_t idx[3] = {0, 1, 2};
    void *buf = NULL;
    cbvh_file *f = NULL;
    assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_OK);
    uint64_t st = 41;
    int far = 0, clear = 0;
    for (int i = 0; i < 2000; i++) {
        cbvh_ray r = {{0, 0, 0}, 0, {0, 0, 0}, INFINITY};
        double reach;
        {
            /* origins 1e13 to 1e17 or 1e38 to 3.3e38 from the target, log-uniformly: the farther ones aim at
             * a float's precision there, so only the rays whose line crosses the triangle clearly inside
             * (0.05 in barycentrics, and farther from an edge than a millionth of the origin's distance, far
             * above the reference's own rounding) are checked */
            const double wb = 0.1 + 0.4 * scene_rand_unit(&st), wc = 0.1 + 0.4 * scene_rand_unit(&st);
            reach = i % 2 ? 1e13 * pow(1e4, scene_rand_unit(&st)) : 1e38 * pow(3.3, scene_rand_unit(&st));
            for (int a = 0; a < 3; a++) {
                const double target = (1.0 - wb - wc) * pos[a] + wb * pos[3 + a] + wc * pos[6 + a];
                r.org[a] = (float)(target + (2.0 * scene_rand_unit(&st) - 1.0) * reach);
                r.dir[a] = (float)(target - r.org[a]);
            }
        }
        int past = 0;
        for (int v = 0; v < 3; v++)
            for (int a = 0; a < 3; a++)
                past |= fabs((double)pos[3 * v + a] - r.org[a]) > 1e38;
        far += past;
        double pos_d[9], t_cross, u_cross, v_cross, margin;
        for (int k = 0; k < 9; k++)
            pos_d[k] = pos[k];
        if (!ref_ray_triangle(pos_d, &r, &t_cross, &u_cross, &v_cross, &margin) ||
            fmin(fmin(u_cross, v_cross), 1.0 - u_cross - v_cross) < 0.05 || margin < 1e-6 * reach) {
            cbvh_hit ignored; /* not clearly inside: either answer, the same on every path */
            hit_everywhere(f, &r, &ignored);
            continue;
        }
        clear++;
        /* reference: the plane crossing in double */
        double e1[3], e2[3], n[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = (double)pos[3 + a] - pos[a];
            e2[a] = (double)pos[6 + a] - pos[a];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double num = 0, den = 0;
        for (int a = 0; a < 3; a++) {
            num += n[a] * ((double)pos[a] - r.org[a]);
            den += n[a] * r.dir[a];
        }
        const double t_ref = num / den;
        cbvh_hit h;
        if (!hit_everywhere(f, &r, &h))
            fail_msg("ray %d missed; the plane crossing is at t %g", i, t_ref);
        if (!(fabs(h.t - t_ref) <= 1e-5 * t_ref))
            fail_msg("ray %d: t %.9g, reference %.9g", i, h.t, t_ref);
    }
    printf("near FLT_MAX: %d rays checked, %d from more than 1e38 away\n", clear, far);
    /* the cases under test: origins more than 1e38 away (every path agreeing), and rays checked */
    assert_true(far > 500 && clear > 400);
    cbvh_close(f);
    cbvh_buffer_free(NULL, buf);
}

/* F11: a mesh near +-3.4e38 seen from the other side of the float range.
 * With the origin near -+2e38, a near box plane minus the origin is past
 * FLT_MAX and rounded to inf in float, so the slab test put the box at
 * t = inf and missed it, although the ray (its direction as long as that
 * distance) crosses the mesh near t = 2 (fuzz input
 * findings/cook-far-side-box-overflow.bin). The cooker now refuses such a
 * mesh (cbvh.h's exact range): soups of 48 triangles within 2^-88 times
 * [2.3e38, 3.3e38] (up to 1.07e12) on every axis, under random signs,
 * extents 2^-88 times 1e36 to 1e38 (so the origin is sometimes moved next to
 * the mesh, sometimes not), and rays from 1e11 to 3.3e38 away aimed at least 0.1 (barycentric) inside a
 * random triangle: every traversal, the stream and occluded hit, no later
 * than the aimed triangle and no earlier than the double reference's
 * closest crossing. */
static void test_far_side_boxes(void **state)
{
    (void)state;
    enum { TRIS = 48, RAYS = 100 };
    uint64_t st = 11;
    int halved = 0, moved = 0, rays = 0;
    for (int m = 0; m < 24; m++) {
        float pos[9 * TRIS], sign[3];
        uint32_t idx[3 * TRIS];
        const double spread = 1e38 * pow(10.0, -2.0 * scene_rand_unit(&st));
        for (int a = 0; a < 3; a++)
            sign[a] = scene_rand_unit(&st) < 0.5 ? -1.0f : 1.0f;
        for (int k = 0; k < 9 * TRIS; k++) /* the soup at 2^-88 of the finding's scale: in the exact range */
            pos[k] = sign[k % 3] * ldexpf((float)(3.3e38 - spread * scene_rand_unit(&st)), -88);
        for (uint32_t k = 0; k < 3 * TRIS; k++)
            idx[k] = k;
        ref_fixture fx;
        assert_int_equal(ref_fixture_open(&fx, pos, 3 * TRIS, idx, TRIS, test_options()), CBVH_OK);
        for (int i = 0; i < test_reps(RAYS); i++) {
            const uint32_t tri = (uint32_t)(scene_rand_unit(&st) * TRIS) % TRIS;
            const size_t at = fx.index_of_id[tri];
            if (at == (size_t)-1)
                continue; /* dropped as degenerate */
            const double *t9 = fx.tris.v + 9 * at;
            const double wb = 0.1 + 0.35 * scene_rand_unit(&st), wc = 0.1 + 0.35 * scene_rand_unit(&st);
            cbvh_ray r = {{0, 0, 0}, 0, {0, 0, 0}, INFINITY};
            /* half the origins 1e11 to 1e13 away (many left where they are), half 1e13 to 3.3e38 (moved) */
            const double reach = i % 2 ? 1e11 * pow(100.0, scene_rand_unit(&st))
                                       : 1e13 * pow(3.3e38 / 1e13, scene_rand_unit(&st));
            for (int a = 0; a < 3; a++) {
                const double target = (1.0 - wb - wc) * t9[a] + wb * t9[3 + a] + wc * t9[6 + a];
                r.org[a] = -sign[a] * (float)(reach * (0.3 + 0.7 * scene_rand_unit(&st)));
                r.dir[a] = (float)((target - r.org[a]) / 2.0); /* the target at t = 2 */
            }
            double t_aim, u, v, margin;
            if (!ref_ray_triangle(t9, &r, &t_aim, &u, &v, &margin) || fmin(fmin(u, v), 1.0 - u - v) < 0.05 ||
                margin < 1e-6 * reach)
                continue; /* rounding dir moved the aim too close to an edge, or past the reference's
                             precision */
            struct cbvh_ray_ctx ctx;
            assert_true(cbvh_ray_prepare(&ctx, &r, fx.file, NULL));
            halved += ctx.box_halve != 0;
            moved += ctx.t_frame.base != 0.0;
            rays++;
            cbvh_hit unknown; /* an unknown traversal stays a miss, halved or not */
            assert_int_equal(cbvh_raycast(fx.file, &r, (cbvh_traversal)99, &unknown, NULL), 0);
            assert_int_equal(cbvh_occluded(fx.file, &r, (cbvh_traversal)99, NULL), 0);
            ref_ray_hit loose;
            assert_true(ref_ray_closest(&fx.tris, &r, 1e-6 * fx.diag, &loose));
            cbvh_hit h;
            if (!hit_everywhere(fx.file, &r, &h))
                fail_msg("mesh %d ray %d missed; triangle %u is crossed at t %g", m, i, tri, t_aim);
            if (!(h.t <= t_aim * (1 + 1e-5) && h.t >= loose.t * (1 - 1e-5)))
                fail_msg("mesh %d ray %d: t %.9g outside [%.9g, %.9g]", m, i, h.t, loose.t, t_aim);
        }
        ref_fixture_close(&fx);
    }
    printf("far side: %d rays, %d with origins moved, %d with halved box tests\n", rays, moved, halved);
    /* origins moved next to the mesh and not; in the exact range no plane - origin overflows, so no box
     * test runs at half scale */
    assert_true(rays > test_least(300) && moved > test_least(100) && rays - moved > test_least(50));
    assert_int_equal(halved, 0);
}

/* The F8 fix first let a finite float sum overflow skip the sign test:
 * at coordinates near 1e19 the edge functions are near 2e38, and a ray whose
 * edge functions had opposite signs but a sum past FLT_MAX was reported as a
 * hit (fuzz input findings/cook-overflowing-edge-sum-false-hit.bin). The
 * cooker now refuses the input's triangle (cbvh.h's exact range); random
 * triangles up to the range's edge (3.6e10 to 1.08e12) and rays aimed 0.1
 * inside or outside an edge (in barycentrics), against the double-precision
 * plane crossing: hit or miss as aimed. */
static void test_overflowing_edge_sums(void **state)
{
    (void)state;
    uint64_t st = 8;
    int misses = 0;
    for (int m = 0; m < 40; m++) {
        float pos[9] = {-0x1p+63f,       0x1.f803b8p+61f, 0x1.ep+46f,      0x1.ep+62f,     0x1.c0002p+62f,
                        0x1.f803b8p+61f, 0x1.ep+46f,      -0x1.80008p+62f, 0x1.f803b8p+61f};
        const double scale = 3.6e10 * pow(30.0, scene_rand_unit(&st));
        const uint32_t idx[3] = {0, 1, 2};
        void *buf = NULL;
        cbvh_file *f = NULL;
        if (m == 0) {
            assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_ERROR_BAD_MESH);
            continue;
        }
        for (int k = 0; k < 9; k++)
            pos[k] = (float)((2.0 * scene_rand_unit(&st) - 1.0) * scale);
        if (ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f) != CBVH_OK)
            continue; /* a random triangle may be degenerate */
        for (int i = 0; i < 50; i++) {
            cbvh_ray r = {{0x1.b3a124p+62f, 0x1.9e6a3p+60f, -0x1.e5cc04p+62f},
                          0,
                          {-0x1.e48ff8p+60f, 0x1.21a5f2p+62f, 0x1.4ad5f8p+61f},
                          INFINITY};
            int inside = 0;
            {
                /* weights of a, b, c: all >= 0.1 inside; one <= -0.1 outside */
                inside = i % 2;
                double w[3];
                for (int k = 0; k < 3; k++)
                    w[k] = 0.1 + scene_rand_unit(&st);
                if (!inside)
                    w[i % 3] = -0.1 - scene_rand_unit(&st);
                const double sum = w[0] + w[1] + w[2];
                for (int a = 0; a < 3; a++) {
                    const double target = (w[0] * pos[a] + w[1] * pos[3 + a] + w[2] * pos[6 + a]) / sum;
                    r.org[a] = (float)((2.0 * scene_rand_unit(&st) - 1.0) * 2.0 * scale);
                    r.dir[a] = (float)(target - r.org[a]);
                }
            }
            cbvh_hit h;
            const int got = hit_everywhere(f, &r, &h);
            if (got != inside)
                fail_msg("triangle %d ray %d aimed %s the triangle: %s", m, i, inside ? "inside" : "outside",
                         got ? "hit" : "missed");
            misses += !inside;
        }
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
    assert_true(misses > 450);
}

/* F1, far origins: a unit sphere seen from 2^66 (about 7e19) away. In float,
 * coordinates relative to such an origin collapse to one point. The rays
 * pass exactly through the world origin (org = -2^66 dir, dir of small
 * integers, all exact in float), which lies inside the sphere, so they must
 * hit it where the same line cast from near by hits it: on the same
 * triangle up to edge ties, at t = 2^66 + that ray's t (up to float rounding). */
static void test_far_origin_hits(void **state)
{
    (void)state;
    scene sc;
    ref_fixture fx;
    assert_true(scene_sphere(&sc, 2000, (float[3]){0.3f, -0.2f, 0.1f}, 1.0f));
    open_scene(&fx, &sc, test_options());
    uint64_t st = 99;
    int rays = 0;
    while (rays < 500) {
        float dir[3];
        for (int a = 0; a < 3; a++)
            dir[a] = (float)((int)(scene_rand_unit(&st) * 9.0) - 4);
        if (dir[0] == 0 && dir[1] == 0 && dir[2] == 0)
            continue;
        rays++;
        const float far = 0x1p66f;
        const cbvh_ray far_ray = {
            {-far * dir[0], -far * dir[1], -far * dir[2]}, 0, {dir[0], dir[1], dir[2]}, INFINITY};
        const cbvh_ray near_ray = {
            {-8 * dir[0], -8 * dir[1], -8 * dir[2]}, 0, {dir[0], dir[1], dir[2]}, INFINITY};
        cbvh_hit hf, hn;
        assert_true(hit_everywhere(fx.file, &near_ray, &hn));
        if (!hit_everywhere(fx.file, &far_ray, &hf))
            fail_msg("ray %d (dir %g %g %g) from 2^66 missed", rays, dir[0], dir[1], dir[2]);
        const double expect = (double)far - 8.0 + hn.t;
        assert_true(fabs(hf.t - expect) <= 2e-7 * expect);
        /* The far hit's triangle lies on the line, at the near hit's distance. */
        double t, u, v, m;
        const size_t k = fx.index_of_id[hf.tri];
        assert_true(k != (size_t)-1);
        assert_true(ref_ray_triangle(fx.tris.v + 9 * k, &near_ray, &t, &u, &v, &m));
        assert_true(m >= -1e-5);
        assert_true(fabs(t - hn.t) <= 1e-5);
    }
    /* A far ray that stops before the mesh, or points away from it, misses. */
    const cbvh_ray short_ray = {{-0x1p66f, 0, 0}, 0, {1, 0, 0}, 0x1p65f};
    const cbvh_ray away = {{-0x1p66f, 0, 0}, 0, {-1, 0, 0}, INFINITY};
    cbvh_hit h;
    assert_false(hit_everywhere(fx.file, &short_ray, &h));
    assert_false(hit_everywhere(fx.file, &away, &h));
    /* tmin just short of the sphere still sees it; tmin beyond its far side does not */
    const cbvh_ray tmin_ray = {{-0x1p66f, 0, 0}, 0x1p66f - 4, {1, 0, 0}, INFINITY};
    const cbvh_ray past = {{-0x1p66f, 0, 0}, 0x1p66f + 0x1p44f, {1, 0, 0}, INFINITY};
    assert_true(hit_everywhere(fx.file, &tmin_ray, &h));
    assert_true(h.t >= tmin_ray.tmin);
    assert_false(hit_everywhere(fx.file, &past, &h));
    ref_fixture_close(&fx);
    scene_free(&sc);
}

/* F2: t was interpolated as T / det, whose error grows as 1/area: on a
 * sliver of length 1000 and aspect 1e5 hit points were 0.6 off the plane,
 * and some rays well inside missed. Rays aimed at points inside slivers of
 * aspect up to 1e7 (z = 0 plane) get the hit point on the plane within 1e-5
 * of the length, identically on every path, and must hit up to aspect 1e6;
 * at 1e7 the width (1e-4) is within a few float steps of the coordinates
 * relative to the origins (about 100 * 2^-24 each), where the float edge
 * tests may legitimately miss, so only the hits' accuracy is asserted. */
static void test_sliver_t(void **state)
{
    (void)state;
    for (int e = 0; e <= 7; e++) {
        const float w = 1e3f / powf(10.0f, (float)e);
        const float pos[9] = {0, 0, 0, 1e3f, 0, 0, 500, w, 0};
        const uint32_t idx[3] = {0, 1, 2};
        void *buf = NULL;
        cbvh_file *f = NULL;
        assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_OK);
        uint64_t st = 7 + (uint64_t)e;
        double worst = 0.0;
        int hits = 0;
        for (int i = 0; i < test_reps(2000); i++) {
            /* a point well inside: x in [300, 700], y in [0.2, 0.4] w (inside for x in [250, 750]) */
            const double x = 300.0 + 400.0 * scene_rand_unit(&st), y = w * (0.2 + 0.2 * scene_rand_unit(&st));
            const double th = PI * scene_rand_unit(&st), ph = 2.0 * PI * scene_rand_unit(&st);
            const double d[3] = {sin(th) * cos(ph) * 100.0, sin(th) * sin(ph) * 100.0,
                                 cos(th) * 100.0 + (i % 2 ? 1 : -1)};
            const cbvh_ray r = {{(float)(x - d[0]), (float)(y - d[1]), (float)(-d[2])},
                                0,
                                {(float)d[0], (float)d[1], (float)d[2]},
                                INFINITY};
            /* the float ray crosses the plane inside the triangle? (its origin was rounded) */
            const double tz = -(double)r.org[2] / r.dir[2];
            const double px = r.org[0] + tz * r.dir[0], py = r.org[1] + tz * r.dir[1];
            if (!(py > 0.1 * w && py < 0.5 * w && px > 260.0 && px < 740.0))
                continue;
            cbvh_hit h;
            if (!hit_everywhere(f, &r, &h)) {
                if (e <= 6)
                    fail_msg("aspect 1e%d: ray %d inside the sliver missed", e, i);
                continue;
            }
            hits++;
            worst = fmax(worst, fabs((double)r.org[2] + (double)h.t * r.dir[2]));
        }
        if (!(worst <= 1e-5 * 1e3))
            fail_msg("aspect 1e%d: hit point %g off the plane", e, worst);
        assert_true(hits > test_least(500));
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
}

/* The leaf filter's t test (leaf_outside_lanes, in leaves whose box holds the ray's start) only rules out
 * triangles the exact test would reject: on the wide layout, the SIMD leaves (four lanes with SSE2, eight
 * with AVX2) and the scalar ones (which test every triangle exactly) give the same answers bit for bit for
 * rays that start on the surface, as shadow rays and game probes do: at random points of random triangles (a
 * quarter of them within 1e-6 of an edge), in random directions (a third of them grazing the start triangle's
 * plane at 1e-2 to 1e-6), with tmin 0 or a small gap, then with tmin and tmax on the float at, just above and
 * just below the first hit's t. */
static void compare_scalar_leaves(const cbvh_file *f, const cbvh_ray *ray, int *compared)
{
    static const int kernels[3] = {TEST_KERNEL_SCALAR, TEST_KERNEL_SSE2, TEST_KERNEL_AVX2};
    static const char *names[3] = {"scalar", "SSE2", "AVX2"};
    cbvh_hit h[3];
    int hit[3], occ[3];
    for (int k = 0; k < 3; k++) {
        if (!test_set_kernel(kernels[k])) { /* a CPU without AVX2 */
            hit[k] = hit[0];
            h[k] = h[0];
            occ[k] = occ[0];
            continue;
        }
        hit[k] = cbvh_raycast(f, ray, CBVH_TRAVERSAL_SORTED, &h[k], NULL);
        occ[k] = cbvh_occluded(f, ray, CBVH_TRAVERSAL_SORTED, NULL);
    }
    for (int k = 1; k < 3; k++)
        if (hit[0] != hit[k] || occ[0] != occ[k] ||
            (hit[0] && !(h[0].tri == h[k].tri && h[0].t == h[k].t && h[0].u == h[k].u && h[0].v == h[k].v)))
            fail_msg(
                "ray (%a %a %a) + t (%a %a %a), t in [%a, %a]: %s walks hit %d (tri %u t %a) occluded %d, "
                "scalar walks hit %d (tri %u t %a) occluded %d",
                ray->org[0], ray->org[1], ray->org[2], ray->dir[0], ray->dir[1], ray->dir[2], ray->tmin,
                ray->tmax, names[k], hit[k], h[k].tri, h[k].t, occ[k], hit[0], h[0].tri, h[0].t, occ[0]);
    (*compared)++;
}

static void test_leaf_range_filter(void **state)
{
    (void)state;
    const int was = test_kernel_now;
    if (test_layout != CBVH_LAYOUT_WIDE4 || !test_set_kernel(TEST_KERNEL_SCALAR))
        skip(); /* the scalar leaves are the wide layout's, and only a static program reaches the switch */
    int compared = 0;
    for (int which = 0; which < 3; which++) {
        scene sc;
        ref_fixture fx;
        assert_true(which == 0   ? scene_sphere(&sc, 3000, (float[3]){0.5f, -0.25f, 2.0f}, 3.0f)
                    : which == 1 ? scene_terrain(&sc, 3000, 50.0f)
                                 : scene_soup(&sc, 2000, 0.1f, 11));
        open_scene(&fx, &sc, test_options());
        uint64_t st = 99 + (uint64_t)which;
        for (int i = 0; i < test_reps(1500); i++) {
            const double *v = fx.tris.v + 9 * (size_t)(scene_rand_unit(&st) * (double)fx.tris.count);
            double a = scene_rand_unit(&st), b = scene_rand_unit(&st);
            if (a + b > 1.0) {
                a = 1.0 - a;
                b = 1.0 - b;
            }
            if (i % 4 == 0)
                a = 1e-6 * scene_rand_unit(&st); /* next to the edge v0-v2 */
            double n[3], d[3];
            ref_triangle_normal(v, n);
            const double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            const double th = PI * scene_rand_unit(&st), ph = 2.0 * PI * scene_rand_unit(&st);
            d[0] = sin(th) * cos(ph);
            d[1] = sin(th) * sin(ph);
            d[2] = cos(th);
            if (i % 3 == 0 && nl > 0.0) { /* grazing: the in-plane part plus a little of the normal */
                const double dn = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / nl;
                const double lift = pow(10.0, -2.0 - 2.0 * (double)(i % 9 / 3)) * (i % 2 ? 1.0 : -1.0);
                for (int x = 0; x < 3; x++)
                    d[x] += (lift - dn) * n[x] / nl;
            }
            cbvh_ray ray = {{0}, 0.0f, {(float)d[0], (float)d[1], (float)d[2]}, INFINITY};
            for (int x = 0; x < 3; x++)
                ray.org[x] = (float)(v[x] + a * (v[3 + x] - v[x]) + b * (v[6 + x] - v[x]));
            if (!(ray.dir[0] != 0.0f || ray.dir[1] != 0.0f || ray.dir[2] != 0.0f))
                continue;
            compare_scalar_leaves(fx.file, &ray, &compared);
            ray.tmin = (float)(1e-4 * fx.diag);
            compare_scalar_leaves(fx.file, &ray, &compared);
            ray.tmin = 0.0f;
            if (i % 2) {
                /* from off the surface, through the point: the first hit is the only triangle near the
                 * ends of the ranges below, so an occlusion query that accepted a lane without its exact
                 * test would disagree there */
                const double back = 1e-2 * fx.diag * (0.1 + scene_rand_unit(&st));
                for (int x = 0; x < 3; x++)
                    ray.org[x] = (float)((double)ray.org[x] - back * (double)ray.dir[x]);
            }
            cbvh_hit h;
            test_set_kernel(TEST_KERNEL_SCALAR);
            const int hit = cbvh_raycast(fx.file, &ray, CBVH_TRAVERSAL_SORTED, &h, NULL);
            if (!hit)
                continue;
            const float at[3] = {h.t, nextafterf(h.t, INFINITY), nextafterf(h.t, -INFINITY)};
            for (int k = 0; k < 3; k++) {
                if (!(at[k] >= 0.0f))
                    continue;
                ray.tmin = at[k];
                ray.tmax = INFINITY;
                compare_scalar_leaves(fx.file, &ray, &compared);
                ray.tmin = 0.0f;
                ray.tmax = at[k];
                compare_scalar_leaves(fx.file, &ray, &compared);
            }
        }
        ref_fixture_close(&fx);
        scene_free(&sc);
    }
    test_set_kernel(was);
    assert_true(compared > test_least(15000));
}

/* F6: u, v came from the sheared edge functions, which cancel on slivers
 * with large coordinates relative to the origin: on the finding's sliver
 * (aspect 1.8e7, coordinates 2.7e7) the barycentric point lay 2.7e6 from the
 * hit. The finding's ray, then rays at random points of the sliver: the
 * barycentric point must be the hit point (within 1e-6 of the coordinates). */
static void test_sliver_barycentrics(void **state)
{
    (void)state;
    const float pos[9] = {0, 0, 0, 2.75f, -0.56f, 0, -2.67e7f, -2.67e7f, -2.67e7f};
    const uint32_t idx[3] = {0, 1, 2};
    void *buf = NULL;
    cbvh_file *f = NULL;
    assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_OK);
    uint64_t st = 17;
    for (int i = 0; i < 1000; i++) {
        cbvh_ray r = {{-13355977.0f, -13355978.0f, 13355980.0f}, 0, {0, 0, -1}, INFINITY};
        if (i > 0) {
            /* a point of the sliver, a random direction towards it from 1.3e7 away */
            const double f1 = scene_rand_unit(&st), f2 = scene_rand_unit(&st) * (1.0 - f1);
            const double th = PI * scene_rand_unit(&st), ph = 2.0 * PI * scene_rand_unit(&st);
            const double d[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
            for (int a = 0; a < 3; a++) {
                const double p = pos[a] + f1 * (pos[3 + a] - pos[a]) + f2 * (pos[6 + a] - pos[a]);
                r.org[a] = (float)(p - 1.3e7 * d[a]);
                r.dir[a] = (float)d[a];
            }
        }
        cbvh_hit h;
        if (!hit_everywhere(f, &r, &h))
            continue;
        double gap2 = 0.0;
        for (int a = 0; a < 3; a++) {
            const double hit = r.org[a] + (double)h.t * r.dir[a];
            const double bary =
                (1.0 - h.u - h.v) * pos[a] + h.u * (double)pos[3 + a] + h.v * (double)pos[6 + a];
            gap2 += (hit - bary) * (hit - bary);
        }
        if (!(sqrt(gap2) <= 1e-6 * 2.67e7 * 1.8))
            fail_msg("ray %d: the barycentric point (u %g v %g) is %g from the hit point", i, h.u, h.v,
                     sqrt(gap2));
    }
    cbvh_close(f);
    cbvh_buffer_free(NULL, buf);
}

/* F9: on a needle whose two short-edge vertices are closer than the
 * rounding of its long edges (b and c 1e-16 apart, a at distance 3), the
 * normal taken from the long edges pointed anywhere and the barycentric
 * point lay 0.2 from the hit. Rays along -y aimed at the middle of the
 * needle's cross-section at x = -f, for widths from CBVH_COORDINATE_MIN
 * (the narrowest needle the exact range keeps, cbvh.h) to 1e-4: the
 * barycentric point must be the hit point (within 1e-6 of the length) for
 * every traversal. The finding's needle (width 7e-17) is below the range:
 * its short edge is stored as a point and the cooker drops it. */
static void test_needle_barycentrics(void **state)
{
    (void)state;
    static const double widths[4] = {CBVH_COORDINATE_MIN, 1e-12, 1e-8, 1e-4};
    const uint32_t idx[3] = {0, 1, 2};
    uint64_t st = 23;
    for (int wi = 0; wi < 5; wi++) {
        /* wi 4: the finding's triangle and ray, as the fuzzer cooked them */
        const float k = wi < 4 ? (float)widths[wi] : 0x1.494948p-54f;
        const float pos[9] = {-1.0f,
                              2.71875f,
                              wi < 4 ? 0.0f : 0x1.0a0c02p-123f,
                              -k,
                              -k,
                              -k,
                              wi < 4 ? 0.0f : 0x1.040608p-113f,
                              wi < 4 ? 0.0f : 0x1.8383p-132f,
                              wi < 4 ? 0.0f : 0x1.c100cp-131f};
        void *buf = NULL;
        cbvh_file *f = NULL;
        if (wi == 4) {
            assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_ERROR_EMPTY_MESH);
            continue;
        }
        assert_int_equal(ref_cook_open(pos, 3, idx, 1, NULL, &buf, &f), CBVH_OK);
        int hits = 0;
        for (int i = 0; i < 200; i++) {
            cbvh_ray r = {{-0.25f, 0x1.45p+2f, -0x1.494948p-55f}, 0, {0, -1, 0}, INFINITY};
            if (wi < 4 || i > 0) {
                /* edge a-b crosses x = -fx at parameter s, where its z is -s k; edge a-c stays at z = 0 */
                const double fx = 0.05 + 0.9 * scene_rand_unit(&st);
                const double sp = (1.0 - fx) / (1.0 - (double)k);
                r.org[0] = (float)-fx;
                r.org[2] = (float)(-0.5 * sp * k);
            }
            cbvh_hit h;
            if (!hit_everywhere(f, &r, &h))
                continue;
            hits++;
            double gap2 = 0.0;
            for (int a = 0; a < 3; a++) {
                const double hit = r.org[a] + (double)h.t * r.dir[a];
                const double bary =
                    (1.0 - h.u - h.v) * pos[a] + h.u * (double)pos[3 + a] + h.v * (double)pos[6 + a];
                gap2 += (hit - bary) * (hit - bary);
            }
            if (!(sqrt(gap2) <= 3e-6))
                fail_msg("width %g ray %d: the barycentric point (u %g v %g) is %g from the hit point",
                         (double)k, i, h.u, h.v, sqrt(gap2));
        }
        /* rays aimed inside the cross-section hit, whatever the width */
        if (hits < (wi < 4 ? 190 : 1))
            fail_msg("width %g: only %d of the rays aimed at the needle hit it", (double)k, hits);
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
}

static void test_invalid_rays(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 500, (float[3]){0, 0, 0}, 1.0f));
    open_scene(&fx, &s, test_options());
    const cbvh_ray good = {{0, 0, -5}, 0.0f, {0, 0, 1}, INFINITY};
    cbvh_ray bad[12];
    for (int k = 0; k < 12; k++)
        bad[k] = good;
    bad[0].org[0] = NAN;
    bad[1].org[1] = INFINITY;
    bad[2].dir[2] = NAN;
    bad[3].dir[0] = -INFINITY;
    bad[4].dir[2] = 0.0f; /* all zero */
    bad[5].tmin = -1.0f;
    bad[6].tmin = 3.0f;
    bad[6].tmax = 2.0f;
    bad[7].tmax = NAN;
    bad[8].tmin = NAN;
    bad[9].tmin = INFINITY;
    bad[10].tmax = -INFINITY;
    bad[11].dir[2] = -0.0f;
    bad[11].dir[0] = -0.0f;
    for (int b = 0; b < 12; b++) {
        assert_false(ref_ray_valid(&bad[b]));
        for (int k = 0; k < 4; k++) {
            cbvh_hit h = {0, 0, 0, 0};
            assert_int_equal(cbvh_raycast(fx.file, &bad[b], traversals[k], &h, NULL), 0);
            assert_int_equal(h.tri, CBVH_NO_HIT);
            assert_int_equal(cbvh_occluded(fx.file, &bad[b], traversals[k], NULL), 0);
        }
    }
    /* Valid edge cases: infinite tmax, tmin == tmax at the hit, unnormalized tiny direction. */
    cbvh_hit h;
    assert_true(cbvh_raycast(fx.file, &good, CBVH_TRAVERSAL_SORTED, &h, NULL));
    cbvh_ray pinned = good;
    pinned.tmin = pinned.tmax = h.t;
    assert_true(cbvh_raycast(fx.file, &pinned, CBVH_TRAVERSAL_SORTED, &h, NULL));
    cbvh_ray tiny = good;
    tiny.dir[2] = 1e-30f;
    assert_true(cbvh_raycast(fx.file, &tiny, CBVH_TRAVERSAL_STACKLESS, &h, NULL));
    assert_true(fabs(h.t * 1e-30 - 4.0) < 1e-3);
    /* NULL file / ray / hit and an unknown traversal. */
    assert_int_equal(cbvh_raycast(NULL, &good, CBVH_TRAVERSAL_SORTED, &h, NULL), 0);
    assert_int_equal(h.tri, CBVH_NO_HIT);
    assert_int_equal(cbvh_raycast(fx.file, NULL, CBVH_TRAVERSAL_SORTED, &h, NULL), 0);
    assert_int_equal(cbvh_raycast(fx.file, &good, CBVH_TRAVERSAL_SORTED, NULL, NULL), 1);
    assert_int_equal(cbvh_raycast(fx.file, &good, (cbvh_traversal)77, &h, NULL), 0);
    assert_int_equal(cbvh_occluded(fx.file, &good, (cbvh_traversal)77, NULL), 0);
    assert_int_equal(cbvh_occluded(NULL, &good, CBVH_TRAVERSAL_SORTED, NULL), 0);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* Counters: added to, never reset; a hit tests at least one node and triangle;
 * the sort byte saves work on a closed mesh compared with the fixed order. */
static void test_stats(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 20000, (float[3]){0, 0, 0}, 1.0f));
    open_scene(&fx, &s, test_options());
    cbvh_query_stats st[4];
    memset(st, 0, sizeof(st));
    uint64_t rng = 77;
    for (int r = 0; r < 2000; r++) {
        const cbvh_ray ray = ref_make_ray(&fx, &rng, 0);
        for (int k = 0; k < 4; k++) {
            cbvh_hit h;
            const cbvh_query_stats before = st[k];
            const int hit = cbvh_raycast(fx.file, &ray, traversals[k], &h, &st[k]);
            assert_true(st[k].nodes_visited > before.nodes_visited);
            if (hit)
                assert_true(st[k].triangles_tested > before.triangles_tested);
        }
    }
    /* Sorted and distance-ordered walks beat the fixed order of the unsorted and stackless walks. */
    assert_true(st[0].nodes_visited < st[2].nodes_visited);
    assert_true(st[3].triangles_tested < st[1].triangles_tested);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* ------------------------------------------------------------------ */
/* Raycasts with options: culling, filters, all hits, the hit record    */
/* ------------------------------------------------------------------ */

#define MAX_CANDIDATES 512

/* Every candidate a filter saw: ids, records, how many times. */
typedef struct candidates {
    cbvh_hit_record rec[MAX_CANDIDATES];
    int n, overflow;
    cbvh_filter_result answer; /* what the filter returns */
} candidates;

static cbvh_filter_result record_candidate(void *user, const cbvh_hit_record *c)
{
    candidates *all = user;
    if (all->n < MAX_CANDIDATES)
        all->rec[all->n++] = *c;
    else
        all->overflow = 1;
    return all->answer;
}

static cbvh_filter_result reject_odd(void *user, const cbvh_hit_record *c)
{
    (void)user;
    return c->tri & 1u ? CBVH_FILTER_REJECT : CBVH_FILTER_ACCEPT;
}

/* Triangle id's normal from the input arrays (its winding as given), in double. */
static void input_normal(const scene *s, uint32_t id, double n[3])
{
    const float *p0 = s->positions + 3 * (size_t)s->indices[3 * (size_t)id];
    const float *p1 = s->positions + 3 * (size_t)s->indices[3 * (size_t)id + 1];
    const float *p2 = s->positions + 3 * (size_t)s->indices[3 * (size_t)id + 2];
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)p1[a] - p0[a];
        e2[a] = (double)p2[a] - p0[a];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* The cosine between the ray and triangle id's normal; negative: the ray meets the front face. */
static double facing_cosine(const scene *s, uint32_t id, const cbvh_ray *ray)
{
    double n[3], dot = 0.0, nn = 0.0, dd = 0.0;
    input_normal(s, id, n);
    for (int a = 0; a < 3; a++) {
        dot += n[a] * ray->dir[a];
        nn += n[a] * n[a];
        dd += (double)ray->dir[a] * ray->dir[a];
    }
    return dot / sqrt(nn * dd);
}

/* The nearest candidate that `keep` keeps: its index, -1 for none, -2 when a second one is within tol. */
static int nearest_kept(const candidates *all, const scene *s, const cbvh_ray *ray, int keep, double tol)
{
    int best = -1, tie = 0;
    for (int i = 0; i < all->n; i++) {
        const cbvh_hit_record *c = &all->rec[i];
        const int kept = keep == 0 ? facing_cosine(s, c->tri, ray) < 0.0 : (c->tri & 1u) == 0;
        if (!kept)
            continue;
        if (best < 0 || c->t < all->rec[best].t - tol) {
            tie = best >= 0 && c->t > all->rec[best].t - tol;
            best = i;
        } else if (c->t <= all->rec[best].t + tol) {
            tie = 1;
        }
    }
    return tie ? -2 : best;
}

/* One ray of test_query_options: the record against cbvh_raycast and the input mesh, all hits against
 * the brute-force reference, culling and a filter against the all-hits list, STOP and occlusion. */
static void check_options_ray(const ref_fixture *fx, const scene *s, const cbvh_ray *ray, long *culled_checks)
{
    cbvh_query_options o;
    assert_int_equal(cbvh_query_options_init(&o, sizeof o), CBVH_OK);
    cbvh_hit_record rec;
    cbvh_hit plain;
    for (int k = 0; k < 4; k++) {
        o.traversal = traversals[k];
        const int hit = cbvh_raycast(fx->file, ray, traversals[k], &plain, NULL);
        assert_int_equal(cbvh_raycast_with(fx->file, ray, &o, &rec, NULL), CBVH_OK);
        assert_int_equal(rec.tri, plain.tri);
        if (!hit)
            continue;
        assert_true(rec.t == plain.t && rec.u == plain.u && rec.v == plain.v);
        double n[3], len = 0.0, dot = 0.0;
        input_normal(s, rec.tri, n);
        for (int a = 0; a < 3; a++)
            len += n[a] * n[a];
        len = sqrt(len);
        for (int a = 0; a < 3; a++) {
            assert_true(fabs(rec.normal[a] - n[a] / len) < 1e-5);
            dot += (double)rec.normal[a] * ray->dir[a];
        }
        assert_int_equal(rec.front, dot < 0.0);
        assert_int_equal(rec.material, cbvh_file_get_material(fx->file, rec.tri));
    }
    /* All hits: every robust reference hit once, nothing that is not a hit. */
    static candidates all;
    all.n = 0;
    all.overflow = 0;
    all.answer = CBVH_FILTER_REJECT;
    o.traversal = CBVH_TRAVERSAL_SORTED;
    o.filter = record_candidate;
    o.filter_user = &all;
    assert_int_equal(cbvh_raycast_with(fx->file, ray, &o, &rec, NULL), CBVH_OK);
    assert_int_equal(rec.tri, CBVH_NO_HIT);
    assert_false(all.overflow);
    const double tol = t_tolerance(fx, ray, 0.0), slack = 2e-5 * fx->diag;
    for (size_t i = 0; i < fx->tris.count; i++) {
        double t, u, v, m;
        const int crossed = ref_ray_triangle(fx->tris.v + 9 * i, ray, &t, &u, &v, &m);
        int seen = 0;
        for (int j = 0; j < all.n; j++)
            seen += all.rec[j].tri == fx->tris.id[i];
        assert_true(seen <= 1);
        if (crossed && m > slack && t > ray->tmin + tol && t < ray->tmax - tol && !seen)
            fail_msg("all hits: triangle %u crossed at t %g (margin %g) was not reported", fx->tris.id[i], t,
                     m);
        if (seen && !(crossed && m >= -slack))
            fail_msg("all hits: triangle %u reported, but the ray misses it", fx->tris.id[i]);
    }
    /* Culling and a filter: the nearest of the hits they keep (unless two are as near). */
    const int keeps[2] = {0, 1};
    for (int q = 0; q < 2; q++) {
        for (int j = 0; j < all.n; j++)
            if (q == 0 && fabs(facing_cosine(s, all.rec[j].tri, ray)) < 1e-4)
                return; /* grazing: which face the ray meets is not for the test to say */
        const int want =
            nearest_kept(&all, s, ray, keeps[q], 4 * t_tolerance(fx, ray, all.n ? all.rec[0].t : 0.0));
        cbvh_query_options c;
        cbvh_query_options_init(&c, sizeof c);
        if (q == 0)
            c.cull = CBVH_CULL_BACK;
        else
            c.filter = reject_odd;
        int occluded = -1;
        assert_int_equal(cbvh_raycast_with(fx->file, ray, &c, &rec, NULL), CBVH_OK);
        assert_int_equal(cbvh_occluded_with(fx->file, ray, &c, &occluded, NULL), CBVH_OK);
        assert_int_equal(occluded, want != -1);
        if (want >= 0) {
            assert_int_equal(rec.tri, all.rec[want].tri);
            (*culled_checks)++;
        } else if (want == -1) {
            assert_int_equal(rec.tri, CBVH_NO_HIT);
        }
        if (q == 0 && rec.tri != CBVH_NO_HIT)
            assert_int_equal(rec.front, 1);
        /* the front faces culled instead: what is left are the back faces */
        c.cull = q == 0 ? CBVH_CULL_FRONT : CBVH_CULL_NONE;
        assert_int_equal(cbvh_raycast_with(fx->file, ray, &c, &rec, NULL), CBVH_OK);
        if (q == 0 && rec.tri != CBVH_NO_HIT)
            assert_int_equal(rec.front, 0);
    }
    /* STOP ends the query at the first candidate, which is the answer. */
    if (all.n > 0) {
        all.n = 0;
        all.answer = CBVH_FILTER_STOP;
        assert_int_equal(cbvh_raycast_with(fx->file, ray, &o, &rec, NULL), CBVH_OK);
        assert_int_equal(all.n, 1);
        assert_int_equal(rec.tri, all.rec[0].tri);
        assert_true(rec.t == all.rec[0].t);
    }
}

static void test_query_options(void **state)
{
    (void)state;
    scene s, soup;
    ref_fixture fx;
    /* a closed sphere (outward and inward faces) with a soup of random windings inside and around it */
    assert_true(scene_sphere(&s, 2000, (float[3]){0.0f, 0.0f, 0.0f}, 2.0f));
    assert_true(scene_soup(&soup, 1500, 0.4f, 11));
    assert_true(scene_append(&s, &soup, 3));
    scene_free(&soup);
    open_scene(&fx, &s, test_options());
    uint64_t st = 21;
    long culled_checks = 0;
    for (int r = 0; r < test_reps(1500); r++) {
        const cbvh_ray ray = ref_make_ray(&fx, &st, r % REF_RAY_KINDS);
        if (ref_ray_valid(&ray))
            check_options_ray(&fx, &s, &ray, &culled_checks);
    }
    printf("query options: %ld culled or filtered answers checked\n", culled_checks);
    assert_true(culled_checks > test_least(1000));

    /* bad arguments: an error, never a silent miss */
    const cbvh_ray ray = {{0.0f, 0.0f, -10.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
    cbvh_query_options o;
    cbvh_hit_record rec;
    int occluded = 7;
    assert_int_equal(cbvh_query_options_init(NULL, sizeof o), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_query_options_init(&o, 1), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_query_options_init(&o, sizeof o + 8), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_query_options_init(&o, sizeof o), CBVH_OK);
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, &rec, NULL), CBVH_OK);
    assert_true(rec.tri != CBVH_NO_HIT && rec.front == 1);
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, NULL, &rec, NULL), CBVH_OK);
    assert_true(rec.tri != CBVH_NO_HIT);
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, NULL, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_raycast_with(NULL, &ray, &o, &rec, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(rec.tri, CBVH_NO_HIT);
    assert_int_equal(cbvh_occluded_with(fx.file, NULL, &o, &occluded, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(occluded, 0);
    assert_int_equal(cbvh_occluded_with(fx.file, &ray, &o, NULL, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    o.cull = (cbvh_cull)3;
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, &rec, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(rec.tri, CBVH_NO_HIT);
    o.cull = CBVH_CULL_NONE;
    o.traversal = (cbvh_traversal)99;
    assert_int_equal(cbvh_occluded_with(fx.file, &ray, &o, &occluded, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    o.traversal = CBVH_TRAVERSAL_SORTED;
    o.struct_size = 0;
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, &rec, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    o.struct_size = sizeof o + 8;
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, &rec, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    /* a caller compiled when the options ended at traversal: culling and filter take their defaults */
    o.struct_size = offsetof(cbvh_query_options, cull);
    o.cull = (cbvh_cull)3;
    assert_int_equal(cbvh_raycast_with(fx.file, &ray, &o, &rec, NULL), CBVH_OK);
    assert_true(rec.tri != CBVH_NO_HIT);
    o.struct_size = sizeof o;
    o.cull = CBVH_CULL_NONE;
    const cbvh_ray bad[3] = {{{NAN, 0.0f, 0.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY},
                             {{0.0f, 0.0f, -10.0f}, 0.0f, {0.0f, 0.0f, 0.0f}, INFINITY},
                             {{0.0f, 0.0f, -10.0f}, 2.0f, {0.0f, 0.0f, 1.0f}, 1.0f}};
    for (int i = 0; i < 3; i++)
        assert_int_equal(cbvh_raycast_with(fx.file, &bad[i], &o, &rec, NULL), CBVH_ERROR_INVALID_ARGUMENT);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* A placed instance (cbvh_query_options.transform): the mesh rotated, scaled and moved without cooking it
 * again. World rays aimed at the placed mesh answer as the double-precision reference on the placed
 * triangles (check_closest), the normal is the placed triangle's, and any-hit agrees; a caller's struct
 * that ends before the field ignores it; bad transforms are errors. */
static void test_transform(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 3000, (float[3]){1, -2, 3}, 2.0f));
    open_scene(&fx, &s, test_options());
    uint64_t st = 77;
    double *world_v = malloc(sizeof(double) * 9 * fx.tris.count);
    assert_non_null(world_v);
    const float scales[] = {1.0f, 0.25f, 7.5f, 1.0f, 3.0f, 0.5f};
    for (int trial = 0; trial < 6; trial++) {
        cbvh_transform tr;
        double q[4], len = 0.0;
        for (int i = 0; i < 4; i++) {
            q[i] = 2.0 * scene_rand_unit(&st) - 1.0;
            len += q[i] * q[i];
        }
        len = sqrt(len);
        for (int i = 0; i < 4; i++) /* not unit: the library normalizes */
            tr.rotation[i] = trial == 0 ? (i == 3 ? 1.0f : 0.0f) : (float)(3.0 * q[i] / len);
        tr.scale = scales[trial];
        for (int a = 0; a < 3; a++)
            tr.translation[a] =
                trial == 0 ? 0.0f : (float)((2.0 * scene_rand_unit(&st) - 1.0) * 3.0 * fx.diag);
        /* the reference placement, from the quaternion as given, normalized here */
        double qn = 0.0, m[3][3];
        for (int i = 0; i < 4; i++)
            qn += (double)tr.rotation[i] * tr.rotation[i];
        const double x = tr.rotation[0], y = tr.rotation[1], z = tr.rotation[2], w = tr.rotation[3],
                     k = 2.0 / qn;
        const double rows[3][3] = {{1 - k * (y * y + z * z), k * (x * y - z * w), k * (x * z + y * w)},
                                   {k * (x * y + z * w), 1 - k * (x * x + z * z), k * (y * z - x * w)},
                                   {k * (x * z - y * w), k * (y * z + x * w), 1 - k * (x * x + y * y)}};
        memcpy(m, rows, sizeof m);
        ref_fixture world = fx;
        world.tris.v = world_v;
        for (int a = 0; a < 3; a++) {
            world.lo[a] = INFINITY;
            world.hi[a] = -INFINITY;
        }
        for (size_t i = 0; i < 3 * fx.tris.count; i++) {
            const double *p = fx.tris.v + 3 * i;
            for (int a = 0; a < 3; a++) {
                const double c =
                    tr.translation[a] + tr.scale * (m[a][0] * p[0] + m[a][1] * p[1] + m[a][2] * p[2]);
                world_v[3 * i + (size_t)a] = c;
                world.lo[a] = fmin(world.lo[a], c);
                world.hi[a] = fmax(world.hi[a], c);
            }
        }
        world.diag = fx.diag * tr.scale;
        cbvh_query_options opt;
        assert_int_equal(cbvh_query_options_init(&opt, sizeof opt), CBVH_OK);
        opt.transform = &tr;
        int hits = 0;
        for (int r = 0; r < test_reps(400); r++) {
            const cbvh_ray ray = ref_make_ray(&world, &st, r % 3);
            cbvh_hit_record rec;
            assert_int_equal(cbvh_raycast_with(fx.file, &ray, &opt, &rec, NULL), CBVH_OK);
            const cbvh_hit h = {rec.tri, rec.t, rec.u, rec.v};
            check_closest(&world, &ray, rec.tri != CBVH_NO_HIT, &h);
            int occluded = -1;
            assert_int_equal(cbvh_occluded_with(fx.file, &ray, &opt, &occluded, NULL), CBVH_OK);
            assert_int_equal(occluded, rec.tri != CBVH_NO_HIT);
            if (rec.tri == CBVH_NO_HIT)
                continue;
            hits++;
            /* the placed triangle's unit normal, in double */
            const double *v = world_v + 9 * fx.index_of_id[rec.tri];
            const double e1[3] = {v[3] - v[0], v[4] - v[1], v[5] - v[2]},
                         e2[3] = {v[6] - v[0], v[7] - v[1], v[8] - v[2]};
            const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
            const double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            const double dot = (n[0] * rec.normal[0] + n[1] * rec.normal[1] + n[2] * rec.normal[2]) / nl;
            if (!(dot > 0.9999))
                fail_msg("trial %d ray %d: normal (%g %g %g) against the placed triangle's, cosine %g", trial,
                         r, (double)rec.normal[0], (double)rec.normal[1], (double)rec.normal[2], dot);
        }
        assert_true(hits > test_least(100));
    }
    /* A caller whose struct ends before `transform` has none: the mesh's own frame. */
    cbvh_transform far = {{0, 0, 0, 1}, {1000, 0, 0}, 1.0f};
    cbvh_query_options old;
    assert_int_equal(cbvh_query_options_init(&old, offsetof(cbvh_query_options, transform)), CBVH_OK);
    const cbvh_ray at = {{1, -2, 10}, 0.0f, {0, 0, -1}, INFINITY};
    cbvh_hit_record plain, with_old;
    assert_int_equal(cbvh_raycast_with(fx.file, &at, NULL, &plain, NULL), CBVH_OK);
    assert_int_equal(cbvh_raycast_with(fx.file, &at, &old, &with_old, NULL), CBVH_OK);
    assert_true(plain.tri != CBVH_NO_HIT && with_old.tri == plain.tri && with_old.t == plain.t);
    cbvh_query_options opt;
    assert_int_equal(cbvh_query_options_init(&opt, sizeof opt), CBVH_OK);
    opt.transform = &far; /* the mesh moved 1000 along x: the same ray misses */
    assert_int_equal(cbvh_raycast_with(fx.file, &at, &opt, &with_old, NULL), CBVH_OK);
    assert_int_equal(with_old.tri, CBVH_NO_HIT);
    /* bad transforms */
    const cbvh_transform bad[] = {{{0, 0, 0, 0}, {0, 0, 0}, 1.0f},        {{0, 0, 0, 1}, {0, 0, 0}, 0.0f},
                                  {{0, 0, 0, 1}, {0, 0, 0}, -1.0f},       {{0, 0, 0, 1}, {0, 0, 0}, NAN},
                                  {{0, 0, 0, 1}, {INFINITY, 0, 0}, 1.0f}, {{NAN, 0, 0, 1}, {0, 0, 0}, 1.0f},
                                  {{0, 0, 0, 1}, {0, 0, 0}, 1e-45f}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        opt.transform = &bad[i];
        int occluded = -1;
        assert_int_equal(cbvh_raycast_with(fx.file, &at, &opt, &with_old, NULL), CBVH_ERROR_INVALID_ARGUMENT);
        assert_int_equal(with_old.tri, CBVH_NO_HIT);
        assert_int_equal(cbvh_occluded_with(fx.file, &at, &opt, &occluded, NULL),
                         CBVH_ERROR_INVALID_ARGUMENT);
        assert_int_equal(occluded, 0);
    }
    free(world_v);
    ref_fixture_close(&fx);
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_basic),
        cmocka_unit_test(test_watertight_fan),
        cmocka_unit_test(test_slab_edge_cases),
        cmocka_unit_test(test_wide4_visit_table),
        cmocka_unit_test(test_wide4_descent_table),
#ifdef CBVH_HAVE_SIMD
        cmocka_unit_test(test_wide4_refs),
#endif
#ifdef CBVH_HAVE_SIMD
        cmocka_unit_test(test_wide4_affine_box_test),
#endif
        cmocka_unit_test(test_shear_axes_and_slab_select),
        cmocka_unit_test(test_any_hit_order),
        cmocka_unit_test(test_soup),
        cmocka_unit_test(test_sphere_and_terrain),
        cmocka_unit_test(test_cook_variants),
        cmocka_unit_test(test_closed_mesh_no_leaks),
        cmocka_unit_test(test_far_vertices),
        cmocka_unit_test(test_far_from_origin),
        cmocka_unit_test(test_invalid_rays),
        cmocka_unit_test(test_stats),
        cmocka_unit_test(test_huge_coordinates),
        cmocka_unit_test(test_top_box_grazing_rays),
        cmocka_unit_test(test_far_origin_hits),
        cmocka_unit_test(test_sliver_t),
        cmocka_unit_test(test_sliver_barycentrics),
        cmocka_unit_test(test_leaf_range_filter),
        cmocka_unit_test(test_needle_barycentrics),
        cmocka_unit_test(test_near_flt_max),
        cmocka_unit_test(test_far_side_boxes),
        cmocka_unit_test(test_overflowing_edge_sums),
        cmocka_unit_test(test_query_options),
        cmocka_unit_test(test_transform),
    };
    int failed = TEST_RUN_LAYOUTS(tests, 1);
    fprintf(stderr, "test_raycast: %ld reference checks\n", checks_done);
    return failed;
}
