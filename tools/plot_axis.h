/* plot_axis.h: the scale of a plot axis: linear, or log10 only where the values span decades; ticks at 1-2-5
 * values with readable labels. */
#ifndef CBVH_TOOLS_PLOT_AXIS_H
#define CBVH_TOOLS_PLOT_AXIS_H

#include <stddef.h>

#define PLOT_AXIS_MAX_TICKS 24
/* Pixels between the 0 line and the lowest decade of a log axis that has zeros. */
#define PLOT_AXIS_ZERO_BAND 24.0

typedef struct plot_axis {
    int log;                   /* log10: the positive values span PLOT_AXIS_LOG_SPAN or more */
    int zero_band;             /* log axis with some values 0: they sit on a 0 line below the lowest decade */
    double lo, hi;             /* the range shown, in data units (log: lo > 0) */
    double step;               /* linear tick step */
    int factor_exp;            /* linear tick labels are the values over 10^factor_exp (0: as they are) */
    double pixel_lo, pixel_hi; /* where lo and hi go: set by the caller after plot_axis_fit */
    size_t tick_count;
    double ticks[PLOT_AXIS_MAX_TICKS];
} plot_axis;

/* Largest over smallest positive value from which an axis is logarithmic. */
#define PLOT_AXIS_LOG_SPAN 100.0

/* Fits the axis to the finite values: log10 when none is negative and the
 * positive ones span PLOT_AXIS_LOG_SPAN or more (ticks at the decades, plus 2
 * and 5 when two decades or fewer show), else linear (4 to 10 ticks at
 * multiples of 1, 2 or 5 times a power of ten, starting at 0 when the values
 * are all >= 0 and the smallest is under a third of the largest). No finite
 * value gives the range [0, 1]. */
void plot_axis_fit(plot_axis *a, const double *values, size_t n);

/* The pixel of a value; NAN for a value the axis cannot show (non-finite, or
 * negative on a log axis, or 0 on a log axis without a zero band). */
double plot_axis_pixel(const plot_axis *a, double v);

/* The label of tick value t, UTF-8: "250", "0.05", "10⁻⁶", "2×10⁻⁶" (linear
 * ticks divided by 10^factor_exp). */
void plot_axis_tick_label(const plot_axis *a, double t, char *buf, size_t size);

/* What the axis title needs appended: " (×10⁻⁶)" when the ticks are scaled, " (log)" on a log axis, else "".
 */
void plot_axis_title_note(const plot_axis *a, char *buf, size_t size);

#endif
