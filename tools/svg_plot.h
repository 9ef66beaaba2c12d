/* svg_plot.h: a dependency-free SVG scatter plot writer: readable axes, marker styles, legend, labels that
 * never overlap, Pareto front, focusable points for HTML. */
#ifndef CBVH_TOOLS_SVG_PLOT_H
#define CBVH_TOOLS_SVG_PLOT_H

#include <stddef.h>
#include <stdio.h>

#include "label_layout.h"

/* Marker styles: a colour of the Okabe-Ito palette (told apart by colour-blind
 * readers) and a shape each, so colour and shape both tell the groups apart.
 * Style 0 is a black star, meant for the reference or default point. */
#define PLOT_STYLE_COUNT 8
/* A legend entry with this style shows the dashed line of the Pareto front. */
#define PLOT_STYLE_FRONT PLOT_STYLE_COUNT

/* The size of one panel (svg_plot_panel), in pixels. */
#define PLOT_PANEL_W 500.0
#define PLOT_PANEL_H 360.0

typedef struct plot_point {
    double x, y;        /* non-finite: left out (counted in a note) */
    unsigned style;     /* 0 .. PLOT_STYLE_COUNT - 1 */
    const char *label;  /* short text beside the marker; NULL: none */
    const char *detail; /* shown on hover and focus, lines separated by '\n'; NULL: the label */
    int reference;      /* a reference to compare with, not a choice: never on the Pareto front */
} plot_point;

typedef struct plot_panel {
    const char *title;
    const char *x_title, *y_title;
    const plot_point *points;
    size_t count;
    int pareto; /* draw the Pareto front: lower x and lower y are better */
} plot_panel;

typedef struct plot_legend_entry {
    unsigned style; /* a marker style, or PLOT_STYLE_FRONT */
    const char *text;
} plot_legend_entry;

/* Writes text content or an attribute value: the XML specials escaped, control
 * characters dropped, bytes that are not valid UTF-8 written as '?', so any
 * string (a file name) gives a valid document. */
void svg_write_escaped(FILE *out, const char *s);

/* Width in pixels of s (UTF-8) in a sans-serif font of font_size pixels: an
 * estimate from DejaVu Sans's advance widths, the widest of the common sans
 * fonts, so the real text is at most as wide. */
double svg_text_width(const char *s, double font_size);

/* Starts a document of width x height: with standalone, an XML prolog and an
 * <svg> root with its namespace; without, an inline <svg> element for an HTML
 * page. aria_label (may be NULL) names the picture for screen readers. */
void svg_plot_begin(FILE *out, double width, double height, int standalone, const char *aria_label);
/* Ends the document; returns 0, or -1 when writing failed. */
int svg_plot_end(FILE *out);

/* A line of text at (x, y) (baseline), anchor "start", "middle" or "end". */
void svg_plot_text(FILE *out, double x, double y, double font_size, const char *anchor, int bold,
                   const char *text);

/* Writes one scatter plot into the PLOT_PANEL_W x PLOT_PANEL_H rectangle at
 * (left, top): title, axes (plot_axis.h), grid, the Pareto front, markers and
 * labels placed by label_layout inside the plot frame, with leader lines when
 * displaced. Each marker carries a <title> with its detail. With id non-NULL
 * (HTML) every point is focusable (tabindex) and shows its detail in a box on
 * hover or focus; ids in the panel start with id. spots (may be NULL) receives
 * each point's label box in the document's coordinates. Returns the labels
 * placed; the others are counted in a note under the plot. */
size_t svg_plot_panel(FILE *out, const plot_panel *panel, double left, double top, const char *id,
                      label_spot *spots);

/* Writes the legend's entries (marker and text) in rows that fit `width`,
 * starting at (left, top); out NULL only measures. Returns the height used. */
double svg_plot_legend(FILE *out, const plot_legend_entry *entries, size_t count, double left, double top,
                       double width);

#endif
