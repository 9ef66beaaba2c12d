/* pareto.h: the Pareto front of points where lower is better on both axes. */
#ifndef CBVH_TOOLS_PARETO_H
#define CBVH_TOOLS_PARETO_H

#include <stddef.h>

/* Sets on_front[i] to 1 when no other point is at least as good on both axes
 * and better on one (x[j] <= x[i], y[j] <= y[i], one of them strictly), else 0.
 * Points with a non-finite coordinate are never on the front and dominate
 * nothing. Returns the number of points on the front. O(n^2), for plots. */
size_t pareto_front(const double *x, const double *y, size_t n, unsigned char *on_front);

#endif
