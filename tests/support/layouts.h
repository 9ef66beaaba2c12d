/* layouts.h: runs a test program's cmocka group once per node layout (and the wide layout's scalar child test). */
#ifndef CBVH_TESTS_SUPPORT_LAYOUTS_H
#define CBVH_TESTS_SUPPORT_LAYOUTS_H

#include <stdio.h>

#include "cbvh.h"
#include "support/reference.h"

/* Test hook of the library (lib/query/raycast.h), hidden in the shared
 * library: programs linked statically can choose the scalar child test;
 * for the others the weak reference is NULL and the scalar run is skipped. */
void cbvh_walk_set_scalar(int scalar) __attribute__((weak));

/* What test_set_scalar last set: a test that switches the child test restores it. */
static int test_scalar_now;

static inline int test_set_scalar(int scalar)
{
    if (!cbvh_walk_set_scalar)
        return 0;
    cbvh_walk_set_scalar(scalar);
    test_scalar_now = scalar;
    return 1;
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

/* Runs `tests` on the binary layout, then on wide4 with SIMD child tests,
 * then (when `scalar` is set and the program can reach the hook) on wide4
 * with the scalar child test, then on wide4 with the files ref_cook_open opens
 * expanded (cbvh_file_expand_triangles). Returns the number of failed tests
 * over all runs. A function, so the runs happen in this order. */
static inline int test_run_layouts(const char *names[4], const struct CMUnitTest *tests, size_t count,
                                   int scalar)
{
    int failed = 0;
    test_layout = CBVH_LAYOUT_BINARY;
    test_set_scalar(0);
    failed += _cmocka_run_group_tests(names[0], tests, count, NULL, NULL);
    test_layout = CBVH_LAYOUT_WIDE4;
    failed += _cmocka_run_group_tests(names[1], tests, count, NULL, NULL);
    if (scalar && test_set_scalar(1)) {
        failed += _cmocka_run_group_tests(names[2], tests, count, NULL, NULL);
        test_set_scalar(0);
    }
    ref_expand_triangles = 1;
    failed += _cmocka_run_group_tests(names[3], tests, count, NULL, NULL);
    ref_expand_triangles = 0;
    return failed;
}

#define TEST_RUN_LAYOUTS(tests, scalar)                                                                      \
    test_run_layouts((const char *[4]){"binary layout", "wide4 layout", "wide4 layout, scalar child test",   \
                                       "wide4 layout, expanded triangles"},                                  \
                     tests, sizeof(tests) / sizeof((tests)[0]), scalar)

#endif
