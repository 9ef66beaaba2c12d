/* report_html.c: `cbvh report --html`: one self-contained page (inline CSS and SVG, no script, nothing
 * fetched) with, per mesh, the advice, the plots and the summary table. */
#include <stdlib.h>
#include <string.h>

#include "report.h"

#define LEGEND_W 1000.0

/* Hover and focus show a point's detail box; everything reads without them. */
static const char style_sheet[] =
    "body{font-family:'DejaVu Sans',Verdana,sans-serif;margin:1.5em auto;max-width:1560px;padding:0 "
    "1em;color:#111}\n"
    "h1{font-size:1.5em}h2{font-size:1.25em;margin-top:2em;border-bottom:1px solid #ccc}\n"
    "p{max-width:62em;line-height:1.45}.advice{background:#eef6ee;border-left:4px solid #009E73;padding:.6em "
    ".9em}\n"
    ".plots{display:flex;flex-wrap:wrap;gap:8px}figure{margin:0}svg{max-width:100%;height:auto}\n"
    ".tip{visibility:hidden;pointer-events:none}.pt:hover+.tip,.pt:focus+.tip{visibility:visible}\n"
    ".pt{cursor:pointer;outline:none}.pt:hover .hit,.pt:focus .hit{stroke:#000;stroke-width:2}\n"
    ".table{overflow-x:auto}table{border-collapse:collapse;font-size:.8em}\n"
    "th,td{border:1px solid #ccc;padding:.25em .45em;text-align:right;white-space:nowrap}\n"
    "th{background:#f2f2f2}td.text{text-align:left}tr.recommended td{background:#eef6ee;font-weight:bold}\n";

static void html_text(FILE *out, const char *s)
{
    svg_write_escaped(out, s); /* the same escaping serves HTML text and attributes */
}

static void write_table(FILE *out, const report_row *rows, size_t count, const report_row *pick)
{
    char cell[256];
    const report_row *def = report_default_row(rows, count);
    fputs("<div class=\"table\"><table class=\"summary\">\n<thead><tr>", out);
    for (int c = 1; c < REPORT_COLUMN_COUNT; c++) { /* the mesh is the section's heading */
        fputs("<th scope=\"col\">", out);
        html_text(out, report_column_title(c));
        fputs("</th>", out);
    }
    fputs("</tr></thead>\n<tbody>\n", out);
    for (size_t i = 0; i < count; i++) {
        fputs(&rows[i] == pick ? "<tr class=\"recommended\">" : "<tr>", out);
        for (int c = 1; c < REPORT_COLUMN_COUNT; c++) {
            if (c == 1) { /* what differs from the default; the whole configuration on hover */
                fputs("<td class=\"text\" title=\"", out);
                html_text(out, rows[i].config);
                fputs("\">", out);
                report_short_label(&rows[i], def, cell, sizeof cell);
            } else {
                fputs("<td>", out);
                report_cell(&rows[i], c, cell, sizeof cell);
            }
            html_text(out, cell);
            fputs("</td>", out);
        }
        fputs("</tr>\n", out);
    }
    fputs("</tbody></table></div>\n", out);
}

static int write_mesh(FILE *out, const report_row *rows, size_t count, size_t mesh_index, plot_point *points,
                      report_point_text *text)
{
    char advice[4096], id[32];
    const report_row *pick = report_recommend(rows, count, advice, sizeof advice);
    fprintf(out, "<section class=\"mesh\" id=\"mesh%zu\">\n<h2>", mesh_index);
    html_text(out, report_mesh_name(&rows[0]));
    fprintf(out, " <small>(%llu triangles, %zu configurations)</small></h2>\n<p class=\"advice\">",
            (unsigned long long)rows[0].triangles, count);
    char *first_end = strstr(advice, ". "); /* the recommendation itself in bold, the reasons after it */
    if (first_end) {
        first_end[1] = '\0';
        fputs("<strong>", out);
        html_text(out, advice);
        fputs("</strong> ", out);
        html_text(out, first_end + 2);
    } else {
        html_text(out, advice);
    }
    fputs("</p>\n", out);

    plot_legend_entry entries[REPORT_LEGEND_MAX];
    char texts[REPORT_LEGEND_MAX][256];
    size_t e = report_legend(rows, count, entries, texts);
    double h = svg_plot_legend(NULL, entries, e, 4, 4, LEGEND_W - 8) + 8;
    fputs("<figure class=\"legend\">\n", out);
    svg_plot_begin(out, LEGEND_W, h, 0, "legend: marker shape and colour tell which choice a point varies");
    svg_plot_legend(out, entries, e, 4, 4, LEGEND_W - 8);
    if (svg_plot_end(out))
        return -1;
    fputs("</figure>\n<div class=\"plots\">\n", out);
    for (int k = 0; k < REPORT_PLOT_COUNT; k++) {
        plot_panel panel;
        report_plot_panel(k, rows, count, points, text, &panel);
        snprintf(id, sizeof id, "m%zu-k%d", mesh_index, k);
        fputs("<figure>\n", out);
        svg_plot_begin(out, PLOT_PANEL_W, PLOT_PANEL_H, 0, panel.title);
        svg_plot_panel(out, &panel, 0, 0, id, NULL);
        if (svg_plot_end(out))
            return -1;
        fputs("</figure>\n", out);
    }
    fputs("</div>\n", out);
    write_table(out, rows, count, pick);
    fputs("</section>\n", out);
    return ferror(out) ? -1 : 0;
}

int report_html_write(FILE *out, const report_row *rows, size_t count, const report_setup *setup)
{
    plot_point *points = malloc((count ? count : 1) * sizeof *points);
    report_point_text *text = malloc((count ? count : 1) * sizeof *text);
    int status = points && text ? 0 : -1;
    fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
          "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
          "<title>cbvh report: error against run time</title>\n<style>\n",
          out);
    fputs(style_sheet, out);
    fputs("</style>\n</head>\n<body>\n<h1>cbvh report: error against run time</h1>\n", out);
    fprintf(out,
            "<p>Every choice the file format offers, measured on the same %zu incoherent rays (one thread, "
            "median of "
            "%u rounds timed in turns with the default configuration, %s); %zu rays are checked against a "
            "double-precision brute force. Each point is one "
            "configuration: the default is the black star, and the other markers change one choice from it, "
            "the marker's shape and colour telling which. <strong>Lower left is better</strong> (faster and "
            "smaller error); the dashed line is the Pareto front, the configurations nothing beats on both "
            "axes. Hover over a point, or move to it with the Tab key, to see its configuration and "
            "figures.</p>\n",
            setup->rays, setup->reps, setup->cpu_clock ? "CPU time" : "wall-clock time", setup->sample);
    for (size_t i = 0, mesh = 0; i < count && !status; mesh++) {
        size_t n = report_mesh_rows(rows + i, count - i);
        status = write_mesh(out, rows + i, n, mesh, points, text);
        i += n;
    }
    fputs("</body>\n</html>\n", out);
    free(points);
    free(text);
    return status || ferror(out) ? -1 : 0;
}
