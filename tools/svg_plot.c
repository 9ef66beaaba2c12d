/* svg_plot.c: a dependency-free SVG scatter plot writer: readable axes, marker styles, legend, labels that
 * never overlap, Pareto front, focusable points for HTML. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pareto.h"
#include "plot_axis.h"
#include "svg_plot.h"

/* Panel geometry: the plot frame inside the panel. */
#define MARGIN_L 74.0
#define MARGIN_R 16.0
#define MARGIN_T 34.0
#define MARGIN_B 58.0
/* Data values keep this far from the frame, so no marker sits on it. */
#define INSET 12.0
#define MARKER_R 5.0
#define LABEL_FONT 11.0
#define LABEL_H 13.0
#define TIP_FONT 11.0
#define TIP_LINE 14.0

/* Okabe & Ito's palette (black first), one shape per colour. */
static const char *const style_colour[PLOT_STYLE_COUNT] = {"#000000", "#E69F00", "#0072B2", "#D55E00",
                                                           "#009E73", "#CC79A7", "#56B4E9", "#F0E442"};
enum {
    SHAPE_STAR,
    SHAPE_CIRCLE,
    SHAPE_SQUARE,
    SHAPE_DIAMOND,
    SHAPE_TRIANGLE_UP,
    SHAPE_TRIANGLE_DOWN,
    SHAPE_HEXAGON,
    SHAPE_PLUS
};

/* Length of the UTF-8 sequence starting with lead byte c that the following bytes complete, else 0. */
static int utf8_length(const unsigned char *s)
{
    int n = s[0] < 0x80             ? 1
            : (s[0] & 0xe0) == 0xc0 ? 2
            : (s[0] & 0xf0) == 0xe0 ? 3
            : (s[0] & 0xf8) == 0xf0 ? 4
                                    : 0;
    if (n == 2 && s[0] < 0xc2)
        return 0;
    for (int k = 1; k < n; k++)
        if ((s[k] & 0xc0) != 0x80)
            return 0;
    return n;
}

void svg_write_escaped(FILE *out, const char *text)
{
    const unsigned char *s = (const unsigned char *)text;
    while (s && *s) {
        unsigned char c = *s;
        int n = utf8_length(s);
        if (n > 1) {
            fwrite(s, 1, (size_t)n, out);
            s += n;
            continue;
        }
        s++;
        switch (c) {
        case '&':
            fputs("&amp;", out);
            break;
        case '<':
            fputs("&lt;", out);
            break;
        case '>':
            fputs("&gt;", out);
            break;
        case '"':
            fputs("&quot;", out);
            break;
        case '\'':
            fputs("&#39;", out);
            break;
        default:
            if (c >= 0x80)
                fputc('?', out);
            else if (c >= 0x20 || c == '\t' || c == '\n')
                fputc(c, out);
        }
    }
}

double svg_text_width(const char *text, double font_size)
{
    /* DejaVu Sans advance widths, thousandths of an em. */
    static const short lower[26] = {613, 635, 550, 635, 615, 352, 635, 634, 278, 278, 579, 278, 974,
                                    634, 612, 635, 635, 411, 521, 392, 634, 592, 818, 592, 592, 525};
    static const short upper[26] = {684, 686, 698, 770, 632, 575, 775, 752, 295, 295, 656, 557, 863,
                                    748, 787, 603, 787, 695, 635, 611, 732, 684, 989, 685, 611, 685};
    double em = 0.0;
    const unsigned char *s = (const unsigned char *)text;
    while (s && *s) {
        unsigned c = *s;
        int n = utf8_length(s);
        s += n > 0 ? n : 1;
        if (n > 1)
            em += 0.84; /* superscripts, the multiplication sign, dashes: at most this */
        else if (c >= 'a' && c <= 'z')
            em += lower[c - 'a'] / 1000.0;
        else if (c >= 'A' && c <= 'Z')
            em += upper[c - 'A'] / 1000.0;
        else if (c >= '0' && c <= '9')
            em += 0.636;
        else if (strchr(" .,:;'|!", (int)c))
            em += 0.337;
        else if (strchr("-()[]/", (int)c))
            em += 0.39;
        else if (strchr("%@&WM", (int)c))
            em += 1.0;
        else
            em += 0.84;
    }
    return em * font_size * 1.03;
}

void svg_plot_begin(FILE *out, double width, double height, int standalone, const char *aria_label)
{
    if (standalone)
        fputs("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n"
              "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\"",
              out);
    else
        fputs("<svg class=\"plot\"", out);
    fprintf(out,
            " width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\" font-family=\"DejaVu Sans, Verdana, "
            "sans-serif\"",
            width, height, width, height);
    if (aria_label) {
        fputs(" role=\"img\" aria-label=\"", out);
        svg_write_escaped(out, aria_label);
        fputc('"', out);
    }
    fputs(">\n<rect width=\"100%\" height=\"100%\" fill=\"#fff\"/>\n", out);
}

int svg_plot_end(FILE *out)
{
    fputs("</svg>\n", out);
    return ferror(out) ? -1 : 0;
}

void svg_plot_text(FILE *out, double x, double y, double font_size, const char *anchor, int bold,
                   const char *text)
{
    fprintf(out, "<text x=\"%.1f\" y=\"%.1f\" font-size=\"%.0f\" text-anchor=\"%s\"%s>", x, y, font_size,
            anchor, bold ? " font-weight=\"bold\"" : "");
    svg_write_escaped(out, text);
    fputs("</text>\n", out);
}

/* The path of a marker of style `style` centred at (x, y). */
static void marker_path(FILE *out, unsigned style, double x, double y, double r)
{
    fputs("d=\"", out);
    switch (style % PLOT_STYLE_COUNT) {
    case SHAPE_STAR:
        for (int k = 0; k < 10; k++) {
            double a = -1.5707963 + k * 0.6283185, q = k % 2 ? r * 0.5 : r * 1.35;
            fprintf(out, "%c%.1f %.1f", k ? 'L' : 'M', x + q * cos(a), y + q * sin(a));
        }
        break;
    case SHAPE_CIRCLE:
        fprintf(out, "M%.1f %.1fa%.1f %.1f 0 1 0 %.1f 0a%.1f %.1f 0 1 0 %.1f 0", x - r, y, r, r, 2 * r, r, r,
                -2 * r);
        break;
    case SHAPE_SQUARE:
        r *= 0.9;
        fprintf(out, "M%.1f %.1fh%.1fv%.1fh%.1f", x - r, y - r, 2 * r, 2 * r, -2 * r);
        break;
    case SHAPE_DIAMOND:
        r *= 1.25;
        fprintf(out, "M%.1f %.1fL%.1f %.1fL%.1f %.1fL%.1f %.1f", x, y - r, x + r, y, x, y + r, x - r, y);
        break;
    case SHAPE_TRIANGLE_UP:
        r *= 1.2;
        fprintf(out, "M%.1f %.1fL%.1f %.1fL%.1f %.1f", x, y - r, x + r * 0.87, y + r * 0.5, x - r * 0.87,
                y + r * 0.5);
        break;
    case SHAPE_TRIANGLE_DOWN:
        r *= 1.2;
        fprintf(out, "M%.1f %.1fL%.1f %.1fL%.1f %.1f", x, y + r, x + r * 0.87, y - r * 0.5, x - r * 0.87,
                y - r * 0.5);
        break;
    case SHAPE_HEXAGON:
        for (int k = 0; k < 6; k++)
            fprintf(out, "%c%.1f %.1f", k ? 'L' : 'M', x + r * cos(k * 1.0471976),
                    y + r * sin(k * 1.0471976));
        break;
    default: { /* a thick plus */
        double t = r * 0.38;
        fprintf(out, "M%.1f %.1fh%.1fv%.1fh%.1fv%.1fh%.1fv%.1fh%.1fv%.1fh%.1fv%.1fh%.1f", x - t, y - r, 2 * t,
                r - t, r - t, 2 * t, t - r, r - t, -2 * t, t - r, t - r, -2 * t, r - t);
    }
    }
    fputs("Z\"", out);
}

static void write_marker(FILE *out, unsigned style, double x, double y, const char *extra)
{
    unsigned s = style % PLOT_STYLE_COUNT;
    fputs("<path ", out);
    marker_path(out, s, x, y, MARKER_R);
    fprintf(out, " fill=\"%s\" stroke=\"%s\" stroke-width=\"%s\"%s/>\n", style_colour[s], s ? "#222" : "#000",
            s ? "0.7" : "0.5", extra ? extra : "");
}

/* Tick marks, grid lines and tick labels of one axis. */
static void write_axis(FILE *out, const plot_axis *a, int vertical, double x0, double y0, double x1,
                       double y1)
{
    char label[64];
    for (size_t k = 0; k <= a->tick_count; k++) {
        double p;
        if (k == a->tick_count) { /* the 0 line of a log axis with zeros */
            if (!a->zero_band)
                break;
            p = a->pixel_lo;
            snprintf(label, sizeof label, "0");
        } else {
            p = plot_axis_pixel(a, a->ticks[k]);
            plot_axis_tick_label(a, a->ticks[k], label, sizeof label);
        }
        if (vertical) {
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e4e4e4\"/>\n", x0,
                    p, x1, p);
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\"/>\n", x0 - 4,
                    p, x0, p);
            svg_plot_text(out, x0 - 7, p + 4, 11, "end", 0, label);
        } else {
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e4e4e4\"/>\n", p,
                    y0, p, y1);
            fprintf(out, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\"/>\n", p, y0,
                    p, y0 + 4);
            svg_plot_text(out, p, y0 + 17, 11, "middle", 0, label);
        }
    }
    if (a->zero_band) { /* a break mark between the 0 line and the lowest decade */
        double dir = a->pixel_hi >= a->pixel_lo ? 1.0 : -1.0, m = a->pixel_lo + dir * PLOT_AXIS_ZERO_BAND / 2;
        if (vertical)
            fprintf(out, "<path d=\"M%.1f %.1fl8 -4M%.1f %.1fl8 -4\" stroke=\"#000\" fill=\"none\"/>\n",
                    x0 - 4, m + 1, x0 - 4, m + 5);
        else
            fprintf(out, "<path d=\"M%.1f %.1fl4 -8M%.1f %.1fl4 -8\" stroke=\"#000\" fill=\"none\"/>\n",
                    m - 3, y0 + 4, m + 1, y0 + 4);
    }
}

static void axis_title(char *buf, size_t size, const char *title, const plot_axis *a)
{
    char note[64];
    plot_axis_title_note(a, note, sizeof note);
    snprintf(buf, size, "%s%s", title ? title : "", note);
}

/* The front's staircase: between neighbours (by x) a horizontal then a vertical step. */
static void write_front(FILE *out, const double *px, const double *py, const unsigned char *on_front,
                        size_t n)
{
    size_t *order = malloc((n ? n : 1) * sizeof *order), m = 0;
    if (!order)
        return;
    for (size_t i = 0; i < n; i++)
        if (on_front[i])
            order[m++] = i;
    for (size_t i = 1; i < m; i++) /* insertion sort by pixel x: a handful of points */
        for (size_t j = i; j > 0 && px[order[j]] < px[order[j - 1]]; j--) {
            size_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    if (m > 0) {
        fputs("<path class=\"front\" fill=\"none\" stroke=\"#555\" stroke-width=\"1.3\" stroke-dasharray=\"5 "
              "3\" d=\"",
              out);
        for (size_t k = 0; k < m; k++) {
            if (k == 0)
                fprintf(out, "M%.1f %.1f", px[order[k]], py[order[k]]);
            else
                fprintf(out, "H%.1fV%.1f", px[order[k]], py[order[k]]);
        }
        fputs("\"/>\n", out);
    }
    free(order);
}

/* Label order: the reference first, then the points on the front, then the rest, each by index. */
static size_t label_rank(const plot_point *p, const unsigned char *on_front, size_t i)
{
    return p[i].style == 0 ? 0 : on_front[i] ? 1 : 2;
}

/* The box with the detail text shown on hover and focus of a point (HTML only). */
static void write_tip(FILE *out, const char *detail, double x, double y, double left, double top)
{
    size_t lines = 1;
    double width = 0.0;
    char line[512];
    for (const char *s = detail;; lines++) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        snprintf(line, sizeof line, "%.*s", (int)n, s);
        width = fmax(width, svg_text_width(line, TIP_FONT));
        if (!e)
            break;
        s = e + 1;
    }
    double w = width + 12, h = (double)lines * TIP_LINE + 8;
    double bx = x + 10 + w <= left + PLOT_PANEL_W ? x + 10 : x - 10 - w, by = y - h / 2;
    bx = fmax(left, bx);
    by = fmin(fmax(by, top), top + PLOT_PANEL_H - h);
    fprintf(out,
            "<g class=\"tip\" aria-hidden=\"true\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" "
            "height=\"%.1f\" rx=\"3\" "
            "fill=\"#fffff4\" stroke=\"#333\"/>\n",
            bx, by, w, h);
    fprintf(out, "<text font-size=\"%.0f\">", TIP_FONT);
    size_t k = 0;
    for (const char *s = detail;; k++) {
        const char *e = strchr(s, '\n');
        size_t n = e ? (size_t)(e - s) : strlen(s);
        snprintf(line, sizeof line, "%.*s", (int)n, s);
        fprintf(out, "<tspan x=\"%.1f\" y=\"%.1f\"%s>", bx + 6, by + 4 + TIP_LINE * (double)(k + 1) - 3,
                k == 0 ? " font-weight=\"bold\"" : "");
        svg_write_escaped(out, line);
        fputs("</tspan>", out);
        if (!e)
            break;
        s = e + 1;
    }
    fputs("</text></g>\n", out);
}

size_t svg_plot_panel(FILE *out, const plot_panel *panel, double left, double top, const char *id,
                      label_spot *spots)
{
    size_t n = panel->count;
    const plot_point *pts = panel->points;
    double fx0 = left + MARGIN_L, fx1 = left + PLOT_PANEL_W - MARGIN_R;
    double fy0 = top + PLOT_PANEL_H - MARGIN_B, fy1 = top + MARGIN_T; /* frame: y grows downwards */
    double *px = malloc(2 * (n ? n : 1) * sizeof *px), *py = px ? px + (n ? n : 1) : NULL;
    double *xs = malloc(2 * (n ? n : 1) * sizeof *xs), *ys = xs ? xs + (n ? n : 1) : NULL;
    unsigned char *on_front = calloc(n ? n : 1, 1);
    label_request *req = malloc((n ? n : 1) * sizeof *req);
    label_box *obstacles = malloc((n ? n : 1) * sizeof *obstacles);
    label_spot *own = spots ? NULL : malloc((n ? n : 1) * sizeof *own);
    size_t *order = malloc((n ? n : 1) * sizeof *order);
    size_t placed = 0;
    if (!px || !xs || !on_front || !req || !obstacles || (!spots && !own) || !order) {
        fputs("<!-- out of memory: plot left out -->\n", out);
        goto done;
    }
    if (!spots)
        spots = own;
    for (size_t i = 0; i < n; i++) {
        xs[i] = pts[i].x;
        ys[i] = pts[i].y;
    }
    plot_axis ax = {.pixel_lo = fx0 + INSET, .pixel_hi = fx1 - INSET};
    plot_axis ay = {.pixel_lo = fy0 - INSET, .pixel_hi = fy1 + INSET};
    plot_axis_fit(&ax, xs, n);
    plot_axis_fit(&ay, ys, n);
    ax.pixel_lo = fx0 + INSET;
    ax.pixel_hi = fx1 - INSET;
    ay.pixel_lo = fy0 - INSET;
    ay.pixel_hi = fy1 + INSET;

    size_t shown = 0, left_out = 0;
    for (size_t i = 0; i < n; i++) {
        px[i] = plot_axis_pixel(&ax, pts[i].x);
        py[i] = plot_axis_pixel(&ay, pts[i].y);
        if (!isfinite(px[i]) || !isfinite(py[i])) {
            px[i] = py[i] = NAN;
            left_out++;
        }
        if (!isfinite(px[i]) || pts[i].reference)
            xs[i] = ys[i] = NAN; /* off the front */
    }
    if (panel->pareto)
        pareto_front(xs, ys, n, on_front);

    fprintf(out, "<g class=\"panel\"%s%s%s>\n", id ? " id=\"" : "", id ? id : "", id ? "\"" : "");
    svg_plot_text(out, left + PLOT_PANEL_W / 2, top + 20, 13, "middle", 1, panel->title);
    write_axis(out, &ay, 1, fx0, fy0, fx1, fy1);
    write_axis(out, &ax, 0, fx0, fy0, fx1, fy1);
    fprintf(out,
            "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" stroke=\"#000\"/>\n",
            fx0, fy1, fx1 - fx0, fy0 - fy1);
    char title[256];
    axis_title(title, sizeof title, panel->x_title, &ax);
    svg_plot_text(out, (fx0 + fx1) / 2, fy0 + 36, 12, "middle", 0, title);
    axis_title(title, sizeof title, panel->y_title, &ay);
    double cx = left + 14, cy = (fy0 + fy1) / 2;
    fprintf(out,
            "<text x=\"%.1f\" y=\"%.1f\" font-size=\"12\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f "
            "%.1f)\">",
            cx, cy, cx, cy);
    svg_write_escaped(out, title);
    fputs("</text>\n", out);
    if (panel->pareto)
        write_front(out, px, py, on_front, n);

    /* Labels: markers are obstacles; the most important points choose first. */
    size_t m = 0;
    for (int rank = 0; rank < 3; rank++)
        for (size_t i = 0; i < n; i++)
            if (label_rank(pts, on_front, i) == (size_t)rank)
                order[m++] = i;
    for (size_t i = 0; i < n; i++) {
        obstacles[i] = isfinite(px[i]) ? (label_box){px[i] - MARKER_R - 1, py[i] - MARKER_R - 1,
                                                     px[i] + MARKER_R + 1, py[i] + MARKER_R + 1}
                                       : (label_box){0, 0, 0, 0};
        shown += isfinite(px[i]) != 0;
    }
    for (size_t k = 0; k < n; k++) {
        size_t i = order[k];
        int has = pts[i].label && *pts[i].label && isfinite(px[i]);
        req[k] = (label_request){px[i], py[i], has ? svg_text_width(pts[i].label, LABEL_FONT) : 0.0,
                                 has ? LABEL_H : 0.0};
    }
    label_box area = {fx0 + 2, fy1 + 2, fx1 - 2, fy0 - 2};
    label_spot *ordered = malloc((n ? n : 1) * sizeof *ordered);
    if (!ordered) {
        fputs("</g>\n", out);
        goto done;
    }
    placed = label_layout(req, n, obstacles, n, &area, 1.5, MARKER_R + 3, ordered);
    size_t wanted = 0;
    for (size_t k = 0; k < n; k++) {
        spots[order[k]] = ordered[k];
        wanted += req[k].width > 0;
    }
    free(ordered);
    for (size_t i = 0; i < n; i++) { /* leader lines under the markers */
        const label_spot *s = &spots[i];
        if (!s->placed || !s->leader)
            continue;
        double tx = fmin(fmax(px[i], s->box.x0), s->box.x1), ty = fmin(fmax(py[i], s->box.y0), s->box.y1);
        double dx = tx - px[i], dy = ty - py[i], d = sqrt(dx * dx + dy * dy);
        if (d > MARKER_R + 1)
            fprintf(out,
                    "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#888\" "
                    "stroke-width=\"0.8\"/>\n",
                    px[i] + dx / d * (MARKER_R + 1), py[i] + dy / d * (MARKER_R + 1), tx, ty);
    }
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(px[i]))
            continue;
        fputs(id ? "" : "<g>", out);
        if (!id) {
            fputs("<title>", out);
            svg_write_escaped(out, pts[i].detail ? pts[i].detail : pts[i].label);
            fputs("</title>", out);
        }
        write_marker(out, pts[i].style, px[i], py[i], id ? " class=\"mark\"" : NULL);
        fputs(id ? "" : "</g>\n", out);
    }
    for (size_t i = 0; i < n; i++) {
        const label_spot *s = &spots[i];
        if (!s->placed)
            continue;
        fprintf(out, "<text class=\"label\" x=\"%.1f\" y=\"%.1f\" font-size=\"%.0f\" fill=\"#111\">",
                s->box.x0 + 0.5, s->box.y1 - 3, LABEL_FONT);
        svg_write_escaped(out, pts[i].label);
        fputs("</text>\n", out);
    }
    if (id) /* focusable points with their detail boxes, last so the boxes cover the plot */
        for (size_t i = 0; i < n; i++) {
            if (!isfinite(px[i]))
                continue;
            const char *detail = pts[i].detail ? pts[i].detail : pts[i].label;
            fprintf(out, "<g class=\"pt\" tabindex=\"0\" id=\"%s-p%zu\" aria-label=\"", id, i);
            svg_write_escaped(out, detail);
            fputs("\"><title>", out);
            svg_write_escaped(out, detail);
            fputs("</title><path class=\"hit\" ", out);
            marker_path(out, pts[i].style, px[i], py[i], MARKER_R + 2);
            fputs(" fill=\"transparent\" stroke=\"none\"/></g>\n", out);
            write_tip(out, detail ? detail : "", px[i], py[i], left, top);
        }
    if (left_out || placed < wanted) {
        char note[256];
        size_t len = 0;
        if (left_out) { /* name them, as far as the line goes */
            len += (size_t)snprintf(note, sizeof note, "Not shown (no value here):");
            for (size_t i = 0, k = 0; i < n && len < sizeof note; i++)
                if (!isfinite(px[i]))
                    len += (size_t)snprintf(note + len, sizeof note - len, "%s %s", k++ ? "," : "",
                                            pts[i].label ? pts[i].label : "?");
            len += len < sizeof note ? (size_t)snprintf(note + len, sizeof note - len, ". ") : 0;
        }
        if (placed < wanted && len < sizeof note)
            snprintf(note + len, sizeof note - len, "%zu label%s left out for lack of room.", wanted - placed,
                     wanted - placed == 1 ? "" : "s");
        for (size_t cut = strlen(note);
             cut > 0 && svg_text_width(note, 10) > fx1 - fx0;) { /* to the plot's width */
            do
                cut--;
            while (cut > 0 && ((unsigned char)note[cut] & 0xc0) == 0x80); /* at a character's first byte */
            memcpy(note + cut, "...", 4);
        }
        svg_plot_text(out, fx0, top + PLOT_PANEL_H - 6, 10, "start", 0, note);
    }
    fputs("</g>\n", out);
done:
    free(px);
    free(xs);
    free(on_front);
    free(req);
    free(obstacles);
    free(own);
    free(order);
    return placed;
}

double svg_plot_legend(FILE *out, const plot_legend_entry *entries, size_t count, double left, double top,
                       double width)
{
    const double row = 20.0, sample = 26.0, space = 22.0;
    double x = left, y = top;
    for (size_t i = 0; i < count; i++) {
        double w = sample + svg_text_width(entries[i].text, 12);
        if (x > left && x + w > left + width) {
            x = left;
            y += row;
        }
        if (out) {
            if (entries[i].style >= PLOT_STYLE_FRONT)
                fprintf(out,
                        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#555\" "
                        "stroke-width=\"1.3\" "
                        "stroke-dasharray=\"5 3\"/>\n",
                        x, y + row / 2, x + sample - 6, y + row / 2);
            else
                write_marker(out, entries[i].style, x + 8, y + row / 2, NULL);
            svg_plot_text(out, x + sample - 2, y + row / 2 + 4, 12, "start", 0, entries[i].text);
        }
        x += w + space;
    }
    return count ? y + row - top : 0.0;
}
