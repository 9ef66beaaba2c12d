/* pareto.c: the Pareto front of points where lower is better on both axes. */
#include <math.h>

#include "pareto.h"

size_t pareto_front(const double *x, const double *y, size_t n, unsigned char *on_front)
{
    size_t count = 0;
    for (size_t i = 0; i < n; i++) {
        int front = isfinite(x[i]) && isfinite(y[i]);
        for (size_t j = 0; j < n && front; j++)
            if (j != i && isfinite(x[j]) && isfinite(y[j]) && x[j] <= x[i] && y[j] <= y[i] &&
                (x[j] < x[i] || y[j] < y[i]))
                front = 0;
        on_front[i] = (unsigned char)front;
        count += (size_t)front;
    }
    return count;
}
