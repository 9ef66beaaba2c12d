/* test_stream.c: ray streams give exactly the single-ray answers, with the scalar and SSE2 node kernels. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

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
#include "query/ray_box.h"
#include "query/stream.h"
#include "query/test_hooks.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

/* The settings each stream check runs with: the node kernel (cbvh_stream_set_kernel: 0 best, 1 scalar, 2
 * SSE2) and the streams' way (cbvh_stream_set_way: 0 by the mesh and the batch, 1 the batch walk, 2 every
 * window interleaved, 3 window by window as a mesh that does not stay in the caches has it, 4 by window with
 * single rays; 2 and 3 batch on the binary layout). The test meshes are small, so their default (the third)
 * is, in the stack's batch, the batch walk for coherent windows and single rays for the others (larger
 * batches of the _scratch forms: the batch walk); the others force the rest: the choice by the rays'
 * coherence (coherent rays in the batch, the others interleaved), on the best kernel and the scalar one,
 * the batch walk, and every window interleaved (the walk the single rays take, so that the counters can be
 * compared too). */
static const struct {
    int kernel, way;
} settings[] = {
    {0, 3}, {1, 3}, {2, 0}, {0, 1}, {0, 2},
};
#define SETTINGS (sizeof settings / sizeof settings[0])

/* Rays of every kind, with invalid ones mixed in every seventh slot. */
static cbvh_ray *make_rays(const ref_fixture *fx, size_t count, uint64_t seed, int coherent)
{
    cbvh_ray *rays = malloc(sizeof(cbvh_ray) * (count ? count : 1));
    assert_non_null(rays);
    uint64_t st = seed;
    for (size_t r = 0; r < count; r++) {
        rays[r] = ref_make_ray(fx, &st, coherent ? 1 : (int)(r % REF_RAY_KINDS));
        if (coherent) { /* one camera position: every ray in the same octant or nearly */
            for (int a = 0; a < 3; a++) {
                const float target = rays[r].org[a] + rays[r].dir[a];
                rays[r].org[a] = (float)(fx->hi[a] + fx->diag);
                rays[r].dir[a] = target - rays[r].org[a];
            }
        }
        if (r % 7 == 3) {
            switch ((r / 7) % 4) {
            case 0:
                rays[r].org[1] = NAN;
                break;
            case 1:
                rays[r].dir[0] = rays[r].dir[1] = rays[r].dir[2] = 0.0f;
                break;
            case 2:
                rays[r].tmin = -1.0f;
                break;
            default:
                rays[r].tmax = rays[r].tmin - 1.0f;
                break;
            }
        }
    }
    return rays;
}

/* The _scratch streams answer as the stack's (hits, occ) whatever their batch: scratch for 1, 33 and 1000
 * rays at an odd address, for more than the largest batch, too small for one ray, and none; nothing is
 * written past the end of the scratch. */
static void check_scratch(const ref_fixture *fx, const cbvh_ray *rays, size_t count, const cbvh_hit *hits,
                          const uint8_t *occ)
{
    const size_t batches[] = {1, 33, 1000, 5000};
    const size_t largest = cbvh_stream_scratch_size(5000);
    uint8_t *mem = malloc(largest + 64);
    cbvh_hit *h = malloc(sizeof(cbvh_hit) * (count + 1));
    uint8_t *o = malloc(count + 1);
    assert_non_null(mem);
    assert_non_null(h);
    assert_non_null(o);
    assert_true(cbvh_stream_scratch_size(0) == cbvh_stream_scratch_size(1));
    assert_true(cbvh_stream_scratch_size(1) < cbvh_stream_scratch_size(33));
    assert_true(cbvh_stream_scratch_size(4096) == largest); /* batches stop at 4096 rays */
    for (size_t k = 0; k < sizeof batches / sizeof batches[0] + 2; k++) {
        const int none = k == sizeof batches / sizeof batches[0] + 1;
        const size_t size = k < sizeof batches / sizeof batches[0] ? cbvh_stream_scratch_size(batches[k])
                            : none                                 ? 0
                                                                   : cbvh_stream_scratch_size(1) - 1;
        uint8_t *scratch = mem + 1; /* any alignment */
        memset(mem, 0x5A, largest + 64);
        memset(h, 0xAB, sizeof(cbvh_hit) * (count + 1));
        memset(o, 0xAB, count + 1);
        cbvh_raycast_stream_scratch(fx->file, rays, count, h, NULL, none ? NULL : scratch, size);
        cbvh_occluded_stream_scratch(fx->file, rays, count, o, NULL, none ? NULL : scratch, size);
        for (size_t r = 0; r < count; r++) {
            assert_int_equal(h[r].tri, hits[r].tri);
            if (h[r].tri != CBVH_NO_HIT)
                assert_true(h[r].t == hits[r].t && h[r].u == hits[r].u && h[r].v == hits[r].v);
            assert_int_equal(o[r], occ[r]);
        }
        assert_int_equal(h[count].tri, 0xABABABABu);
        assert_int_equal(o[count], 0xAB);
        assert_int_equal(mem[0], 0x5A);
        for (size_t b = 1 + size; b < largest + 64; b++)
            assert_int_equal(mem[b], 0x5A);
    }
    free(mem);
    free(h);
    free(o);
}

/* The stream over rays[0, count) equals cbvh_raycast / cbvh_occluded (sorted) ray by ray, bit for bit. */
static void check_stream(const ref_fixture *fx, const cbvh_ray *rays, size_t count)
{
    cbvh_hit *hits = malloc(sizeof(cbvh_hit) * (count + 1));
    uint8_t *occ = malloc(count + 1);
    assert_non_null(hits);
    assert_non_null(occ);
    /* the single-ray answers and counters, once: every setting is compared with them */
    cbvh_hit *single = malloc(sizeof(cbvh_hit) * (count + 1));
    uint8_t *single_occ = malloc(count + 1);
    assert_non_null(single);
    assert_non_null(single_occ);
    cbvh_query_stats single_stats = {0, 0}, single_occ_stats = {0, 0};
    for (size_t r = 0; r < count; r++) {
        cbvh_raycast(fx->file, &rays[r], CBVH_TRAVERSAL_SORTED, &single[r], &single_stats);
        single_occ[r] = (uint8_t)cbvh_occluded(fx->file, &rays[r], CBVH_TRAVERSAL_SORTED, &single_occ_stats);
    }
    for (size_t k = 0; k < SETTINGS; k++) {
        cbvh_stream_set_kernel(settings[k].kernel);
        cbvh_stream_set_way(settings[k].way);
        memset(hits, 0xAB, sizeof(cbvh_hit) * (count + 1));
        memset(occ, 0xAB, count + 1);
        cbvh_query_stats st = {0, 0}, occ_stats = {0, 0};
        cbvh_raycast_stream(fx->file, rays, count, hits, &st);
        cbvh_occluded_stream(fx->file, rays, count, occ, &occ_stats);
        /* Nothing written past the end. */
        assert_int_equal(occ[count], 0xAB);
        assert_int_equal(hits[count].tri, 0xABABABABu);
        for (size_t r = 0; r < count; r++) {
            const cbvh_hit *h = &single[r];
            if (hits[r].tri != h->tri ||
                (h->tri != CBVH_NO_HIT && (hits[r].t != h->t || hits[r].u != h->u || hits[r].v != h->v))) {
                fprintf(stderr, "setting %zu ray %zu: stream tri %u t %.9g, single tri %u t %.9g\n", k, r,
                        hits[r].tri, hits[r].t, h->tri, h->t);
                fail();
            }
            assert_int_equal(occ[r], single_occ[r]);
            /* occluded exactly when there is a closest hit: the occlusion queries' shortcut (a lane the
             * leaf filter accepts without its exact test) against the closest hit's exact tests */
            assert_int_equal(occ[r], hits[r].tri != CBVH_NO_HIT);
        }
        if (count > 0 && ref_ray_valid(&rays[0]))
            assert_true(st.nodes_visited > 0);
        if (settings[k].way == 2 && test_layout == CBVH_LAYOUT_WIDE4) {
            /* the interleaved walks (the wide layout's) are the single-ray walks: the same boxes and
             * triangles, ray by ray */
            assert_true(st.nodes_visited == single_stats.nodes_visited);
            assert_true(st.triangles_tested == single_stats.triangles_tested);
            assert_true(occ_stats.nodes_visited == single_occ_stats.nodes_visited);
            assert_true(occ_stats.triangles_tested == single_occ_stats.triangles_tested);
        }
        /* the scratch sizes (eight interleaved walks there, four on the stack) with the default (whose way
         * depends on the batch's size), the choice by window (batches and interleaved windows) and every
         * window interleaved: the other settings change the walks, not how the scratch is cut */
        if (settings[k].way != 1 && settings[k].kernel != 1)
            check_scratch(fx, rays, count, hits, occ);
    }
    cbvh_stream_set_kernel(0);
    cbvh_stream_set_way(0);
    free(single);
    free(single_occ);
    free(hits);
    free(occ);
}

static void open_scene(ref_fixture *fx, scene *s)
{
    assert_int_equal(
        ref_fixture_open(fx, s->positions, s->vertex_count, s->indices, s->triangle_count, test_options()),
        CBVH_OK);
}

/* Counts around the SIMD widths, the stack batch (32) and its octant window (256), the batch sizes of the
 * scratch checks and their windows. */
static void test_counts(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_soup(&s, 2000, 0.1f, 3));
    open_scene(&fx, &s);
    const size_t counts[] = {0, 1, 3, 4, 5, 7, 8, 9, 31, 32, 33, 255, 256, 257, 2047, 2048, 2049, 5000, 8001};
    for (size_t c = 0; c < sizeof(counts) / sizeof(counts[0]); c++) {
        cbvh_ray *rays = make_rays(&fx, counts[c], 100 + c, 0);
        check_stream(&fx, rays, counts[c]);
        free(rays);
    }
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* Closed and open meshes, incoherent and coherent (single-octant) streams. */
static void test_meshes(void **state)
{
    (void)state;
    for (int m = 0; m < 3; m++) {
        scene s;
        ref_fixture fx;
        if (m == 0)
            assert_true(scene_sphere(&s, 20000, (float[3]){1, 2, 3}, 2.0f));
        else if (m == 1)
            assert_true(scene_terrain(&s, 8000, 100.0f));
        else
            assert_true(scene_sphere(&s, 3000, (float[3]){-70000.0f, 70000.0f, 1000.0f}, 5.0f));
        open_scene(&fx, &s);
        for (int coherent = 0; coherent < 2; coherent++) {
            const size_t count = (size_t)test_reps(6000);
            cbvh_ray *rays = make_rays(&fx, count, 7 + (uint64_t)m, coherent);
            check_stream(&fx, rays, count);
            free(rays);
        }
        ref_fixture_close(&fx);
        scene_free(&s);
    }
}

/* Rays from off the surface through points of random triangles, with their range ending just before, at
 * and just after their first hit (the only triangle near those ends): the streams and single rays must
 * still agree, and occlude exactly when they hit (check_stream). */
static void test_range_ends(void **state)
{
    (void)state;
    scene s;
    ref_fixture fx;
    assert_true(scene_sphere(&s, 3000, (float[3]){0.5f, -0.25f, 2.0f}, 3.0f));
    open_scene(&fx, &s);
    enum { POINTS = 600, PER_POINT = 5 };
    cbvh_ray *rays = malloc(sizeof(cbvh_ray) * POINTS * PER_POINT);
    assert_non_null(rays);
    uint64_t st = 77;
    size_t n = 0;
    for (int i = 0; i < POINTS; i++) {
        const double *v = fx.tris.v + 9 * (size_t)(scene_rand_unit(&st) * (double)fx.tris.count);
        double a = scene_rand_unit(&st), b = scene_rand_unit(&st);
        if (a + b > 1.0) {
            a = 1.0 - a;
            b = 1.0 - b;
        }
        cbvh_ray ray = {{0}, 0.0f, {0}, INFINITY};
        const double z = 2.0 * scene_rand_unit(&st) - 1.0, ph = 6.283185307179586 * scene_rand_unit(&st);
        ray.dir[0] = (float)(sqrt(1.0 - z * z) * cos(ph));
        ray.dir[1] = (float)(sqrt(1.0 - z * z) * sin(ph));
        ray.dir[2] = (float)z;
        const double back = 1e-2 * fx.diag * (0.1 + scene_rand_unit(&st));
        for (int x = 0; x < 3; x++)
            ray.org[x] =
                (float)(v[x] + a * (v[3 + x] - v[x]) + b * (v[6 + x] - v[x]) - back * (double)ray.dir[x]);
        cbvh_hit h;
        if (!cbvh_raycast(fx.file, &ray, CBVH_TRAVERSAL_SORTED, &h, NULL) || !(h.t > 0.0f))
            continue;
        const float before = nextafterf(h.t, 0.0f), after = nextafterf(h.t, INFINITY);
        const float ranges[PER_POINT][2] = {
            {0.0f, before}, {0.0f, h.t}, {h.t, INFINITY}, {after, INFINITY}, {before, h.t}};
        for (int k = 0; k < PER_POINT; k++) {
            rays[n] = ray;
            rays[n].tmin = ranges[k][0];
            rays[n].tmax = ranges[k][1];
            n++;
        }
    }
    assert_true(n > 1000);
    check_stream(&fx, rays, n);
    free(rays);
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* The batch node kernels agree box by box on awkward rays: 0, -0 and
 * denormal directions, origins on the box planes, dead rays (tmax < 0): the
 * same rays on each box's list, in the tested order, with the same entry
 * distances, as the scalar kernel, whose lists are the slab test's (ray_box.h). */
static void test_node_kernels_agree(void **state)
{
    (void)state;
    enum { BATCH = 256, LANES = CBVH_STREAM_LANES };
    static _Alignas(32) float box_ray[BATCH][8]; /* the kernels' aligned loads */
    struct cbvh_stream_batch batch;
    memset(&batch, 0, sizeof batch);
    batch.box_ray = box_ray;
    batch.capacity = BATCH;
    const float dirs[] = {0.0f, -0.0f, 1e-40f, -1e-40f, 1e30f, -1e30f, 1.0f, -1.0f, 0.37f};
    const float coords[] = {-2.0f, -1.0f, 0.0f, 0.5f, 1.0f, 3.0f};
    const cbvh_stream_node_fn fns[] = {cbvh_stream_node_scalar,
#ifdef CBVH_HAVE_SIMD
                                       cbvh_stream_node_sse2
#endif
    };
    const int nfns = (int)(sizeof(fns) / sizeof(fns[0]));
    uint64_t st = 9;
    for (int round = 0; round < 200; round++) {
        const uint32_t octant = (uint32_t)(scene_rand_next(&st) % 8);
        const uint32_t n = (uint32_t)(scene_rand_next(&st) % (BATCH + 1));
        for (uint32_t r = 0; r < BATCH; r++) {
            float *b = batch.box_ray[r];
            for (int a = 0; a < 3; a++) {
                b[CBVH_LANE_OX + a] = coords[scene_rand_next(&st) % 6];
                float d = dirs[scene_rand_next(&st) % 9];
                d = (octant >> a & 1u) ? -fabsf(d) : fabsf(d); /* the batch's octant */
                b[CBVH_LANE_RX + a] = 1.0f / d;
            }
            b[CBVH_LANE_TMIN] = scene_rand_next(&st) % 2 ? 0.0f : 0.5f;
            b[CBVH_LANE_TMAX] = scene_rand_next(&st) % 5 == 0 ? -1.0f : 2.0f;
        }
        /* 1 to 4 boxes, each a few grid cells of [-1, 1]^3 or the whole cube */
        struct cbvh_stream_boxes boxes;
        memset(&boxes, 0, sizeof boxes);
        boxes.count = 1 + (uint32_t)(scene_rand_next(&st) % LANES);
        for (uint32_t k = 0; k < boxes.count; k++) {
            for (int a = 0; a < 3; a++) {
                const float lo = k == 0 ? -1.0f : coords[scene_rand_next(&st) % 4];
                const float hi = k == 0 ? 1.0f : lo + 1.0f;
                boxes.plane[a][k] = (octant >> a & 1u) ? hi : lo;
                boxes.plane[3 + a][k] = (octant >> a & 1u) ? lo : hi;
            }
        }
        uint16_t rays[BATCH];
        for (uint32_t j = 0; j < n; j++)
            rays[j] = (uint16_t)(n - 1 - j); /* any order */
        static uint16_t list_ray[2][LANES][BATCH];
        static float list_entry[2][LANES][BATCH];
        uint32_t count[2][LANES];
        for (int f = 0; f < nfns; f++) {
            uint16_t sink_ray;
            float sink_entry;
            struct cbvh_stream_lists lists;
            for (uint32_t k = 0; k < LANES; k++) {
                lists.ray[k] = k < boxes.count ? list_ray[f][k] : &sink_ray;
                lists.entry[k] = k < boxes.count ? list_entry[f][k] : &sink_entry;
            }
            fns[f](&batch, rays, n, &boxes, &lists, count[f]);
            for (uint32_t k = 0; k < boxes.count; k++) {
                if (f == 0) {
                    /* the scalar lists are the slab test's */
                    uint32_t m = 0;
                    for (uint32_t j = 0; j < n; j++) {
                        const float *b = batch.box_ray[rays[j]];
                        const float org[3] = {b[CBVH_LANE_OX], b[CBVH_LANE_OY], b[CBVH_LANE_OZ]};
                        const float rcp[3] = {b[CBVH_LANE_RX], b[CBVH_LANE_RY], b[CBVH_LANE_RZ]};
                        float e;
                        if (cbvh_slab_test(boxes.plane[0][k], boxes.plane[1][k], boxes.plane[2][k],
                                           boxes.plane[3][k], boxes.plane[4][k], boxes.plane[5][k], org, rcp,
                                           b[CBVH_LANE_TMIN], b[CBVH_LANE_TMAX], &e)) {
                            assert_true(m < count[0][k]);
                            assert_int_equal(list_ray[0][k][m], rays[j]);
                            assert_memory_equal(&list_entry[0][k][m], &e, sizeof e);
                            m++;
                        }
                    }
                    assert_int_equal(m, count[0][k]);
                    continue;
                }
                assert_int_equal(count[f][k], count[0][k]);
                assert_memory_equal(list_ray[f][k], list_ray[0][k], count[0][k] * sizeof(uint16_t));
                assert_memory_equal(list_entry[f][k], list_entry[0][k], count[0][k] * sizeof(float));
            }
        }
    }
}

static void test_null_arguments(void **state)
{
    (void)state;
    cbvh_hit h[2] = {{0, 0, 0, 0}, {0, 0, 0, 0}};
    uint8_t occ[2] = {1, 1};
    const cbvh_ray rays[2] = {{{0, 0, 0}, 0, {1, 0, 0}, 1}, {{0, 0, 0}, 0, {1, 0, 0}, 1}};
    cbvh_raycast_stream(NULL, rays, 2, h, NULL);
    assert_int_equal(h[0].tri, CBVH_NO_HIT);
    assert_int_equal(h[1].tri, CBVH_NO_HIT);
    cbvh_occluded_stream(NULL, rays, 2, occ, NULL);
    assert_int_equal(occ[0], 0);
    assert_int_equal(occ[1], 0);
    cbvh_raycast_stream(NULL, rays, 2, NULL, NULL); /* nowhere to write: nothing happens */
    cbvh_occluded_stream(NULL, rays, 2, NULL, NULL);
    uint8_t scratch[4096];
    h[0].tri = h[1].tri = 0;
    occ[0] = occ[1] = 1;
    cbvh_raycast_stream_scratch(NULL, rays, 2, h, NULL, scratch, sizeof scratch);
    assert_int_equal(h[0].tri, CBVH_NO_HIT);
    assert_int_equal(h[1].tri, CBVH_NO_HIT);
    cbvh_occluded_stream_scratch(NULL, rays, 2, occ, NULL, scratch, sizeof scratch);
    assert_int_equal(occ[0], 0);
    assert_int_equal(occ[1], 0);
    cbvh_raycast_stream_scratch(NULL, rays, 2, NULL, NULL, scratch, sizeof scratch);
    cbvh_occluded_stream_scratch(NULL, rays, 2, NULL, NULL, NULL, 0);
}

/* The occlusion streams' choice of way (stream.c): a window is coherent when at least half of its sampled
 * pairs of consecutive rays point within about 8 degrees of each other, the same way round. */
static void test_window_coherence(void **state)
{
    (void)state;
    enum { N = 1000 };
    cbvh_ray *rays = calloc(N, sizeof *rays);
    assert_non_null(rays);
    uint64_t st = 5;
    /* a camera's rays in scanline order: coherent; rays in all directions: not */
    for (int j = 0; j < N; j++) {
        const float x = (float)(j % 40) / 40.0f - 0.5f, y = (float)(j / 40) / 25.0f - 0.5f;
        rays[j].dir[0] = x;
        rays[j].dir[1] = y;
        rays[j].dir[2] = -1.0f;
    }
    assert_true(cbvh_stream_window_coherent(rays, N));
    for (int j = 0; j < N; j++)
        for (int a = 0; a < 3; a++)
            rays[j].dir[a] = (float)(2.0 * scene_rand_unit(&st) - 1.0);
    assert_false(cbvh_stream_window_coherent(rays, N));
    /* parallel rays, whatever their length: coherent; every other one turned round: not */
    for (int j = 0; j < N; j++) {
        const float len = 1.0f + (float)(j % 7);
        rays[j].dir[0] = 0.0f * len;
        rays[j].dir[1] = -0.6f * len;
        rays[j].dir[2] = 0.8f * len;
    }
    assert_true(cbvh_stream_window_coherent(rays, N));
    for (int j = 1; j < N; j += 2)
        for (int a = 0; a < 3; a++)
            rays[j].dir[a] = -rays[j].dir[a];
    assert_false(cbvh_stream_window_coherent(rays, N));
    /* about 5 degrees apart: coherent; about 12: not */
    const double steps[2] = {5.0, 12.0};
    for (int k = 0; k < 2; k++) {
        for (int j = 0; j < N; j++) {
            const double a = (double)j * steps[k] * 3.141592653589793 / 180.0;
            rays[j].dir[0] = (float)cos(a);
            rays[j].dir[1] = (float)sin(a);
            rays[j].dir[2] = 0.0f;
        }
        assert_int_equal(cbvh_stream_window_coherent(rays, N), k == 0);
    }
    /* zero and NaN directions count as apart; one ray has no pair: batched */
    memset(rays, 0, sizeof *rays * N);
    assert_false(cbvh_stream_window_coherent(rays, N));
    for (int j = 0; j < N; j++)
        rays[j].dir[0] = NAN;
    assert_false(cbvh_stream_window_coherent(rays, N));
    assert_true(cbvh_stream_window_coherent(rays, 1));
    free(rays);
}

/* The streams' way (kernel_choice.c's cbvh_stream_way_for) for each kind of mesh and batch, and under each
 * setting of the test hook. */
static void test_stream_way(void **state)
{
    (void)state;
    struct cbvh_file f;
    memset(&f, 0, sizeof f);
    for (uint32_t layout = 0; layout < 2; layout++) {
        const int wide = layout == CBVH_LAYOUT_WIDE4;
        f.layout = wide ? CBVH_LAYOUT_WIDE4 : CBVH_LAYOUT_BINARY;
        /* vertices that do not stay in the caches: incoherent windows interleaved (wide), else the batch */
        f.vertices_far = 1;
        f.info.triangle_count = 1000000;
        for (uint32_t capacity = 1; capacity <= CBVH_STREAM_MAX_BATCH; capacity *= 4)
            assert_int_equal(cbvh_stream_way_for(&f, capacity),
                             wide ? CBVH_STREAM_BY_WINDOW : CBVH_STREAM_BATCHED);
        /* in the caches: the stack's batch walks incoherent windows one ray at a time */
        f.vertices_far = 0;
        f.info.triangle_count = 100;
        assert_int_equal(cbvh_stream_way_for(&f, CBVH_STREAM_STACK_BATCH), CBVH_STREAM_BY_WINDOW_SINGLE);
        assert_int_equal(cbvh_stream_way_for(&f, CBVH_STREAM_STACK_BATCH + 1), CBVH_STREAM_BATCHED);
        /* a larger batch batches them up to CBVH_STREAM_SHARED_TRIANGLES_PER_RAY triangles a ray of the batch
         * (wide; binary: any mesh) */
        const uint32_t per_ray = CBVH_STREAM_SHARED_TRIANGLES_PER_RAY;
        f.info.triangle_count = per_ray * 1024u;
        assert_int_equal(cbvh_stream_way_for(&f, 1024), CBVH_STREAM_BATCHED);
        f.info.triangle_count = per_ray * 1024u + per_ray;
        assert_int_equal(cbvh_stream_way_for(&f, 1024),
                         wide ? CBVH_STREAM_BY_WINDOW_SINGLE : CBVH_STREAM_BATCHED);
        assert_int_equal(cbvh_stream_way_for(&f, 1025), CBVH_STREAM_BATCHED);
        /* the hook's settings override the mesh's way; the binary layout has no interleaved walks */
        const enum cbvh_stream_way forced[4] = {
            CBVH_STREAM_BATCHED, wide ? CBVH_STREAM_INTERLEAVED : CBVH_STREAM_BATCHED,
            wide ? CBVH_STREAM_BY_WINDOW : CBVH_STREAM_BATCHED, CBVH_STREAM_BY_WINDOW_SINGLE};
        for (int setting = 1; setting <= 4; setting++) {
            cbvh_stream_set_way(setting);
            assert_int_equal(cbvh_stream_way_for(&f, 1024), forced[setting - 1]);
            assert_int_equal(cbvh_stream_way_for(&f, CBVH_STREAM_STACK_BATCH), forced[setting - 1]);
        }
        cbvh_stream_set_way(0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counts),         cmocka_unit_test(test_meshes),
        cmocka_unit_test(test_range_ends),     cmocka_unit_test(test_node_kernels_agree),
        cmocka_unit_test(test_null_arguments), cmocka_unit_test(test_window_coherence),
        cmocka_unit_test(test_stream_way),
    };
    return TEST_RUN_LAYOUTS(tests, 1);
}
