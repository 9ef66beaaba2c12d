/* test_oom.c: every allocation of cook, open, cook_to_path and expand failed in turn (clean error, nothing
 * leaked, no partial file), and cooks killed mid-write never damage the destination. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif
#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#ifndef _WIN32
#include <sys/wait.h>
#endif
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "cbvh.h"
#include "support/counting_alloc.h"
#include "support/test_os.h"
#include "support/scene_gen.h"

static scene mesh;     /* small, with materials: every section present */
static scene big_mesh; /* for the kill test */
static void *file_raw, *file_zlib, *file_q16;
static size_t size_raw, size_zlib, size_q16;

static cbvh_mesh as_mesh(const scene *s)
{
    cbvh_mesh m = {s->positions, s->vertex_count, 0, s->indices, s->triangle_count, s->material_ids};
    return m;
}

static void options_for(cbvh_cook_options *o, int level, int quantized)
{
    cbvh_cook_options_init(o, sizeof *o);
    o->compress_level = level;
    o->vertex_format = quantized ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
}

static int group_setup(void **state)
{
    (void)state;
    float c[3] = {0, 0, 0};
    if (!scene_sphere(&mesh, 500, c, 1.0f) || !scene_terrain(&big_mesh, 250000, 100.0f))
        return -1;
    mesh.material_ids = malloc(mesh.triangle_count * sizeof(uint32_t));
    for (size_t t = 0; t < mesh.triangle_count; t++)
        mesh.material_ids[t] = (uint32_t)(t % 7) * 1000u;
    cbvh_mesh m = as_mesh(&mesh);
    cbvh_cook_options o;
    options_for(&o, 0, 0);
    if (cbvh_cook(&m, &o, NULL, &file_raw, &size_raw, NULL, NULL) != CBVH_OK)
        return -1;
    options_for(&o, 6, 0);
    if (cbvh_cook(&m, &o, NULL, &file_zlib, &size_zlib, NULL, NULL) != CBVH_OK)
        return -1;
    options_for(&o, 0, 1);
    if (cbvh_cook(&m, &o, NULL, &file_q16, &size_q16, NULL, NULL) != CBVH_OK)
        return -1;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    cbvh_buffer_free(NULL, file_raw);
    cbvh_buffer_free(NULL, file_zlib);
    cbvh_buffer_free(NULL, file_q16);
    scene_free(&mesh);
    scene_free(&big_mesh);
    return 0;
}

/* Cooks with allocation n failing, for n = 0, 1, 2 ... until the cook
 * succeeds; each failure must be CBVH_ERROR_OUT_OF_MEMORY with a message and
 * nothing live. With fail_all, every allocation from n on fails too (the
 * cleanup paths must not allocate). Returns the number of failure points. */
static size_t oom_loop_cook(int level, int quantized, int fail_all, const void *expect, size_t expect_size)
{
    cbvh_mesh m = as_mesh(&mesh);
    cbvh_cook_options o;
    options_for(&o, level, quantized);
    for (size_t n = 0;; n++) {
        counting_alloc c;
        cbvh_allocator a = counting_allocator(&c, n, fail_all);
        void *out = NULL;
        size_t out_size = 0;
        cbvh_error err;
        cbvh_result r = cbvh_cook(&m, &o, &a, &out, &out_size, NULL, &err);
        if (r == CBVH_OK) {
            assert_int_equal(out_size, expect_size);
            assert_memory_equal(out, expect, out_size);
            cbvh_buffer_free(&a, out);
            assert_int_equal(c.live, 0);
            return n;
        }
        if (r != CBVH_ERROR_OUT_OF_MEMORY)
            fail_msg("cook with allocation %zu failing: %s (%s)", n, cbvh_result_string(r), err.message);
        assert_true(err.message[0] != 0);
        assert_null(out);
        if (c.live != 0)
            fail_msg("cook with allocation %zu failing leaked %ld blocks", n, c.live);
        assert_true(n < 100000);
    }
}

static void test_cook_oom(void **state)
{
    (void)state;
    size_t raw = oom_loop_cook(0, 0, 0, file_raw, size_raw);
    size_t zlib = oom_loop_cook(6, 0, 0, file_zlib, size_zlib);
    size_t q16 = oom_loop_cook(0, 1, 0, file_q16, size_q16);
    size_t raw_all = oom_loop_cook(0, 0, 1, file_raw, size_raw);
    printf("cook failure points: raw %zu, zlib %zu, quantized %zu (raw, every later allocation failing too: "
           "%zu)\n",
           raw, zlib, q16, raw_all);
    assert_true(raw > 0 && zlib > 0 && q16 > 0);
}

/* What a file opened under the failing allocator must still do: hit the sphere. */
static void hits_the_sphere(const cbvh_file *f)
{
    cbvh_hit h;
    cbvh_ray ray = {{0, 0, -5}, 0, {0, 0, 1}, INFINITY};
    assert_int_equal(cbvh_raycast(f, &ray, CBVH_TRAVERSAL_SORTED, &h, NULL), 1);
}

/* The same for opening from memory (aligned and misaligned buffers) and by path. */
static size_t oom_loop_open(const void *data, size_t size, const char *path)
{
    return counting_open_failures(data, size, path, hits_the_sphere);
}

static void write_whole(const char *path, const void *data, size_t size)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    assert_int_equal(fwrite(data, 1, size, fp), size);
    assert_int_equal(fclose(fp), 0);
}

static void test_open_oom(void **state)
{
    (void)state;
    size_t raw = oom_loop_open(file_raw, size_raw, NULL);
    size_t zlib = oom_loop_open(file_zlib, size_zlib, NULL);
    size_t q16 = oom_loop_open(file_q16, size_q16, NULL);
    /* a misaligned copy makes the loader copy raw sections */
    uint8_t *odd = malloc(size_raw + 1);
    memcpy(odd + 1, file_raw, size_raw);
    size_t misaligned = oom_loop_open(odd + 1, size_raw, NULL);
    free(odd);
    char dir[200], path[256];
    test_temp_dir(dir, sizeof dir, "cbvh_oom");
    snprintf(path, sizeof path, "%s/f.cbvh", dir);
    write_whole(path, file_zlib, size_zlib);
    size_t by_path = oom_loop_open(NULL, 0, path);
    unlink(path);
    rmdir(dir);
    printf("open failure points: raw %zu, zlib %zu, quantized %zu, misaligned raw %zu, zlib by path %zu\n",
           raw, zlib, q16, misaligned, by_path);
}

/* The closest hits of a fan of rays through the sphere's center, into out[count]. */
static void cast_fan(const cbvh_file *f, cbvh_hit *out, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        const float a = 0.37f * (float)i, z = 1.0f - 2.0f * (float)(i + 1) / (float)(count + 1);
        const cbvh_ray r = {{0.01f, 0.02f, 0.03f}, 0.0f, {cosf(a), sinf(a), z}, INFINITY};
        cbvh_raycast(f, &r, CBVH_TRAVERSAL_SORTED, &out[i], NULL);
    }
}

/* cbvh_file_expand_triangles: its allocation failing leaves the file as it was (same answers, nothing
 * expanded, nothing leaked); then it expands (SIMD builds) with the same answers, and a second call
 * allocates nothing. */
static void test_expand_oom(void **state)
{
    (void)state;
    enum { RAYS = 200 };
    counting_alloc c;
    cbvh_allocator a = counting_allocator(&c, -1, 0);
    cbvh_file *f = NULL;
    cbvh_error err;
    assert_int_equal(cbvh_open_memory(file_raw, size_raw, &a, &f, &err), CBVH_OK);
    cbvh_hit before[RAYS], after[RAYS];
    cast_fan(f, before, RAYS);
    assert_int_equal(cbvh_file_expand_triangles(NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    cbvh_file_info info;
    const long live = c.live;
#ifdef CBVH_HAVE_SIMD
    c.fail_at = c.calls;
    assert_int_equal(cbvh_file_expand_triangles(f, &err), CBVH_ERROR_OUT_OF_MEMORY);
    assert_non_null(strstr(err.message, "expanded triangles"));
    assert_int_equal(c.live, live);
    cbvh_file_get_info(f, &info, sizeof info);
    assert_int_equal(info.expanded_bytes, 0);
    cast_fan(f, after, RAYS);
    assert_memory_equal(before, after, sizeof before);
    c.fail_at = -1;
#endif
    assert_int_equal(cbvh_file_expand_triangles(f, &err), CBVH_OK);
    cbvh_file_get_info(f, &info, sizeof info);
#ifdef CBVH_HAVE_SIMD
    /* 36 bytes a triangle, in groups of four */
    assert_int_equal(info.expanded_bytes, 144u * ((info.triangle_count + 3u) / 4u));
    assert_int_equal(c.live, live + 1);
#else
    assert_int_equal(info.expanded_bytes, 0); /* the scalar test has no use for the copy */
    assert_int_equal(c.live, live);
#endif
    const long calls = c.calls;
    assert_int_equal(cbvh_file_expand_triangles(f, &err), CBVH_OK);
    assert_int_equal(c.calls, calls);
    cast_fan(f, after, RAYS);
    assert_memory_equal(before, after, sizeof before);
    cbvh_close(f);
    assert_int_equal(c.live, 0);
}

/* Names in `dir`, other than `keep`. */
static size_t count_entries(const char *dir, const char *keep)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    size_t n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && (!keep || strcmp(e->d_name, keep)))
            n++;
    closedir(d);
    return n;
}

static uint8_t *read_whole(const char *path, size_t *size)
{
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return NULL;
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    uint8_t *b = malloc(n > 0 ? (size_t)n : 1);
    *size = fread(b, 1, (size_t)n, fp);
    fclose(fp);
    return b;
}

/* cook_to_path with each allocation failing: a clean error, nothing live,
 * no file left behind, and an existing file at the path left as it was. */
static void test_cook_to_path_oom(void **state)
{
    (void)state;
    char dir[200], path[256];
    test_temp_dir(dir, sizeof dir, "cbvh_oom");
    snprintf(path, sizeof path, "%s/out.cbvh", dir);
    cbvh_mesh m = as_mesh(&mesh);
    cbvh_cook_options o;
    options_for(&o, 6, 0);
    static const uint8_t old_bytes[] = "an older file that must survive a failed cook";
    size_t points[2] = {0, 0};
    for (int with_old = 0; with_old < 2; with_old++) {
        for (size_t n = 0;; n++) {
            if (with_old)
                write_whole(path, old_bytes, sizeof old_bytes);
            counting_alloc c;
            cbvh_allocator a = counting_allocator(&c, n, 0);
            cbvh_error err;
            cbvh_result r = cbvh_cook_to_path(&m, &o, &a, path, NULL, &err);
            assert_int_equal(c.live, 0);
            size_t got_size = 0;
            uint8_t *got = read_whole(path, &got_size);
            if (r == CBVH_OK) {
                assert_non_null(got);
                assert_int_equal(got_size, size_zlib);
                assert_memory_equal(got, file_zlib, got_size);
                free(got);
                assert_int_equal(count_entries(dir, "out.cbvh"), 0);
                unlink(path);
                points[with_old] = n;
                break;
            }
            if (r != CBVH_ERROR_OUT_OF_MEMORY)
                fail_msg("cook_to_path with allocation %zu failing: %s (%s)", n, cbvh_result_string(r),
                         err.message);
            if (with_old) {
                assert_non_null(got);
                assert_int_equal(got_size, sizeof old_bytes);
                assert_memory_equal(got, old_bytes, sizeof old_bytes);
            } else {
                assert_null(got);
            }
            free(got);
            if (count_entries(dir, "out.cbvh") != 0)
                fail_msg("cook_to_path with allocation %zu failing left a temporary file in %s", n, dir);
            assert_true(n < 100000);
        }
    }
    unlink(path);
    rmdir(dir);
    printf("cook_to_path failure points: %zu into an empty folder, %zu over an existing file\n", points[0],
           points[1]);
}

/* A child cooks a large mesh to the path and is killed after a random delay;
 * the destination must be absent, the old complete file or the new complete
 * file. Temporary files a killed process cannot remove are counted. */
static void test_killed_cook(void **state)
{
    (void)state;
#ifdef _WIN32
    skip(); /* killing a child process mid-cook needs fork() */
#else
    cbvh_mesh m = as_mesh(&big_mesh);
    cbvh_cook_options o;
    options_for(&o, 1, 0);
    void *expect = NULL;
    size_t expect_size = 0;
    assert_int_equal(cbvh_cook(&m, &o, NULL, &expect, &expect_size, NULL, NULL), CBVH_OK);
    char dir[200], path[256];
    test_temp_dir(dir, sizeof dir, "cbvh_kill");
    snprintf(path, sizeof path, "%s/level.cbvh", dir);
    /* how long a whole cook_to_path takes here, to spread the kills over it */
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    assert_int_equal(cbvh_cook_to_path(&m, &o, NULL, path, NULL, NULL), CBVH_OK);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double cook_seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    unlink(path);
    const char *env = getenv("CBVH_KILL_ROUNDS");
    int rounds = env ? atoi(env) : 12;
    uint64_t rng = 2024;
    size_t absent = 0, old_kept = 0, new_complete = 0, finished = 0;
    for (int i = 0; i < rounds; i++) {
        int with_old = i % 2;
        if (with_old)
            write_whole(path, file_raw, size_raw);
        else
            unlink(path);
        /* delays spread over the whole cook, the write and rename at the end
         * included; every third round lands in the last quarter, where the file is written */
        double delay =
            cook_seconds * (i % 3 == 2 ? 0.8 + 0.4 * scene_rand_unit(&rng) : 1.2 * scene_rand_unit(&rng));
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            cbvh_result r = cbvh_cook_to_path(&m, &o, NULL, path, NULL, NULL);
            _exit(r == CBVH_OK ? 0 : 1);
        }
        struct timespec d = {(time_t)delay, (long)((delay - (double)(time_t)delay) * 1e9)};
        nanosleep(&d, NULL);
        kill(pid, SIGKILL);
        int status;
        waitpid(pid, &status, 0);
        if (WIFEXITED(status)) {
            assert_int_equal(WEXITSTATUS(status), 0);
            finished++;
        }
        size_t got_size = 0;
        uint8_t *got = read_whole(path, &got_size);
        if (!got) {
            assert_false(with_old); /* an old file may only be replaced, never removed */
            absent++;
        } else if (with_old && got_size == size_raw && memcmp(got, file_raw, size_raw) == 0) {
            old_kept++;
        } else {
            if (got_size != expect_size || memcmp(got, expect, expect_size) != 0)
                fail_msg("round %d (killed after %.3f s): %s holds %zu bytes that are neither the old nor "
                         "the new file",
                         i, delay, path, got_size);
            cbvh_file *f = NULL;
            assert_int_equal(cbvh_open_path(path, NULL, &f, NULL), CBVH_OK);
            cbvh_close(f);
            new_complete++;
        }
        free(got);
    }
    size_t leftovers = count_entries(dir, "level.cbvh");
    printf("killed cooks: %d rounds over a %.2f s cook: destination absent %zu, old file intact %zu, new "
           "complete file %zu "
           "(%zu children finished before the kill); temporary files left by killed children: %zu\n",
           rounds, cook_seconds, absent, old_kept, new_complete, finished, leftovers);
    /* clean up what killed children left */
    DIR *d = opendir(dir);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        char p[512];
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        unlink(p);
    }
    closedir(d);
    rmdir(dir);
    cbvh_buffer_free(NULL, expect);
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cook_oom),    cmocka_unit_test(test_open_oom),
        cmocka_unit_test(test_expand_oom),  cmocka_unit_test(test_cook_to_path_oom),
        cmocka_unit_test(test_killed_cook),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
