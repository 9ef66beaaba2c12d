/* test_threads.c: several threads query one opened file with every query kind at once and must get exactly
 * the single-threaded answers. */
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>

#include "cbvh.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

enum { QUERY_COUNT = 2048, STREAM_SIZE = 16, KINDS = 11, MAX_THREADS = 16 };

/* One query's answer, compared bytewise between threads. */
typedef struct answer {
    uint64_t hash;
    uint32_t tri, count;
    float t, u, v;
    float point[3], normal[3];
} answer;

static cbvh_file *file;
static cbvh_ray rays[QUERY_COUNT + STREAM_SIZE];
static float radii[QUERY_COUNT];
static answer expected[QUERY_COUNT];

typedef struct fnv {
    uint64_t h;
    uint32_t count;
} fnv;
static int hash_id(void *user, uint32_t tri)
{
    fnv *f = user;
    f->h = (f->h ^ tri) * 0x100000001B3ull;
    f->count++;
    return 0;
}

/* A hit filter that folds every candidate into a hash (independent of their order) and rejects it. */
static cbvh_filter_result hash_candidate(void *user, const cbvh_hit_record *hit)
{
    fnv *f = user;
    uint32_t bits;
    memcpy(&bits, &hit->t, 4);
    f->h += ((uint64_t)hit->tri << 32 | bits) * 0x9E3779B97F4A7C15ull;
    f->count++;
    return CBVH_FILTER_REJECT;
}

/* Query i: its kind is i % KINDS; every thread computes it the same way. */
static void run_query(size_t i, answer *a)
{
    memset(a, 0, sizeof *a);
    const cbvh_ray *r = &rays[i];
    cbvh_hit h;
    cbvh_sweep_hit s;
    float delta[3] = {r->dir[0], r->dir[1], r->dir[2]}, p1[3] = {r->org[0] + radii[i], r->org[1], r->org[2]};
    float half[3] = {radii[i], 0.5f * radii[i], 2.0f * radii[i]};
    switch (i % KINDS) {
    case 0:
    case 1:
    case 2:
    case 3:
        /* only tri is defined on a miss */
        if (cbvh_raycast(file, r, (cbvh_traversal)(i % KINDS), &h, NULL)) {
            a->tri = h.tri;
            a->t = h.t;
            a->u = h.u;
            a->v = h.v;
        } else {
            a->tri = h.tri;
        }
        break;
    case 4:
        a->count = (uint32_t)cbvh_occluded(file, r, (cbvh_traversal)(i / KINDS % 4), NULL);
        break;
    case 5: { /* a batch of STREAM_SIZE rays starting at i: all answers folded into the hash */
        cbvh_hit hits[STREAM_SIZE];
        uint8_t occ[STREAM_SIZE];
        cbvh_raycast_stream(file, r, STREAM_SIZE, hits, NULL);
        cbvh_occluded_stream(file, r, STREAM_SIZE, occ, NULL);
        uint64_t hash = 1469598103934665603ull;
        for (int k = 0; k < STREAM_SIZE; k++) {
            uint32_t bits = 0;
            if (hits[k].tri != CBVH_NO_HIT)
                memcpy(&bits, &hits[k].t, 4);
            hash = (hash ^ hits[k].tri ^ ((uint64_t)bits << 32) ^ occ[k]) * 0x100000001B3ull;
        }
        a->hash = hash;
        break;
    }
    case 6:
        memset(&s, 0, sizeof s);
        a->count = (uint32_t)cbvh_sweep_sphere(file, r->org, radii[i], delta, &s);
        goto sweep;
    case 7:
        memset(&s, 0, sizeof s);
        a->count = (uint32_t)cbvh_sweep_capsule(file, r->org, p1, radii[i], delta, &s);
        goto sweep;
    case 8:
        memset(&s, 0, sizeof s);
        a->count = (uint32_t)cbvh_sweep_box(file, r->org, half, delta, &s);
    sweep:
        if (a->count) {
            a->tri = s.tri;
            a->t = s.t;
            memcpy(a->point, s.point, sizeof a->point);
            memcpy(a->normal, s.normal, sizeof a->normal);
        }
        break;
    case 9: { /* with options: back faces culled, or every hit through a filter */
        cbvh_query_options q;
        cbvh_hit_record rec;
        fnv f = {0, 0};
        cbvh_query_options_init(&q, sizeof q);
        if ((i / KINDS) % 2) {
            q.filter = hash_candidate;
            q.filter_user = &f;
        } else {
            q.cull = CBVH_CULL_BACK;
        }
        cbvh_raycast_with(file, r, &q, &rec, NULL);
        a->tri = rec.tri;
        if (rec.tri != CBVH_NO_HIT) {
            a->t = rec.t;
            a->u = rec.u;
            a->v = rec.v;
            memcpy(a->normal, rec.normal, sizeof a->normal);
        }
        a->hash = f.h;
        a->count = f.count;
        break;
    }
    default: {
        fnv f = {1469598103934665603ull, 0};
        float lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = r->org[k] + 0.5f * r->dir[k] - radii[i];
            hi[k] = lo[k] + 2.0f * radii[i];
        }
        size_t n = (i / KINDS) % 2 ? cbvh_overlap_box(file, lo, hi, hash_id, &f, NULL, 0)
                                   : cbvh_overlap_sphere(file, lo, radii[i], hash_id, &f, NULL, 0);
        a->count = (uint32_t)n;
        a->hash = f.h ^ f.count;
        break;
    }
    }
}

typedef struct worker {
    pthread_t thread;
    size_t start;
    double seconds;
    uint64_t queries, mismatches, by_kind[KINDS];
} worker;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void *work(void *arg)
{
    worker *w = arg;
    double end = now() + w->seconds;
    size_t i = w->start;
    do {
        for (int k = 0; k < 64; k++) {
            answer a;
            run_query(i, &a);
            if (memcmp(&a, &expected[i], sizeof a) != 0) {
                w->mismatches++;
                w->by_kind[i % KINDS]++;
            }
            w->queries++;
            i = (i + 1) % QUERY_COUNT;
        }
    } while (now() < end);
    return NULL;
}

static void test_threads_agree(void **state)
{
    (void)state;
    scene sc;
    assert_true(scene_demo(&sc));
    cbvh_mesh m = {sc.positions, sc.vertex_count, 0, sc.indices, sc.triangle_count, sc.material_ids};
    void *buf = NULL;
    size_t size = 0;
    cbvh_cook_options o;
    test_options_init(&o);
    o.compress_level = 1;
    assert_int_equal(cbvh_cook(&m, &o, NULL, &buf, &size, NULL, NULL), CBVH_OK);
    assert_int_equal(cbvh_open_memory(buf, size, NULL, &file, NULL), CBVH_OK);
    if (ref_expand_triangles) /* the layouts' last run: the threads share an expanded file */
        assert_int_equal(cbvh_file_expand_triangles(file, NULL), CBVH_OK);
    cbvh_file_info info;
    cbvh_file_get_info(file, &info, sizeof info);
    uint64_t rng = 7;
    double ext = 0;
    for (int k = 0; k < 3; k++)
        ext = fmax(ext, (double)info.bounds_max[k] - info.bounds_min[k]);
    for (size_t i = 0; i < QUERY_COUNT + STREAM_SIZE; i++) {
        for (int k = 0; k < 3; k++) {
            double lo = info.bounds_min[k], hi = info.bounds_max[k];
            rays[i].org[k] = (float)(lo + (hi - lo) * (1.4 * scene_rand_unit(&rng) - 0.2));
            rays[i].dir[k] = (float)(lo + (hi - lo) * scene_rand_unit(&rng) - rays[i].org[k]);
        }
        rays[i].tmin = 0;
        rays[i].tmax = (i % 3) ? INFINITY : 0.7f;
        if (i < QUERY_COUNT)
            radii[i] = (float)(0.02 * ext * scene_rand_unit(&rng));
    }
    size_t hits = 0;
    for (size_t i = 0; i < QUERY_COUNT; i++) {
        run_query(i, &expected[i]);
        hits += i % KINDS < 4 ? expected[i].tri != CBVH_NO_HIT : expected[i].count != 0;
    }
    assert_true(hits > QUERY_COUNT / 10); /* the queries do touch the mesh */

    const char *env_s = getenv("CBVH_THREAD_SECONDS"), *env_n = getenv("CBVH_THREADS");
    double seconds = env_s ? atof(env_s) : 3.0;
    int threads = env_n ? atoi(env_n) : 4;
    if (threads < 2)
        threads = 2;
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    worker w[MAX_THREADS];
    for (int t = 0; t < threads; t++) {
        memset(&w[t], 0, sizeof w[t]);
        w[t].start = (size_t)t * QUERY_COUNT / (size_t)threads;
        w[t].seconds = seconds;
        assert_int_equal(pthread_create(&w[t].thread, NULL, work, &w[t]), 0);
    }
    uint64_t total = 0, bad = 0, by_kind[KINDS] = {0};
    for (int t = 0; t < threads; t++) {
        pthread_join(w[t].thread, NULL);
        total += w[t].queries;
        bad += w[t].mismatches;
        for (int k = 0; k < KINDS; k++)
            by_kind[k] += w[t].by_kind[k];
    }
    for (int k = 0; k < KINDS; k++)
        if (by_kind[k])
            printf("query kind %d: %llu answers differ\n", k, (unsigned long long)by_kind[k]);
    printf("threads: %d threads x %.1f s on one file (%u triangles): %llu queries of %d kinds, %llu differ "
           "from single-threaded\n",
           threads, seconds, info.triangle_count, (unsigned long long)total, KINDS, (unsigned long long)bad);
    assert_int_equal(bad, 0);
    assert_true(total >= (uint64_t)threads * 64);
    cbvh_close(file);
    cbvh_buffer_free(NULL, buf);
    scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_threads_agree)};
    return TEST_RUN_LAYOUTS(tests, 0);
}
