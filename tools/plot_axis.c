/* plot_axis.c: the scale of a plot axis: linear, or log10 only where the values span decades; ticks at 1-2-5
 * values with readable labels. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "plot_axis.h"

/* Values are clamped to +-this, so ranges and ticks stay finite. */
#define LARGEST 1e300
/* Linear tick labels switch to a power-of-ten factor outside [1e-2, 1e5). */
#define PLAIN_LO 1e-2
#define PLAIN_HI 1e5

/* The smallest of 1, 2, 5 times a power of ten that is at least raw. */
static double nice_step(double raw)
{
    double mag = pow(10.0, floor(log10(raw))), f = raw / mag;
    return (f <= 1.0 ? 1.0 : f <= 2.0 ? 2.0 : f <= 5.0 ? 5.0 : 10.0) * mag;
}

static void add_tick(plot_axis *a, double t)
{
    if (a->tick_count < PLOT_AXIS_MAX_TICKS)
        a->ticks[a->tick_count++] = t;
}

static void fit_log(plot_axis *a, double min_pos, double max)
{
    int elo = (int)floor(log10(min_pos) + 1e-9), ehi = (int)ceil(log10(max) - 1e-9);
    if (ehi <= elo)
        ehi = elo + 1;
    a->lo = pow(10.0, elo);
    a->hi = pow(10.0, ehi);
    int decades = ehi - elo, every = (decades + 7) / 8;
    for (int e = elo; e <= ehi; e += every) {
        double d = pow(10.0, e);
        add_tick(a, d);
        if (decades <= 2 && e < ehi) {
            add_tick(a, 2 * d);
            add_tick(a, 5 * d);
        }
    }
}

static void fit_linear(plot_axis *a, double lo, double hi)
{
    if (lo >= 0.0 && lo < hi / 3.0)
        lo = 0.0;
    if (hi - lo <= fabs(hi) * 1e-12) { /* one value: a range around it */
        double pad = hi != 0.0 ? fabs(hi) * 0.1 : 1.0;
        lo = lo >= 0.0 && lo - pad < 0.0 ? 0.0 : lo - pad;
        hi += pad;
    }
    double step = nice_step((hi - lo) / 5.0);
    a->step = step;
    a->lo = floor(lo / step + 1e-9) * step;
    a->hi = ceil(hi / step - 1e-9) * step;
    double big = fmax(fabs(a->lo), fabs(a->hi));
    a->factor_exp = big >= PLAIN_HI || big < PLAIN_LO ? (int)floor(log10(step) + 1e-9) : 0;
    long count = lround((a->hi - a->lo) / step);
    for (long k = 0; k <= count; k++) {
        double t = a->lo + (double)k * step;
        add_tick(a, fabs(t) < step * 1e-9 ? 0.0 : t);
    }
}

void plot_axis_fit(plot_axis *a, const double *values, size_t n)
{
    double lo = INFINITY, hi = -INFINITY, min_pos = INFINITY;
    size_t zeros = 0, negatives = 0;
    for (size_t i = 0; i < n; i++) {
        double v = values[i];
        if (!isfinite(v))
            continue;
        v = fmin(fmax(v, -LARGEST), LARGEST);
        lo = fmin(lo, v);
        hi = fmax(hi, v);
        zeros += v == 0.0;
        negatives += v < 0.0;
        if (v > 0.0)
            min_pos = fmin(min_pos, v);
    }
    double pixel_lo = a->pixel_lo, pixel_hi = a->pixel_hi;
    memset(a, 0, sizeof *a);
    a->pixel_lo = pixel_lo;
    a->pixel_hi = pixel_hi;
    if (!(lo <= hi)) {
        lo = 0.0;
        hi = 1.0;
    }
    if (!negatives && isfinite(min_pos) && hi / min_pos >= PLOT_AXIS_LOG_SPAN) {
        a->log = 1;
        a->zero_band = zeros > 0;
        fit_log(a, min_pos, hi);
    } else {
        fit_linear(a, lo, hi);
    }
}

double plot_axis_pixel(const plot_axis *a, double v)
{
    if (!isfinite(v))
        return NAN;
    v = fmin(fmax(v, -LARGEST), LARGEST);
    if (!a->log)
        return a->pixel_lo + (v - a->lo) / (a->hi - a->lo) * (a->pixel_hi - a->pixel_lo);
    double dir = a->pixel_hi >= a->pixel_lo ? 1.0 : -1.0;
    double start = a->pixel_lo + (a->zero_band ? dir * PLOT_AXIS_ZERO_BAND : 0.0);
    if (v == 0.0)
        return a->zero_band ? a->pixel_lo : NAN;
    if (v < 0.0)
        return NAN;
    return start + (log10(v) - log10(a->lo)) / (log10(a->hi) - log10(a->lo)) * (a->pixel_hi - start);
}

/* Appends "10" and the exponent in superscript digits (UTF-8). */
static void power_of_ten(char *buf, size_t size, int e)
{
    static const char *const sup[10] = {"\u2070", "\u00b9", "\u00b2", "\u00b3", "\u2074",
                                        "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};
    char digits[16];
    snprintf(digits, sizeof digits, "%d", e < 0 ? -e : e);
    size_t n = strlen(buf);
    n += (size_t)snprintf(buf + n, n < size ? size - n : 0, "10%s", e < 0 ? "\u207b" : "");
    for (const char *d = digits; *d && n < size; d++)
        n += (size_t)snprintf(buf + n, size - n, "%s", sup[*d - '0']);
}

void plot_axis_tick_label(const plot_axis *a, double t, char *buf, size_t size)
{
    if (!size)
        return;
    buf[0] = '\0';
    if (a->log) {
        int e = (int)floor(log10(t) + 1e-9);
        long mantissa = lround(t / pow(10.0, e));
        if (e >= -3 && e <= 4)
            snprintf(buf, size, "%.*f", e < 0 ? -e : 0, t);
        else {
            if (mantissa != 1)
                snprintf(buf, size, "%ld\u00d7", mantissa);
            power_of_ten(buf, size, e);
        }
        return;
    }
    double scaled = t / pow(10.0, a->factor_exp), step = a->step / pow(10.0, a->factor_exp);
    int decimals = step >= 1.0 ? 0 : (int)ceil(-log10(step) - 1e-9);
    snprintf(buf, size, "%.*f", decimals, fabs(scaled) < step * 1e-9 ? 0.0 : scaled);
}

void plot_axis_title_note(const plot_axis *a, char *buf, size_t size)
{
    if (!size)
        return;
    buf[0] = '\0';
    if (a->log)
        snprintf(buf, size, " (log)");
    else if (a->factor_exp) {
        snprintf(buf, size, " (\u00d7");
        power_of_ten(buf, size, a->factor_exp);
        size_t n = strlen(buf);
        if (n + 1 < size) {
            buf[n] = ')';
            buf[n + 1] = '\0';
        }
    }
}
