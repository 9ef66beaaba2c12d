/* svg_plot.h: a dependency-free SVG scatter plot writer (axes, ticks, log scales, labelled points, side-by-side panels). */
#ifndef CBVH_TOOLS_SVG_PLOT_H
#define CBVH_TOOLS_SVG_PLOT_H

#include <stddef.h>
#include <stdio.h>

typedef struct svg_point {
    double x, y;
    const char *label; /* any text: it is escaped */
} svg_point;

typedef struct svg_axis {
    const char *label;
    int log; /* log10 scale; values <= 0 are drawn on the axis floor as hollow marks */
} svg_axis;

typedef struct svg_panel {
    const char *title;
    svg_axis x, y;
    const svg_point *points;
    size_t count;
} svg_panel;

/* Writes one standalone SVG document with the panels side by side, each a
 * scatter plot with ticks, tick labels, axis labels and one labelled point per
 * entry (non-finite values are left out and listed in a note). Returns 0, or
 * -1 when writing failed. */
int svg_plot_write(FILE *out, const char *title, const svg_panel *panels, size_t panel_count);

#endif
