/* report_plots.c: the report's plots: which measure goes on which axis, marker style and label per
 * configuration, the legend, and the `--svg` figure. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "report.h"

const char *const report_dimension_names[REPORT_DIM_COUNT] = {
    "layout", "box precision", "vertex precision", "leaf size", "traversal", "sections"};

_Static_assert(REPORT_DIM_COUNT + 1 <= PLOT_STYLE_COUNT, "a marker style per dimension plus the default's");

/* Figure layout of --svg: panels per row, heights of the headings. */
#define SVG_COLUMNS 3
#define HEADING_H 34.0

double report_ns_per_ray(const report_row *r)
{
    return r->closest_mrays > 0.0 ? 1e3 / r->closest_mrays : NAN;
}

size_t report_mesh_rows(const report_row *rows, size_t count)
{
    size_t n = 0;
    while (n < count && strcmp(rows[n].mesh, rows[0].mesh) == 0)
        n++;
    return n;
}

const report_row *report_default_row(const report_row *rows, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (rows[i].is_default)
            return &rows[i];
    return NULL;
}

int report_row_exact(const report_row *r)
{
    return r->flips == 0 && r->wrong_triangle == 0 && r->leaks <= 0 && r->t_err_max <= REPORT_TIE_TOLERANCE &&
           r->vertex_error == 0.0;
}

/* The first dimension in which r differs from the default, or -1 (r is the default or there is none). */
static int varied_dimension(const report_row *r, const report_row *def)
{
    if (!def || r->is_default)
        return -1;
    for (int d = 0; d < REPORT_DIM_COUNT; d++)
        if (strcmp(r->value[d], def->value[d]) != 0)
            return d;
    return -1;
}

void report_short_label(const report_row *r, const report_row *def, char *buf, size_t size)
{
    size_t n = 0;
    buf[0] = '\0';
    for (int d = 0; d < REPORT_DIM_COUNT && def && !r->is_default; d++)
        if (strcmp(r->value[d], def->value[d]) != 0)
            n += (size_t)snprintf(buf + n, n < size ? size - n : 0, "%s%s", n ? ", " : "", r->value[d]);
    if (!buf[0])
        snprintf(buf, size, "default");
    if (r->reference && strlen(buf) + 13 < size)
        strcat(buf, " (reference)");
}

typedef struct measure {
    const char *title, *x_title, *y_title;
    double (*x)(const report_row *);
    double (*y)(const report_row *);
    const char *y_format; /* printf format of the y value in the detail */
} measure;

static double inflation(const report_row *r)
{
    return r->inflation_mean;
}
static double extra_nodes(const report_row *r)
{
    return r->extra_nodes;
}
static double distance_error(const report_row *r)
{
    return r->t_err_max;
}
static double wrong_answers(const report_row *r)
{
    return (double)(r->flips + r->wrong_triangle) + (r->leaks > 0 ? (double)r->leaks : 0.0);
}
static double bytes_per_triangle(const report_row *r)
{
    return r->bytes_per_triangle;
}
static double open_ms(const report_row *r)
{
    return r->open_seconds >= 0.0 ? r->open_seconds * 1e3 : NAN;
}

#define NS_TITLE "closest hit, ns per ray (lower is faster)"
static const measure measures[REPORT_PLOT_COUNT] = {
    {"Box inflation against run time", NS_TITLE, "box area over exact box - 1, mean", report_ns_per_ray,
     inflation, "box inflation %.4f"},
    {"Extra work against run time", NS_TITLE, "extra nodes per ray vs exact boxes", report_ns_per_ray,
     extra_nodes, "extra nodes per ray %+.2f"},
    {"Distance error against run time", NS_TITLE, "worst |t - t_ref| / scene diagonal", report_ns_per_ray,
     distance_error, "distance error %.2e"},
    {"Flips and leaks against run time", NS_TITLE, "wrong answers (flips, triangles, leaks)",
     report_ns_per_ray, wrong_answers, "wrong answers %.0f"},
    {"File size against run time", NS_TITLE, "file bytes per triangle", report_ns_per_ray, bytes_per_triangle,
     "%.2f bytes per triangle"},
    {"Compression against open time", "open (map + validate), ms", "file bytes per triangle", open_ms,
     bytes_per_triangle, "%.2f bytes per triangle"},
};

void report_plot_panel(int k, const report_row *rows, size_t count, plot_point *points,
                       report_point_text *text, plot_panel *panel)
{
    const measure *m = &measures[k];
    const report_row *def = report_default_row(rows, count);
    for (size_t i = 0; i < count; i++) {
        const report_row *r = &rows[i];
        report_short_label(r, def, text[i].label, sizeof text[i].label);
        char y[96];
        snprintf(y, sizeof y, m->y_format, m->y(r));
        int n = snprintf(text[i].detail, sizeof text[i].detail, "%s\n%s\n", text[i].label, r->config);
        if (m->x == open_ms)
            snprintf(text[i].detail + n, sizeof text[i].detail - (size_t)n, "open %.3f ms\n%s", m->x(r), y);
        else
            snprintf(text[i].detail + n, sizeof text[i].detail - (size_t)n,
                     "%.0f ns per ray (%.2f MRays/s)\n%s", m->x(r), r->closest_mrays, y);
        points[i] = (plot_point){m->x(r),       m->y(r),        (unsigned)(varied_dimension(r, def) + 1),
                                 text[i].label, text[i].detail, r->reference};
    }
    *panel = (plot_panel){m->title, m->x_title, m->y_title, points, count, 1};
}

size_t report_legend(const report_row *rows, size_t count, plot_legend_entry *entries, char (*texts)[256])
{
    const report_row *def = report_default_row(rows, count);
    size_t n = 0;
    if (def) {
        snprintf(texts[n], sizeof texts[n], "default: %s", def->config);
        entries[n] = (plot_legend_entry){0, texts[n]};
        n++;
    }
    for (int d = 0; d < REPORT_DIM_COUNT; d++) {
        int used = 0;
        for (size_t i = 0; i < count; i++)
            used |= varied_dimension(&rows[i], def) == d;
        if (!used)
            continue;
        snprintf(texts[n], sizeof texts[n], "%s", report_dimension_names[d]);
        entries[n] = (plot_legend_entry){(unsigned)(d + 1), texts[n]};
        n++;
    }
    snprintf(texts[n], sizeof texts[n], "Pareto front (nothing both faster and better)");
    entries[n] = (plot_legend_entry){PLOT_STYLE_FRONT, texts[n]};
    return n + 1;
}

const char *report_mesh_name(const report_row *r)
{
    const char *slash = strrchr(r->mesh, '/');
    return slash ? slash + 1 : r->mesh;
}

int report_svg_write(FILE *out, const report_row *rows, size_t count, const report_setup *setup)
{
    const double width = SVG_COLUMNS * PLOT_PANEL_W,
                 rows_per_mesh = (REPORT_PLOT_COUNT + SVG_COLUMNS - 1) / SVG_COLUMNS;
    plot_legend_entry entries[REPORT_LEGEND_MAX];
    char texts[REPORT_LEGEND_MAX][256];
    double height = HEADING_H + 22;
    for (size_t i = 0; i < count;) { /* measure first: the document's size comes first */
        size_t n = report_mesh_rows(rows + i, count - i);
        size_t e = report_legend(rows + i, n, entries, texts);
        height += HEADING_H + svg_plot_legend(NULL, entries, e, 20, 0, width - 40) + 10 +
                  rows_per_mesh * PLOT_PANEL_H;
        i += n;
    }
    plot_point *points = malloc((count ? count : 1) * sizeof *points);
    report_point_text *text = malloc((count ? count : 1) * sizeof *text);
    if (!points || !text) {
        free(points);
        free(text);
        return -1;
    }
    svg_plot_begin(out, width, height, 1, "cbvh report: error against run time per configuration");
    svg_plot_text(out, width / 2, 24, 17, "middle", 1,
                  "cbvh report: error against run time, one point per configuration");
    char caption[256];
    snprintf(caption, sizeof caption,
             "%zu incoherent rays, one thread, median of %u rounds beside the default (%s); lower left is "
             "better; %zu rays "
             "checked by brute force",
             setup->rays, setup->reps, setup->cpu_clock ? "CPU time" : "wall clock", setup->sample);
    svg_plot_text(out, width / 2, 44, 12, "middle", 0, caption);
    double y = HEADING_H + 22;
    for (size_t i = 0; i < count;) {
        size_t n = report_mesh_rows(rows + i, count - i);
        char heading[256];
        snprintf(heading, sizeof heading, "%s (%llu triangles)", report_mesh_name(&rows[i]),
                 (unsigned long long)rows[i].triangles);
        svg_plot_text(out, 20, y + 22, 15, "start", 1, heading);
        y += HEADING_H;
        size_t e = report_legend(rows + i, n, entries, texts);
        y += svg_plot_legend(out, entries, e, 20, y, width - 40) + 10;
        for (int k = 0; k < REPORT_PLOT_COUNT; k++) {
            plot_panel panel;
            report_plot_panel(k, rows + i, n, points, text, &panel);
            svg_plot_panel(out, &panel, PLOT_PANEL_W * (k % SVG_COLUMNS),
                           y + PLOT_PANEL_H * (k / SVG_COLUMNS), NULL, NULL);
        }
        y += rows_per_mesh * PLOT_PANEL_H;
        i += n;
    }
    free(points);
    free(text);
    return svg_plot_end(out);
}
