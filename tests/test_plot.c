/* test_plot.c: the report's plot code: label placement (no overlap, inside the canvas, also on clustered
 * input), axis ticks, Pareto front, SVG text. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "label_layout.h"
#include "pareto.h"
#include "plot_axis.h"
#include "report.h"
#include "svg_plot.h"

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double next_unit(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Every placed box inside the area, clear of every other placed box and every obstacle. */
static void check_spots(const label_request *req, const label_spot *spots, size_t n,
                        const label_box *obstacles, size_t obstacle_count, const label_box *area)
{
    for (size_t i = 0; i < n; i++) {
        if (!spots[i].placed)
            continue;
        const label_box *b = &spots[i].box;
        if (!label_box_inside(b, area))
            fail_msg("label %zu at [%g %g %g %g] leaves the area [%g %g %g %g]", i, b->x0, b->y0, b->x1,
                     b->y1, area->x0, area->y0, area->x1, area->y1);
        assert_true(fabs((b->x1 - b->x0) - req[i].width) < 1e-9 &&
                    fabs((b->y1 - b->y0) - req[i].height) < 1e-9);
        for (size_t j = 0; j < i; j++)
            if (spots[j].placed && label_boxes_overlap(b, &spots[j].box))
                fail_msg("labels %zu and %zu overlap", j, i);
        for (size_t k = 0; k < obstacle_count; k++)
            if (label_boxes_overlap(b, &obstacles[k]))
                fail_msg("label %zu covers marker %zu", i, k);
    }
}

/* Markers at the given centres, labels of the given size; checks the invariants, returns the number placed.
 */
static size_t layout_points(const double (*xy)[2], size_t n, double w, double h, const label_box *area,
                            label_spot *spots)
{
    label_request *req = malloc(n * sizeof *req);
    label_box *markers = malloc(n * sizeof *markers);
    assert_non_null(req);
    assert_non_null(markers);
    for (size_t i = 0; i < n; i++) {
        req[i] = (label_request){xy[i][0], xy[i][1], w * (0.5 + (double)(i % 3) / 2), h};
        markers[i] = (label_box){xy[i][0] - 6, xy[i][1] - 6, xy[i][0] + 6, xy[i][1] + 6};
    }
    size_t placed = label_layout(req, n, markers, n, area, 1.5, 8.0, spots);
    check_spots(req, spots, n, markers, n, area);
    size_t count = 0;
    for (size_t i = 0; i < n; i++)
        count += (size_t)spots[i].placed;
    assert_int_equal(count, placed);
    free(req);
    free(markers);
    return placed;
}

static void test_lone_label_sits_beside_its_marker(void **state)
{
    (void)state;
    const double xy[1][2] = {{200, 150}};
    label_box area = {0, 0, 400, 300};
    label_spot s;
    assert_int_equal(layout_points(xy, 1, 60, 13, &area, &s), 1);
    assert_false(s.leader);
    assert_true(s.box.x0 >= 206 && s.box.x0 <= 215); /* right of the marker, vertically centred */
    assert_true(fabs((s.box.y0 + s.box.y1) / 2 - 150) < 1e-9);

    /* At the right edge the label goes left, still beside it. */
    const double edge[1][2] = {{395, 150}};
    assert_int_equal(layout_points(edge, 1, 60, 13, &area, &s), 1);
    assert_false(s.leader);
    assert_true(s.box.x1 <= 389);
}

static void test_scattered_points(void **state)
{
    (void)state;
    enum { N = 40 };
    double xy[N][2];
    for (size_t i = 0; i < N; i++) {
        xy[i][0] = 20 + 460 * next_unit();
        xy[i][1] = 20 + 260 * next_unit();
    }
    label_box area = {0, 0, 500, 300};
    label_spot spots[N];
    assert_int_equal(layout_points(xy, N, 60, 13, &area, spots), N);
}

/* Adversarial: every marker on one pixel, in the middle and in each corner and on an edge. */
static void test_points_on_one_pixel(void **state)
{
    (void)state;
    enum { N = 20 };
    static const double spots_at[][2] = {{250, 150}, {0, 0}, {500, 300}, {500, 0}, {0, 300}, {250, 300}};
    label_box area = {0, 0, 500, 300};
    for (size_t k = 0; k < sizeof spots_at / sizeof spots_at[0]; k++) {
        double xy[N][2];
        for (size_t i = 0; i < N; i++) {
            xy[i][0] = spots_at[k][0];
            xy[i][1] = spots_at[k][1];
        }
        label_spot spots[N];
        assert_int_equal(layout_points(xy, N, 70, 13, &area, spots), N);
        size_t leaders = 0;
        for (size_t i = 0; i < N; i++)
            leaders += (size_t)spots[i].leader;
        assert_true(leaders >= N - 8); /* at most the eight places right beside the marker */
    }
}

/* Adversarial: a tight cluster plus a line of points along the top edge. */
static void test_cluster_and_edge_line(void **state)
{
    (void)state;
    enum { N = 36 };
    double xy[N][2];
    for (size_t i = 0; i < 24; i++) {
        xy[i][0] = 480 + 6 * next_unit();
        xy[i][1] = 280 + 6 * next_unit();
    }
    for (size_t i = 24; i < N; i++) {
        xy[i][0] = 20.0 * (double)(i - 24);
        xy[i][1] = 0;
    }
    label_box area = {0, 0, 500, 300};
    label_spot spots[N];
    assert_int_equal(layout_points(xy, N, 60, 13, &area, spots), N);
}

/* More labels than the area holds: some are left out, the rest still obey every rule. */
static void test_more_labels_than_room(void **state)
{
    (void)state;
    enum { N = 300 };
    double(*xy)[2] = malloc(N * sizeof *xy);
    label_spot *spots = malloc(N * sizeof *spots);
    assert_non_null(xy);
    assert_non_null(spots);
    for (size_t i = 0; i < N; i++) {
        xy[i][0] = 100 + 10 * next_unit();
        xy[i][1] = 50 + 10 * next_unit();
    }
    label_box area = {0, 0, 200, 100};
    size_t placed = layout_points((const double(*)[2])xy, N, 80, 13, &area, spots);
    assert_true(placed > 5 && placed < N);
    free(xy);
    free(spots);
}

/* The whole panel: clustered configurations (as the report's are) get every label inside the panel, none
 * overlapping. */
static void test_panel_labels(void **state)
{
    (void)state;
    enum { N = 14 };
    static const char *const names[N] = {
        "default",      "leaf 1",   "leaf 2",    "leaf 8",      "leaf 16",
        "unsorted",     "distance", "stackless", "stream",      "float boxes (reference)",
        "q16 vertices", "zlib",     "wide",      "wide, stream"};
    plot_point pts[N];
    for (size_t i = 0; i < N; i++)
        pts[i] = (plot_point){600 + 3 * next_unit(),
                              0.1 + 1e-3 * next_unit(),
                              (unsigned)(i % PLOT_STYLE_COUNT),
                              names[i],
                              NULL,
                              0};
    pts[3].x = 1e4; /* one far outlier squeezes the rest into a clump */
    plot_panel panel = {"title", "x", "y", pts, N, 1};
    FILE *out = tmpfile();
    assert_non_null(out);
    label_spot spots[N];
    const double left = 100, top = 50;
    size_t placed = svg_plot_panel(out, &panel, left, top, "p", spots);
    assert_int_equal(placed, N);
    label_box canvas = {left, top, left + PLOT_PANEL_W, top + PLOT_PANEL_H};
    for (size_t i = 0; i < N; i++) {
        assert_true(spots[i].placed);
        assert_true(label_box_inside(&spots[i].box, &canvas));
        for (size_t j = 0; j < i; j++)
            assert_false(label_boxes_overlap(&spots[i].box, &spots[j].box));
    }
    /* every point is focusable and has its text */
    rewind(out);
    char buf[1 << 16];
    size_t len = fread(buf, 1, sizeof buf - 1, out);
    buf[len] = '\0';
    size_t focusable = 0;
    for (const char *s = buf; (s = strstr(s, "tabindex=\"0\"")) != NULL; s++)
        focusable++;
    assert_int_equal(focusable, N);
    assert_non_null(strstr(buf, "class=\"front\""));
    assert_non_null(strstr(buf, "float boxes (reference)</text>"));
    fclose(out);

    /* points without a value are named in a note cut to the plot's width */
    for (size_t i = 0; i < N; i += 2)
        pts[i].y = NAN;
    out = tmpfile();
    assert_non_null(out);
    placed = svg_plot_panel(out, &panel, left, top, NULL, spots);
    assert_int_equal(placed, N / 2);
    rewind(out);
    len = fread(buf, 1, sizeof buf - 1, out);
    buf[len] = '\0';
    const char *note = strstr(buf, ">Not shown (no value here): default, leaf 2,");
    assert_non_null(note);
    const char *end = strstr(note, "</text>");
    assert_non_null(end);
    char line[512];
    snprintf(line, sizeof line, "%.*s", (int)(end - note - 1), note + 1);
    assert_true(svg_text_width(line, 10) <= PLOT_PANEL_W);
    assert_non_null(strstr(line, "..."));
    fclose(out);
}

/* ---- axes ---- */

static int is_125(double step)
{
    double mag = pow(10.0, floor(log10(step) + 1e-9)), f = step / mag;
    return fabs(f - 1) < 1e-9 || fabs(f - 2) < 1e-9 || fabs(f - 5) < 1e-9;
}

static void check_linear(const double *v, size_t n, double expect_lo)
{
    plot_axis a = {.pixel_lo = 0, .pixel_hi = 100};
    plot_axis_fit(&a, v, n);
    assert_false(a.log);
    assert_true(a.tick_count >= 4 && a.tick_count <= 11);
    assert_true(is_125(a.step));
    for (size_t i = 0; i < n; i++)
        assert_true(!isfinite(v[i]) ||
                    (fmax(v[i], -1e300) >= a.lo && fmin(v[i], 1e300) <= a.hi)); /* clamped to +-1e300 */
    assert_true(fabs(a.ticks[0] - a.lo) < 1e-12 * fmax(1, fabs(a.lo)));
    for (size_t k = 1; k < a.tick_count; k++)
        assert_true(fabs(a.ticks[k] - a.ticks[k - 1] - a.step) < 1e-9 * a.step);
    if (!isnan(expect_lo))
        assert_true(fabs(a.lo - expect_lo) < 1e-12);
    double p0 = plot_axis_pixel(&a, a.lo), p1 = plot_axis_pixel(&a, a.hi);
    assert_true(fabs(p0) < 1e-9 && fabs(p1 - 100) < 1e-9);
}

static void test_linear_ticks(void **state)
{
    (void)state;
    const double times[] = {412, 893, 640, 701}; /* the 400-900 ns band: many ticks, not two */
    check_linear(times, 4, NAN);
    plot_axis a = {0};
    plot_axis_fit(&a, times, 4);
    assert_true(a.step == 100 && a.lo == 400 && a.hi == 900);
    char label[32];
    plot_axis_tick_label(&a, 500, label, sizeof label);
    assert_string_equal(label, "500");

    const double inflation[] = {0.0, 0.21, 0.19, 0.25};
    check_linear(inflation, 4, 0.0);
    const double extra[] = {-0.5, 3.2, 1.0}; /* negative: never log */
    check_linear(extra, 3, NAN);
    const double same[] = {7, 7, 7};
    check_linear(same, 3, NAN);
    const double none[] = {NAN, INFINITY};
    check_linear(none, 2, 0.0);
    const double huge[] = {-1.7e308, 1.7e308}; /* finite ticks, a handful of them */
    check_linear(huge, 2, NAN);

    const double tiny[] = {0.0, 3.1e-6, 8.7e-6}; /* one decade: linear, ticks scaled by 10^-6 */
    plot_axis_fit(&a, tiny, 3);
    assert_false(a.log);
    assert_int_equal(a.factor_exp, -6);
    plot_axis_tick_label(&a, 4e-6, label, sizeof label);
    assert_string_equal(label, "4");
    plot_axis_title_note(&a, label, sizeof label);
    assert_string_equal(label, " (\u00d710\u207b\u2076)");
}

static void test_log_only_across_decades(void **state)
{
    (void)state;
    const double err[] = {2e-9, 3e-8, 4.5e-5};
    plot_axis a = {.pixel_lo = 300, .pixel_hi = 0};
    plot_axis_fit(&a, err, 3);
    assert_true(a.log);
    assert_false(a.zero_band);
    assert_true(fabs(a.lo / 1e-9 - 1) < 1e-12 &&
                fabs(a.hi / 1e-4 - 1) < 1e-12); /* decades, computed as powers of ten */
    for (size_t k = 0; k < a.tick_count; k++) { /* decades only: five of them */
        double e = log10(a.ticks[k]);
        assert_true(fabs(e - round(e)) < 1e-9);
    }
    char label[32];
    plot_axis_tick_label(&a, 1e-6, label, sizeof label);
    assert_string_equal(label, "10\u207b\u2076");
    plot_axis_tick_label(&a, 1e-3, label, sizeof label);
    assert_string_equal(label, "0.001");
    /* pixels fall as values grow on this y axis, strictly */
    assert_true(plot_axis_pixel(&a, 1e-8) > plot_axis_pixel(&a, 1e-7));
    assert_true(isnan(plot_axis_pixel(&a, 0.0)) && isnan(plot_axis_pixel(&a, -1.0)));

    /* zeros among values that span decades: a 0 line below the lowest decade */
    const double with_zero[] = {0.0, 1.5e-7, 2e-5};
    plot_axis_fit(&a, with_zero, 3);
    assert_true(a.log && a.zero_band);
    assert_true(plot_axis_pixel(&a, 0.0) == 300);
    assert_true(fabs(plot_axis_pixel(&a, a.lo) - (300 - PLOT_AXIS_ZERO_BAND)) < 1e-9);

    /* under PLOT_AXIS_LOG_SPAN: linear */
    const double narrow[] = {1.0, 50.0};
    plot_axis_fit(&a, narrow, 2);
    assert_false(a.log);

    /* two decades or fewer: 1, 2, 5 ticks */
    const double two[] = {1.0, 100.0};
    plot_axis_fit(&a, two, 2);
    assert_true(a.log && a.tick_count == 7);
    assert_true(a.ticks[1] == 2.0 && a.ticks[2] == 5.0);
}

/* ---- Pareto front ---- */

static void test_pareto_front(void **state)
{
    (void)state;
    const double x[] = {1, 2, 3, 4, 2, NAN, 5, 0.5};
    const double y[] = {5, 3, 4, 1, 3, 0, 1, 9};
    unsigned char front[8];
    assert_int_equal(pareto_front(x, y, 8, front), 5);
    const unsigned char expect[8] = {1, 1, 0, 1, 1, 0, 0, 1}; /* (3,4) by (2,3); (5,1) by (4,1); NaN never */
    assert_memory_equal(front, expect, 8);
    /* against the definition on random points */
    for (int round = 0; round < 50; round++) {
        double rx[30], ry[30];
        unsigned char f[30];
        for (int i = 0; i < 30; i++) {
            rx[i] = floor(10 * next_unit());
            ry[i] = floor(10 * next_unit());
        }
        pareto_front(rx, ry, 30, f);
        for (int i = 0; i < 30; i++) {
            int dominated = 0;
            for (int j = 0; j < 30; j++)
                dominated |= rx[j] <= rx[i] && ry[j] <= ry[i] && (rx[j] < rx[i] || ry[j] < ry[i]);
            assert_int_equal(f[i], !dominated);
        }
    }
}

/* ---- text ---- */

static void test_escaping_and_width(void **state)
{
    (void)state;
    FILE *out = tmpfile();
    assert_non_null(out);
    svg_write_escaped(out, "a<b&\"c'\x01\xff\xc3\x97z");
    rewind(out);
    char buf[128];
    size_t n = fread(buf, 1, sizeof buf - 1, out);
    buf[n] = '\0';
    assert_string_equal(
        buf, "a&lt;b&amp;&quot;c&#39;?\xc3\x97z"); /* control dropped, stray byte '?', UTF-8 kept */
    fclose(out);
    assert_true(svg_text_width("mmmm", 10) > svg_text_width("iiii", 10));
    assert_true(svg_text_width("leaf 16", 11) > 30 && svg_text_width("leaf 16", 11) < 50);
    assert_true(svg_text_width("", 11) == 0.0);
}

/* ---- the recommendation ---- */

/* A row of mesh "m": the default, or the default with one value changed; exact, at ns per ray. */
static report_row advice_row(int dim, const char *value, double ns)
{
    static const char *const defaults[REPORT_DIM_COUNT] = {"binary layout", "q16 boxes", "float vertices",
                                                           "leaf 16",       "sorted",    "raw sections"};
    report_row r;
    memset(&r, 0, sizeof r);
    r.mesh = "m";
    r.is_default = dim < 0;
    size_t n = 0;
    for (int d = 0; d < REPORT_DIM_COUNT; d++) {
        snprintf(r.value[d], sizeof r.value[d], "%s", d == dim ? value : defaults[d]);
        n += (size_t)snprintf(r.config + n, sizeof r.config - n, "%s%s", d ? ", " : "", r.value[d]);
    }
    r.closest_mrays = 1e3 / ns;
    r.bytes_per_triangle = 24.0;
    r.open_seconds = 0.01;
    r.compared = 2000;
    r.leaks = 0;
    r.leak_rays = 100;
    return r;
}

static void test_recommendation(void **state)
{
    (void)state;
    char text[4096];
    report_row rows[6];
    rows[0] = advice_row(-1, NULL, 1000);                      /* the default */
    rows[1] = advice_row(REPORT_DIM_SECTIONS, "zlib 6", 1050); /* the same tree: 5 % noise, 10 % allowed */
    rows[1].bytes_per_triangle = 13.0;
    rows[2] = advice_row(REPORT_DIM_LEAF, "leaf 8", 950);           /* faster, within the noise */
    rows[3] = advice_row(REPORT_DIM_VERTICES, "q16 vertices", 500); /* fastest, but lossy */
    rows[3].vertex_error = 1e-5;
    rows[3].t_err_max = 3e-5;
    rows[4] = advice_row(REPORT_DIM_BOXES, "float boxes", 400); /* fastest, but a reference */
    rows[4].reference = 1;
    rows[4].open_seconds = -1;
    rows[5] = advice_row(REPORT_DIM_TRAVERSAL, "stream", 1010);
    rows[5].flips = 1; /* a wrong answer: never recommended */
    const report_row *pick = report_recommend(rows, 6, text, sizeof text);
    assert_ptr_equal(pick, &rows[0]);
    assert_non_null(strstr(text, "Recommended: the default (binary layout"));
    assert_non_null(strstr(text, "\"leaf 8\" at 950 ns"));
    assert_non_null(strstr(text, "differ by 5 %, so differences under 10 %"));
    assert_non_null(strstr(text, "\"zlib 6\" gives 13.0 bytes per triangle instead of 24.0"));
    /* the same tree stored otherwise: its run time is noise, not a cost */
    assert_non_null(strstr(text,
                           "the same tree, so the same speed once open (its 1050 ns per ray against 1000 is "
                           "timing noise)"));
    assert_non_null(strstr(text, "\"q16 vertices\" is not exact")); /* same size: no saving claimed */

    /* beyond the noise, the faster exact configuration wins */
    rows[2].closest_mrays = 1e3 / 800;
    pick = report_recommend(rows, 6, text, sizeof text);
    assert_ptr_equal(pick, &rows[2]);
    assert_non_null(
        strstr(text, "Recommended: \"leaf 8\" (binary layout, q16 boxes, float vertices, leaf 8,"));
    assert_non_null(strstr(text, "25 % faster than the default"));
    assert_non_null(
        strstr(text, "with the same answers, at 1050 ns per ray")); /* another tree than the pick's */

    /* nothing exact: no recommendation */
    for (int i = 0; i < 6; i++)
        rows[i].wrong_triangle = 1;
    assert_null(report_recommend(rows, 6, text, sizeof text));
    assert_non_null(strstr(text, "recommends none"));

    /* a small buffer is cut, never overrun */
    char small[40];
    memset(small, 'x', sizeof small);
    rows[0].wrong_triangle = 0;
    assert_ptr_equal(report_recommend(rows, 6, small, 32), &rows[0]);
    assert_true(strlen(small) < 32 && small[39] == 'x');
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lone_label_sits_beside_its_marker),
        cmocka_unit_test(test_scattered_points),
        cmocka_unit_test(test_points_on_one_pixel),
        cmocka_unit_test(test_cluster_and_edge_line),
        cmocka_unit_test(test_more_labels_than_room),
        cmocka_unit_test(test_panel_labels),
        cmocka_unit_test(test_linear_ticks),
        cmocka_unit_test(test_log_only_across_decades),
        cmocka_unit_test(test_pareto_front),
        cmocka_unit_test(test_escaping_and_width),
        cmocka_unit_test(test_recommendation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
