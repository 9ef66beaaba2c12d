/* layouts.h: runs a test program's cmocka group once per node layout (and the wide layout's other walk
 * kernels). */
#ifndef CBVH_TESTS_SUPPORT_LAYOUTS_H
#define CBVH_TESTS_SUPPORT_LAYOUTS_H

#include <stdio.h>
#include <stdlib.h>

#ifdef HAVE_CONFIG_H
#include "config.h" /* CBVH_HAVE_SIMD */
#endif

#include "cbvh.h"
#include "query/test_hooks.h" /* cbvh_walk_set_kernel: programs link lib/libcbvh_test_hooks.la */
#include "support/reference.h"

/* The kernels of lib/query/raycast.h's enum cbvh_walk_kernel. */
enum { TEST_KERNEL_BEST, TEST_KERNEL_SCALAR, TEST_KERNEL_SSE2, TEST_KERNEL_AVX2 };

/* What test_set_kernel last set: a test that switches the kernel restores it. */
static int test_kernel_now;

/* The kernel the walks took when test_set_kernel last asked for the best one. */
static int test_kernel_best = TEST_KERNEL_BEST;

/* Makes the walks take `kernel`; returns 1 when they now do (0: the build or the CPU lacks the kernel, and
 * the walks took the best below it). */
static inline int test_set_kernel(int kernel)
{
    const int chosen = cbvh_walk_set_kernel(kernel);
    test_kernel_now = kernel;
    if (kernel == TEST_KERNEL_BEST)
        test_kernel_best = chosen;
    return kernel == TEST_KERNEL_BEST || chosen == kernel;
}

/* How many of kernels[0..n) the build and the CPU have; the kernel test_set_kernel last set is set again. */
static inline int test_kernels_available(const int *kernels, size_t n)
{
    const int before = test_kernel_now;
    int available = 0;
    for (size_t k = 0; k < n; k++)
        available += test_set_kernel(kernels[k]);
    test_set_kernel(before);
    return available;
}

/* CBVH_TEST_REPS: the percentage of their random queries the property tests run (default 100; 10 to 100,
 * a smaller one is 10; anything else, 100). tests/sanitize.sh and tests/mingw_wine.sh set 10, quickstart's
 * distcheck 25: there the point is what the sanitizers, Windows and the tarball see on every path (every
 * layout, kernel, shape, scene and cook variant still runs), while the main build's full counts search for
 * wrong answers. */
static inline int test_reps_percent(void)
{
    static int percent;
    if (!percent) {
        const char *e = getenv("CBVH_TEST_REPS");
        const int p = e && *e ? atoi(e) : 100;
        percent = p <= 0 || p > 100 ? 100 : p < 10 ? 10 : p;
        if (percent < 100)
            fprintf(stderr, "CBVH_TEST_REPS=%d: %d%% of the random queries\n", percent, percent);
    }
    return percent;
}

/* How many of `n` random queries to run (rounded up, at least one): a test keeps a prefix of them. */
static inline long test_reps(long n)
{
    const long r = (n * test_reps_percent() + 99) / 100;
    return r > 0 ? r : 1;
}

/* Every `stride`-th item at full counts: the stride that visits test_reps of them. */
static inline long test_reps_stride(long stride)
{
    return (stride * 100 + test_reps_percent() - 1) / test_reps_percent();
}

/* A check that a property test was not empty (at least `n` hits at full counts): with fewer queries, a
 * quarter of their share of n (small samples vary more; at least one). */
static inline long test_least(long n)
{
    const int p = test_reps_percent();
    if (p == 100)
        return n;
    const long r = n * p / 400;
    return r > 0 ? r : 1;
}

/* The layout the group being run cooks with. */
static cbvh_layout test_layout = CBVH_LAYOUT_BINARY;

/* cbvh_cook_options_init plus the layout under test. */
static inline void test_options_init(cbvh_cook_options *o)
{
    cbvh_cook_options_init(o, sizeof *o);
    o->layout = test_layout;
}

/* The default options for the layout under test (for calls that took NULL). */
static inline const cbvh_cook_options *test_options(void)
{
    static cbvh_cook_options o;
    test_options_init(&o);
    return &o;
}

static inline const char *test_layout_name(void)
{
    return test_layout == CBVH_LAYOUT_WIDE4 ? "wide4" : "binary";
}

/* Runs `tests` on the binary layout, then on wide4 with the best walk kernel, then, when `kernels` is set,
 * on wide4 with the SSE2 kernel when the best one is AVX2, and with the scalar kernel when the best one is
 * not already scalar, then on wide4 with the files ref_cook_open
 * opens expanded (cbvh_file_expand_triangles) in builds with SIMD kernels (without them the expansion
 * copies nothing, and that run would repeat the wide4 one query for query). Returns the number of failed
 * tests over all runs. A function, so the runs happen in this order. */
static inline int test_run_layouts(const char *names[5], const struct CMUnitTest *tests, size_t count,
                                   int kernels)
{
    int failed = 0;
    test_layout = CBVH_LAYOUT_BINARY;
    test_set_kernel(TEST_KERNEL_BEST);
    failed += _cmocka_run_group_tests(names[0], tests, count, NULL, NULL);
    test_layout = CBVH_LAYOUT_WIDE4;
    failed += _cmocka_run_group_tests(names[1], tests, count, NULL, NULL);
    if (kernels && test_set_kernel(TEST_KERNEL_AVX2) && test_set_kernel(TEST_KERNEL_SSE2))
        failed += _cmocka_run_group_tests(names[2], tests, count, NULL, NULL);
    if (kernels && test_kernel_best != TEST_KERNEL_SCALAR && test_set_kernel(TEST_KERNEL_SCALAR))
        failed += _cmocka_run_group_tests(names[3], tests, count, NULL, NULL);
    test_set_kernel(TEST_KERNEL_BEST);
#ifdef CBVH_HAVE_SIMD
    ref_expand_triangles = 1;
    failed += _cmocka_run_group_tests(names[4], tests, count, NULL, NULL);
    ref_expand_triangles = 0;
#else
    fprintf(stderr, "%s: skipped (no SIMD kernels: the expansion copies nothing)\n", names[4]);
#endif
    return failed;
}

#define TEST_RUN_LAYOUTS(tests, kernels)                                                                     \
    test_run_layouts((const char *[5]){"binary layout", "wide4 layout", "wide4 layout, SSE2 walks",          \
                                       "wide4 layout, scalar walks", "wide4 layout, expanded triangles"},    \
                     tests, sizeof(tests) / sizeof((tests)[0]), kernels)

#endif
