/* report.h: the rows of `cbvh report` (one per mesh and configuration, each configuration a list of
 * dimensions) and the writers of its plots, page and advice. */
#ifndef CBVH_TOOLS_REPORT_H
#define CBVH_TOOLS_REPORT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "svg_plot.h"

/* The choices a configuration is made of. Plots, legend and advice handle them
 * generically: a new choice is one more entry here and in report_dimension_names. */
enum {
    REPORT_DIM_LAYOUT,
    REPORT_DIM_BOXES,
    REPORT_DIM_VERTICES,
    REPORT_DIM_LEAF,
    REPORT_DIM_TRAVERSAL,
    REPORT_DIM_SECTIONS,
    REPORT_DIM_COUNT
};

/* "layout", "box precision", ... for the legend. */
extern const char *const report_dimension_names[REPORT_DIM_COUNT];

/* A hit on another triangle within this fraction of the diagonal is a tie on a shared edge, not a wrong
 * triangle. */
#define REPORT_TIE_TOLERANCE 1e-5

typedef struct report_row {
    const char *mesh;
    uint64_t triangles;
    char value[REPORT_DIM_COUNT]
              [32];   /* each dimension's value, self-describing: "leaf 8", "q16 boxes", "stackless" */
    char config[192]; /* the values joined by ", " */
    int is_default;   /* the default cook and traversal: the other rows vary one thing from it */
    int reference;    /* not something the format offers (exact float boxes): never recommended */
    uint32_t leaf;
    int quantized_vertices, float_boxes, compress;
    const char *traversal;
    double bytes_per_triangle, open_seconds; /* open_seconds < 0: not a file */
    double closest_mrays, any_mrays;
    double nodes_per_ray, tris_per_ray, extra_nodes, extra_tris;
    double inflation_mean, inflation_worst;
    uint64_t compared, flips, wrong_triangle;
    double t_err_max, t_err_rms;
    double vertex_error;
    int64_t leaks; /* -1: the mesh is not closed */
    uint64_t leak_rays;
} report_row;

/* How the rows were measured, for captions. */
typedef struct report_setup {
    size_t rays, sample;
    unsigned reps;
    int cpu_clock;
} report_setup;

/* The mesh's file name without its folder. */
const char *report_mesh_name(const report_row *r);

/* Nanoseconds per closest-hit ray. */
double report_ns_per_ray(const report_row *r);

/* Rows of the same mesh as rows[0]: their count (rows are grouped by mesh). */
size_t report_mesh_rows(const report_row *rows, size_t count);

/* The default row among rows[0..count) (one mesh), or NULL. */
const report_row *report_default_row(const report_row *rows, size_t count);

/* 1 when the row answers like the double-precision reference: no flip, no
 * wrong triangle, no leak, distance error within the tie tolerance, lossless
 * vertices. */
int report_row_exact(const report_row *r);

/* The values in which r differs from def (the default row, may be NULL) joined
 * ("leaf 8", "q16 vertices"), "default" for the default itself, with
 * " (reference)" after a reference row's. */
void report_short_label(const report_row *r, const report_row *def, char *buf, size_t size);

/* The summary table's columns: mesh and configuration, then the figures. */
#define REPORT_COLUMN_COUNT 18
const char *report_column_title(int column);
/* The text of one cell (numbers as the markdown table shows them). */
void report_cell(const report_row *r, int column, char *buf, size_t size);

/* The plots of one mesh: each measure against run time, and size against open time. */
#define REPORT_PLOT_COUNT 6
/* Legend entries at most: the default, each dimension, the Pareto front. */
#define REPORT_LEGEND_MAX (REPORT_DIM_COUNT + 2)

/* Text behind one plot's points: a label and a detail per row. */
typedef struct report_point_text {
    char label[96];
    char detail[512];
} report_point_text;

/* Fills *panel with plot k (0 <= k < REPORT_PLOT_COUNT) of one mesh's rows:
 * points[i] and text[i] (count of each, caller-provided) for rows[i]. */
void report_plot_panel(int k, const report_row *rows, size_t count, plot_point *points,
                       report_point_text *text, plot_panel *panel);

/* The legend of one mesh's rows: the default configuration in full, each
 * dimension some row varies, the Pareto front. Returns the entries written
 * (at most REPORT_LEGEND_MAX, texts caller-provided alike). */
size_t report_legend(const report_row *rows, size_t count, plot_legend_entry *entries, char (*texts)[256]);

/* The plot SVG (`--svg`): per mesh a legend and one panel per measure. Returns 0, -1 on a write error. */
int report_svg_write(FILE *out, const report_row *rows, size_t count, const report_setup *setup);

/* The self-contained HTML page (`--html`). Returns 0, -1 on a write error. */
int report_html_write(FILE *out, const report_row *rows, size_t count, const report_setup *setup);

/* The recommendation for one mesh's rows, plain text in sentences (may be
 * cut to size). Computed from the figures: the fastest exact configuration
 * (the default when within the timing noise of it), then what smaller files
 * and lossy choices would cost. Returns the recommended row, or NULL when no
 * row is exact. */
const report_row *report_recommend(const report_row *rows, size_t count, char *buf, size_t size);

#endif
