/* svg_plot.c: a dependency-free SVG scatter plot writer (axes, ticks, log scales, labelled points, side-by-side panels). */
#include <math.h>
#include <string.h>

#include "svg_plot.h"

#define PANEL_W 600.0
#define PANEL_H 440.0
#define TITLE_H 34.0
#define MARGIN_L 78.0
#define MARGIN_R 24.0
#define MARGIN_T 40.0
#define MARGIN_B 62.0

static const char *const palette[] = { "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e",
                                       "#17becf", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22" };

/* Text content and attribute values: the five XML specials escaped, control
 * characters (not allowed in XML 1.0) dropped, other bytes above ASCII written
 * as '?' so a file name that is not UTF-8 cannot make the document invalid. */
static void write_escaped(FILE *out, const char *s)
{
    for (; s && *s; s++) {
        unsigned char c = (unsigned char)*s;
        switch (c) {
        case '&': fputs("&amp;", out); break;
        case '<': fputs("&lt;", out); break;
        case '>': fputs("&gt;", out); break;
        case '"': fputs("&quot;", out); break;
        case '\'': fputs("&apos;", out); break;
        default:
            if (c >= 0x80)
                fputc('?', out);
            else if (c >= 0x20 || c == '\t' || c == '\n')
                fputc(c, out);
        }
    }
}

/* One axis mapped onto [pixel_lo, pixel_hi]. In log scale lo and hi are decades. */
typedef struct scale {
    int log;
    double lo, hi, step; /* data range (log: exponents) and tick step */
    double pixel_lo, pixel_hi;
} scale;

static double nice_step(double range)
{
    double raw = range / 5.0, mag = pow(10.0, floor(log10(raw))), f = raw / mag;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * mag;
}

static void scale_fit(scale *s, int log_scale, const svg_point *pts, size_t n, int use_y)
{
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        double v = use_y ? pts[i].y : pts[i].x;
        if (!isfinite(v) || (log_scale && v <= 0.0))
            continue;
        double w = log_scale ? log10(v) : v;
        lo = fmin(lo, w);
        hi = fmax(hi, w);
    }
    s->log = log_scale;
    if (!(lo <= hi)) {
        lo = 0.0;
        hi = 1.0;
    }
    if (log_scale) {
        lo = floor(lo);
        hi = ceil(hi);
        if (hi <= lo)
            hi = lo + 1.0;
        s->step = ceil((hi - lo) / 8.0);
    } else {
        if (hi - lo < 1e-300 * fmax(1.0, fabs(hi))) {
            double pad = lo != 0.0 ? fabs(lo) * 0.1 : 1.0;
            lo -= pad;
            hi += pad;
        }
        s->step = nice_step(hi - lo);
        lo = floor(lo / s->step) * s->step;
        hi = ceil(hi / s->step) * s->step;
    }
    s->lo = lo;
    s->hi = hi;
}

/* Pixel of a data value; values off a log scale (<= 0) sit on the floor. */
static double scale_map(const scale *s, double v, int *off_scale)
{
    double w = v;
    *off_scale = 0;
    if (s->log) {
        if (v <= 0.0) {
            *off_scale = 1;
            return s->pixel_lo;
        }
        w = log10(v);
    }
    return s->pixel_lo + (w - s->lo) / (s->hi - s->lo) * (s->pixel_hi - s->pixel_lo);
}

static void tick_label(char *buf, size_t size, const scale *s, double t)
{
    if (s->log)
        snprintf(buf, size, "1e%d", (int)lround(t));
    else
        snprintf(buf, size, "%.6g", fabs(t) < s->step * 1e-9 ? 0.0 : t);
}

static void write_ticks(FILE *out, const scale *s, int vertical, double x0, double y0, double x1, double y1)
{
    int count = (int)floor((s->hi - s->lo) / s->step + 0.5);
    for (int k = 0; k <= count; k++) {
        double t = s->lo + k * s->step;
        double p = s->pixel_lo + (t - s->lo) / (s->hi - s->lo) * (s->pixel_hi - s->pixel_lo);
        char label[64];
        tick_label(label, sizeof label, s, t);
        if (vertical) { /* y axis: grid line across, label left */
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", x0, p, x1, p);
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\"/>\n", x0 - 5, p, x0, p);
            fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\" font-size=\"11\">%s</text>\n", x0 - 8,
                    p + 4, label);
        } else {
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", p, y0, p, y1);
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\"/>\n", p, y0, p, y0 + 5);
            fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"11\">%s</text>\n", p,
                    y0 + 18, label);
        }
    }
}

static void write_panel(FILE *out, const svg_panel *panel, double left, double top)
{
    double px0 = left + MARGIN_L, px1 = left + PANEL_W - MARGIN_R;
    double py0 = top + PANEL_H - MARGIN_B, py1 = top + MARGIN_T; /* y grows downwards */
    scale sx, sy;
    scale_fit(&sx, panel->x.log, panel->points, panel->count, 0);
    scale_fit(&sy, panel->y.log, panel->points, panel->count, 1);
    sx.pixel_lo = px0;
    sx.pixel_hi = px1;
    sy.pixel_lo = py0;
    sy.pixel_hi = py1;

    fprintf(out, "<g>\n<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\">",
            left + PANEL_W / 2, top + 22);
    write_escaped(out, panel->title);
    fputs("</text>\n", out);
    write_ticks(out, &sy, 1, px0, py0, px1, py1);
    write_ticks(out, &sx, 0, px0, py0, px1, py1);
    fprintf(out, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#000\"/>\n", px0,
            py1, px1 - px0, py0 - py1);
    fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"12\">", (px0 + px1) / 2, py0 + 40);
    write_escaped(out, panel->x.label);
    fputs(panel->x.log ? " (log)" : "", out);
    fputs("</text>\n", out);
    double cy = (py0 + py1) / 2, cx = left + 18;
    fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"12\" transform=\"rotate(-90 %.1f %.1f)\">",
            cx, cy, cx, cy);
    write_escaped(out, panel->y.label);
    fputs(panel->y.log ? " (log)" : "", out);
    fputs("</text>\n", out);

    size_t skipped = 0, floored = 0;
    for (size_t i = 0; i < panel->count; i++) {
        const svg_point *p = &panel->points[i];
        if (!isfinite(p->x) || !isfinite(p->y)) {
            skipped++;
            continue;
        }
        int off_x, off_y;
        double x = scale_map(&sx, p->x, &off_x), y = scale_map(&sy, p->y, &off_y);
        const char *color = palette[i % (sizeof palette / sizeof palette[0])];
        floored += off_x || off_y;
        fprintf(out, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4.5\" fill=\"%s\" stroke=\"%s\" stroke-width=\"1.5\"><title>",
                x, y, off_x || off_y ? "none" : color, color);
        write_escaped(out, p->label);
        fprintf(out, ": x=%.6g y=%.6g</title></circle>\n", p->x, p->y);
        /* Alternate label sides so neighbours overlap less. */
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"%s\" text-anchor=\"%s\">", x + (i % 2 ? -7 : 7),
                y + (i % 4 < 2 ? -6 : 12), color, i % 2 ? "end" : "start");
        write_escaped(out, p->label);
        fputs("</text>\n", out);
    }
    if (skipped || floored) {
        fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"#555\">", px0, py0 + 56);
        if (floored)
            fprintf(out, "hollow: value 0, drawn on the axis floor. ");
        if (skipped)
            fprintf(out, "%zu point(s) without a finite value left out.", skipped);
        fputs("</text>\n", out);
    }
    fputs("</g>\n", out);
}

int svg_plot_write(FILE *out, const char *title, const svg_panel *panels, size_t panel_count)
{
    double width = PANEL_W * (double)(panel_count ? panel_count : 1), height = PANEL_H + TITLE_H;
    fprintf(out, "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
    fprintf(out,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"0 0 %.0f %.0f\" font-family=\"sans-serif\">\n",
            width, height, width, height);
    fprintf(out, "<rect width=\"100%%\" height=\"100%%\" fill=\"#fff\"/>\n");
    fprintf(out, "<text x=\"%.1f\" y=\"22\" text-anchor=\"middle\" font-size=\"16\" font-weight=\"bold\">", width / 2);
    write_escaped(out, title);
    fputs("</text>\n", out);
    for (size_t k = 0; k < panel_count; k++)
        write_panel(out, &panels[k], PANEL_W * (double)k, TITLE_H);
    fputs("</svg>\n", out);
    return ferror(out) ? -1 : 0;
}
